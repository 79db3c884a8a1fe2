// hal_host::PmsmBoard: a simulated 3-phase drive board. It binds the HAL
// (adc, pwm3, encoder, tick, fault) to the plant simulator, so the
// unmodified firmware runs against it as against an STM32F405 board. The
// physics (bridge, diodes, open phase, motor) is the plant's
// (mcsim::PmsmPowerStage); the board adds what sits between it and the MCU:
// current/bus/encoder sensors, the duty register with its computation
// delay, the enable and gate-kill path, the tick counter and injected faults.
//
// Timing, as on a real drive (one PWM period T per control step):
//   t_k       sample(): ADC trigger at the period start: phase currents, DC
//             bus and encoder are measured from the plant state at t_k.
//   [t_k, ..] the firmware's fast step runs and writes new duties.
//   advance() the power stage integrates the plant from t_k to t_k + T
//             (RK4 sub-steps, inputs held constant). The duties in force are
//             those written delay_periods steps earlier (1 = the usual
//             one-period computation delay; 0 = ideal, instantaneous update).
// hal_host::sil_period() (sil_rig.hpp) runs this sequence with the drive.
//
// PWM disabled (or gate kill): every switch open; the currents freewheel
// through the diodes (see mcsim::PmsmPowerStage).
#ifndef HAL_HOST_PMSM_BOARD_HPP
#define HAL_HOST_PMSM_BOARD_HPP

#include <cstdint>
#include <memory>

#include "hal/hal.h"
#include "hal_host/hal_binding.hpp"
#include "hal_host/sim_board.hpp"
#include "hal_host/spi_encoder.hpp"
#include "mcsim/dc_link.hpp"
#include "mcsim/integrator.hpp"
#include "mcsim/inverter.hpp"
#include "mcsim/pmsm_ab.hpp"
#include "mcsim/pmsm_power_stage.hpp"
#include "mcsim/pmsm_rotor_frame.hpp"
#include "mcsim/sensors.hpp"

namespace hal_host {

struct PmsmBoardConfig {
  mcsim::PmsmParams motor{};
  mcsim::InverterParams inverter{};  // t_pwm_s is the control period
  double vbus_v = 24.0;              // DC-bus voltage (stiff source)
  // DC link (mcsim::DcLink): off (the default) = a stiff bus at vbus_v, bit
  // for bit the behaviour before the link existed. On: the bus voltage is
  // the capacitor's, charged by the source and by the bridge (the inverter
  // current from the power into the motor, 3/2 v_ab . i_ab / vbus, averaged
  // over the period); the board has a brake chopper (mc_hal_t.brake) when
  // dc_link.brake_r_ohm > 0. dc_link.source_v is the source's open-circuit
  // voltage (vbus_v is then only the initial value and must equal it).
  bool dc_link_enabled = false;
  // The link is outside the board (set by hal_host::DualPmsmBoard, which
  // owns the one link both axes of a two-axis board share; needs
  // dc_link_enabled): advance() integrates the motor only and records the
  // period's inverter current (inverter_a()); the owner advances the link
  // and sets the bus voltage for the next period (set_vbus_v).
  bool dc_link_shared = false;
  mcsim::DcLinkParams dc_link{};
  mcsim::CurrentSensorParams current_sensor{};
  mcsim::VbusSensorParams vbus_sensor{};
  mcsim::EncoderParams encoder{};
  // An absolute SPI encoder instead of the A/B one (type not kNone): the
  // drive's encoder device is then the image's driver on the chip model
  // (hal_host::SpiEncoder); encoder above is unused.
  SpiEncoderConfig spi_encoder{};
  bool three_shunts = false;    // false: ic is not measured
  int substeps = 4;             // RK4 sub-steps per PWM period, >= 1
  int delay_periods = 1;        // computation delay, 0..4 periods
  double tick_hz = 10.0e6;      // HAL tick counter frequency
  double theta_m0_rad = 0.0;    // initial rotor angle
  double omega_m0_rad_s = 0.0;  // initial speed
  // The motor's temperatures (mcsim/thermal.hpp): off by default. On, the
  // power stage reads 25 C and the board has no motor thermistor (as the
  // ODrive v3.6 by default: its temperature reads absent) unless
  // motor_thermistor: then it reads the plant's winding temperature (a
  // thermistor in the winding, as the VESC 6's motor input takes).
  bool thermal_enabled = false;
  mcsim::ThermalParams thermal{};
  bool motor_thermistor = false;
};

class PmsmBoard final : public SimBoard {
 public:
  // (i_alpha, i_beta, omega_m, theta_m), as mcsim::PmsmAb.
  using State = mcsim::PmsmAb::State;

  // Throws std::invalid_argument naming the bad parameter.
  explicit PmsmBoard(const PmsmBoardConfig& cfg);
  PmsmBoard(const PmsmBoard&) = delete;
  PmsmBoard& operator=(const PmsmBoard&) = delete;

  const mc_hal_t* hal() const override { return &hal_; }

  void sample() override;   // ADC/encoder trigger at the start of the period
  void advance() override;  // integrate the plant over one period

