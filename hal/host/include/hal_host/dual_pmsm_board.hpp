// hal_host::DualPmsmBoard: a two-axis drive board (the ODrive v3.6's M0 and
// M1): two simulated axes (hal_host::PmsmBoard, each with its own HAL,
// motor, sensors and computation delay) on one DC link, one bus capacitor
// and one supply (issue 34 item 2): the current one axis brakes into the bus
// is what the other draws first, and only the difference flows from (or,
// with a supply that can sink, into) the supply or the brake resistor.
//
// One period, as hal_host::sil_period does it for one axis:
//   sample()   both axes' ADC/encoder trigger at the period start; both
//              read the same bus voltage (each through its own sensor).
//   [the two fast steps run and write their duties]
//   advance()  both motors over the period with the bus voltage in force,
//              then the link with both inverter currents (each axis's power
//              over the period / bus voltage, as a one-axis board draws it)
//              and the brake chopper at the larger of the two axes' duties,
//              then both axes' bus voltage set for the next period.
// The brake chopper is the board's, not an axis's: each axis's drive
// computes its duty from the bus voltage it measures (mc_drive's
// brake_step); both measure the same bus, and the chopper is on as much as
// the more demanding of the two asks (an axis that stopped on a fault no
// longer asks; the other still does).
//
// Simplification, stated: the two axes' PWM carriers are taken in phase
// (the ODrive runs TIM8 a half period after TIM1); the link is advanced
// once per period with each axis's mean current, so the carrier phase does
// not change its voltage beyond the ripple the period average already
// leaves out.
#ifndef HAL_HOST_DUAL_PMSM_BOARD_HPP
#define HAL_HOST_DUAL_PMSM_BOARD_HPP

#include <memory>

#include "hal_host/pmsm_board.hpp"
#include "mcsim/dc_link.hpp"

namespace hal_host {

class DualPmsmBoard {
 public:
  static constexpr int kAxes = 2;

  // Throws std::invalid_argument naming the fault (and builds nothing):
  // either axis without dc_link_enabled, link values that differ between
  // the two (one capacitor, one supply), or PWM periods or sub-steps that
  // differ (one period for both axes' fast steps); and whatever PmsmBoard
  // refuses in either axis (the message names the axis).
  DualPmsmBoard(const PmsmBoardConfig& m0, const PmsmBoardConfig& m1);
  DualPmsmBoard(const DualPmsmBoard&) = delete;
  DualPmsmBoard& operator=(const DualPmsmBoard&) = delete;

  // Axis k (0: M0, 1: M1); k outside 0..1 throws std::out_of_range.
  PmsmBoard& axis(int k);
  const PmsmBoard& axis(int k) const;
  const mcsim::DcLink& link() const { return link_; }
  // The chopper's duty over the last period (the larger of the axes').
  double brake_duty() const { return brake_duty_; }

  void sample();   // both axes' trigger at the period start
  void advance();  // both motors, then the link (see above)
  double t_s() const { return ax_[0]->t_s(); }
  double period_s() const { return ax_[0]->period_s(); }

 private:
  std::unique_ptr<PmsmBoard> ax_[kAxes];
  mcsim::DcLink link_;
  int substeps_ = 1;
  double brake_duty_ = 0.0;
};

}  // namespace hal_host

#endif  // HAL_HOST_DUAL_PMSM_BOARD_HPP
