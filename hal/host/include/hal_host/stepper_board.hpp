// hal_host::StepperBoard: a simulated two-phase stepper drive (dual H-bridge)
// behind the HAL (adc, pwm2, encoder, tick, fault), mirroring PmsmBoard, so
// the drive with a plugged stepper law (e.g. firmware/app/mc_ctrl_csmc) runs
// unmodified against the simulator.
//
// Plant: mcsim::StepperPowerStage (the two H-bridges and their diodes
// feeding mcsim::Stepper2Ph, paper 001 eq. (1)), or with common_leg
// mcsim::StepperCommonLegStage (a three-phase board's three legs: winding a
// between legs 1 and 3, b between legs 2 and 3); outputs disabled (or gate
// kill) open every switch.
// pwm2 on the common-leg board: the duties (d_a, d_b) in [-1, 1] ask for
// winding voltages d vbus, as on the H-bridges; the board's pwm2 driver
// puts them on the legs centred in [0, 1]: leg 3 at
// c = (1 - max(d_a, d_b, 0) - min(d_a, d_b, 0)) / 2, legs 1 and 2 at
// c + d_a and c + d_b. All three fit iff (d_a, d_b) is in the hexagon
// |d_a|, |d_b|, |d_a - d_b| <= 1 (quadrature amplitude vbus / sqrt(2) at
// every angle, mcsim/inverter.hpp); a request outside it is clamped leg by
// leg (what the bridge can) and counted (clipped_periods()). The board adds the sensors, the duty register with
// its computation delay, the enable and gate-kill path and the tick counter.
// ADC: ia = winding A, ib = winding B (ic not measured), DC bus.
// Timing as PmsmBoard: sample() at t_k, the firmware's fast step, advance()
// with the duties written delay_periods periods earlier (ZOH, RK4 sub-steps);
// hal_host::sil_period() (sil_rig.hpp) runs this sequence with the drive.
#ifndef HAL_HOST_STEPPER_BOARD_HPP
#define HAL_HOST_STEPPER_BOARD_HPP

#include <cstdint>

#include "hal/hal.h"
#include "hal_host/hal_binding.hpp"
#include "hal_host/sim_board.hpp"
#include "mcsim/integrator.hpp"
#include "mcsim/sensors.hpp"
#include "mcsim/stepper_2ph.hpp"
#include "mcsim/stepper_common_leg_stage.hpp"
#include "mcsim/stepper_power_stage.hpp"

namespace hal_host {

struct StepperBoardConfig {
  mcsim::Stepper2PhParams motor{};
  double t_pwm_s = 1.0e-4;  // PWM = control period
  double vbus_v = 60.0;     // DC-bus voltage (stiff source)
  mcsim::CurrentSensorParams current_sensor{};
  mcsim::VbusSensorParams vbus_sensor{};
  mcsim::EncoderParams encoder{};
  int substeps = 4;           // RK4 sub-steps per period, >= 1
  int delay_periods = 1;      // computation delay, 0..4 periods
  double tick_hz = 10.0e6;    // HAL tick counter frequency
  double theta_m0_rad = 0.0;  // initial shaft angle
  bool common_leg = false;    // three legs with a common one (else two H-bridges)
  double dead_time_s = 0.0;   // common_leg: the legs' dead time (InverterParams)
};

class StepperBoard final : public SimBoard {
 public:
  using State = mcsim::Stepper2Ph::State;  // (i_a, i_b, w, phi)

  // Throws std::invalid_argument naming the bad parameter.
  explicit StepperBoard(const StepperBoardConfig& cfg);
  StepperBoard(const StepperBoard&) = delete;
  StepperBoard& operator=(const StepperBoard&) = delete;

  const mc_hal_t* hal() const override { return &hal_; }

  void sample() override;   // ADC/encoder trigger at the start of the period
  void advance() override;  // integrate the plant over one period

  double t_s() const override { return cfg_.common_leg ? stage3_.t_s() : stage_.t_s(); }
  const State& state() const { return cfg_.common_leg ? stage3_.state() : stage_.state(); }
  const mcsim::StepperPowerStage& power_stage() const { return stage_; }  // H-bridges only
  double period_s() const override { return cfg_.t_pwm_s; }
  bool pwm_enabled() const { return pwm_enabled_ && !fault_line_.killed; }
  const Eigen::Vector2d& v_applied() const {
    return cfg_.common_leg ? stage3_.v_applied() : stage_.v_applied();
  }
  // Common leg: switching periods whose requested (d_a, d_b) lay outside
  // the hexagon (a leg clamped), and the largest requested amplitude
  // |(d_a, d_b)| vbus [V] over the switching periods.
  long clipped_periods() const { return clipped_; }
  double max_request_amplitude_v() const { return max_req_v_; }

  // HAL op implementations (public so the C ops tables can reach them).
  int adc_read(mc_hal_adc_sample_t* s) noexcept;
  int adc_read_temp(mc_hal_adc_temp_t* t) noexcept;
  int pwm_set_duty(float a, float b) noexcept;
  int pwm_enable() noexcept;
  int pwm_disable() noexcept;
  int pwm_get_state(mc_hal_pwm2_state_t* st) noexcept;
  int encoder_read(mc_hal_encoder_sample_t* s) noexcept;
  int tick_read(uint32_t* ticks) const noexcept;
  int tick_freq(uint32_t* hz) const noexcept;
  int fault_read(mc_hal_fault_status_t* st) noexcept;
  void fault_gate_kill() noexcept;
  int fault_gate_release() noexcept;

 private:
  uint32_t ticks_now() const;
  void advance_common_leg(const Eigen::Vector2d& duty, bool switching);

  StepperBoardConfig cfg_;
  mcsim::StepperPowerStage stage_;
  mcsim::StepperCommonLegStage stage3_;
  long clipped_ = 0;
  double max_req_v_ = 0.0;
  mcsim::CurrentSensor isense_[2];
  mcsim::VbusSensor vsense_;
  mcsim::Encoder encoder_;
  mcsim::InputDelay<Eigen::Vector2d, 4> delay_;

  mc_hal_adc_sample_t adc_{};
  bool adc_fresh_ = false;
  uint32_t adc_seq_ = 0;
  Eigen::Vector2d duty_cmd_ = Eigen::Vector2d::Zero();
  bool pwm_enabled_ = false;
  FaultLine fault_line_;
  mc_hal_encoder_sample_t enc_{};

  mc_hal_adc_t adc_dev_{};
  mc_hal_pwm2_t pwm_dev_{};
  mc_hal_encoder_t enc_dev_{};
  mc_hal_tick_t tick_dev_{};
  mc_hal_fault_t fault_dev_{};
  mc_hal_t hal_{};
};

}  // namespace hal_host

#endif  // HAL_HOST_STEPPER_BOARD_HPP