  // Inspection for scenarios and tests (true values, not measurements).
  double t_s() const override { return stage_.t_s(); }
  State state() const;
  const mcsim::PmsmRotorFrame::State& rotor_frame_state() const {
    return stage_.rotor_frame_state();
  }
  const mcsim::PmsmRotorFrame& plant() const { return stage_.plant(); }
  const mcsim::PmsmPowerStage& power_stage() const { return stage_; }
  double period_s() const override { return cfg_.inverter.t_pwm_s; }
  double torque_nm() const { return stage_.torque_nm(); }
  // True phase currents (a, b, c) [A]; with an open phase, exactly 0 in it
  // and exactly opposite in the other two.
  Eigen::Vector3d phase_currents_true_a() const { return stage_.phase_currents_true_a(); }
  // dq currents at the true electrical angle.
  void true_dq_a(double* id_a, double* iq_a) const;
  bool pwm_enabled() const { return pwm_enabled_ && !fault_line_.killed; }
  const Eigen::Vector3d& duties_applied() const { return stage_.duties_applied(); }
  const Eigen::Vector2d& v_alpha_beta_applied() const { return stage_.v_alpha_beta_applied(); }
  // The DC link, nullptr when the bus is stiff (dc_link_enabled false); a
  // shared link is its owner's (bind_shared_link).
  const mcsim::DcLink* dc_link() const {
    if (!cfg_.dc_link_enabled) return nullptr;
    return cfg_.dc_link_shared ? shared_link_ : &link_;
  }
  // With dc_link_shared: the link the owner advances (for dc_link()).
  void bind_shared_link(const mcsim::DcLink* link) { shared_link_ = link; }
  // The current the bridge drew from the bus over the last period [A]
  // (power into the motor / bus voltage; < 0 while braking); 0 with a stiff
  // bus.
  double inverter_a() const { return inverter_a_; }
  // Bus voltage in force [V] (the link's, or the stiff vbus_v).
  double vbus_v() const { return stage_.vbus_v(); }
  // Energy delivered to the motor terminals since construction [J]
  // (integral of 3/2 v_ab . i_ab, trapezoidal per period; only counted with
  // the DC link on) and the brake duty in force.
  double motor_in_j() const { return motor_in_j_; }
  double brake_duty() const { return brake_duty_; }
  // The absolute SPI encoder, nullptr with the A/B encoder.
  SpiEncoder* spi_encoder() { return spi_enc_.get(); }

  // Faults a test can inject into the board (all off by default).
  struct Injection {
    int stuck_phase = -1;  // 0..2: that current channel reads stuck_value_a
    double stuck_value_a = 0.0;
    double offset_a[3] = {0, 0, 0};   // added to each current reading [A]
    bool nan_ia = false;              // the ia conversion returns NaN
    bool encoder_dead = false;        // encoder reads not valid (cable off)
    bool encoder_frozen = false;      // encoder keeps its last count (lost lines)
    double compute_delay_s = 0.0;     // the tick jumps this much after the sample:
                                      // the fast step looks late (deadline overrun)
    int open_phase = -1;              // 0..2: that phase conductor is broken from
                                      // the next advance() on (mcsim::PmsmPowerStage);
                                      // -1: all three connected
    bool motor_disconnected = false;  // no motor on the terminals (all three open)
  };
  // Throws std::invalid_argument (and changes nothing) for open_phase outside
  // -1..2.
  void inject(const Injection& inj);

  // Test hooks.
  void set_vbus_v(double v) {
    cfg_.vbus_v = v;
    stage_.set_vbus_v(v);
  }
  void set_load(const mcsim::LoadTorque& load);  // throws std::invalid_argument
  void set_fault_inputs(uint32_t active_mask);

  // HAL op implementations (public so the C ops tables can reach them).
  // noexcept: they are called from C through the ops tables and must never
  // throw across that boundary.
  int adc_read(mc_hal_adc_sample_t* s) noexcept;
  int adc_read_temp(mc_hal_adc_temp_t* t) noexcept;
  int pwm_set_duty(float a, float b, float c) noexcept;
  int pwm_enable() noexcept;
  int pwm_disable() noexcept;
  int pwm_get_state(mc_hal_pwm3_state_t* st) noexcept;
  int encoder_read(mc_hal_encoder_sample_t* s) noexcept;
  int tick_read(uint32_t* ticks) const noexcept;
  int tick_freq(uint32_t* hz) const noexcept;
  int fault_read(mc_hal_fault_status_t* st) noexcept;
  void fault_gate_kill() noexcept;
  int fault_gate_release() noexcept;
  int brake_set_duty(float duty) noexcept;

 private:
  uint32_t ticks_now() const;

  PmsmBoardConfig cfg_;
  mcsim::PmsmPowerStage stage_;
  mcsim::CurrentSensor isense_[3];
  mcsim::VbusSensor vsense_;
  mcsim::Encoder encoder_;
  std::unique_ptr<SpiEncoder> spi_enc_;
  mcsim::InputDelay<Eigen::Vector3d, 4> delay_;

  // HAL-visible state
  mc_hal_adc_sample_t adc_{};
  bool adc_fresh_ = false;
  uint32_t adc_seq_ = 0;
  Eigen::Vector3d duty_cmd_{0.5, 0.5, 0.5};
  bool pwm_enabled_ = false;
  FaultLine fault_line_;
  mc_hal_encoder_sample_t enc_{};
  Injection inj_{};
  double tick_offset_s_ = 0.0;
  mcsim::DcLink link_;
  const mcsim::DcLink* shared_link_ = nullptr;
  double inverter_a_ = 0.0;
  double motor_in_j_ = 0.0;
  double brake_duty_ = 0.0;

  // ops tables bound to this board
  mc_hal_adc_t adc_dev_{};
  mc_hal_pwm3_t pwm_dev_{};
  mc_hal_encoder_t enc_dev_{};
  mc_hal_tick_t tick_dev_{};
  mc_hal_fault_t fault_dev_{};
  mc_hal_brake_t brake_dev_{};
  mc_hal_t hal_{};
};

}  // namespace hal_host

#endif  // HAL_HOST_PMSM_BOARD_HPP
