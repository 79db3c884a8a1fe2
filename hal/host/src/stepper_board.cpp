// See stepper_board.hpp.
#include "hal_host/stepper_board.hpp"
#include "hal_host/hal_binding.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <stdexcept>
#include <string>

#include "mcsim/status.hpp"

namespace hal_host {
namespace {

using Binding = HalBinding<StepperBoard>;

}  // namespace

StepperBoard::StepperBoard(const StepperBoardConfig& cfg) : cfg_(cfg) {
  check_config(cfg.motor.validate(), "motor");
  for (int k = 0; k < 2; ++k) {
    mcsim::CurrentSensorParams p = cfg.current_sensor;
    p.seed = cfg.current_sensor.seed + static_cast<uint64_t>(k) * 7919U;
    check_config(isense_[k].configure(p), "current_sensor");
  }
  check_config(vsense_.configure(cfg.vbus_sensor), "vbus_sensor");
  check_config(encoder_.configure(cfg.encoder), "encoder");
  if (cfg.substeps < 1) throw std::invalid_argument("substeps must be >= 1");
  if (cfg.delay_periods < 0) throw std::invalid_argument("delay_periods must be >= 0");
  check_config(delay_.configure(static_cast<std::size_t>(cfg.delay_periods), duty_cmd_),
               "delay_periods");
  if (!(cfg.vbus_v > 0.0) || !std::isfinite(cfg.vbus_v)) {
    throw std::invalid_argument("vbus_v must be > 0");
  }
  if (!(cfg.t_pwm_s > 0.0) || !std::isfinite(cfg.t_pwm_s)) {
    throw std::invalid_argument("t_pwm_s must be > 0");
  }
  if (!(cfg.tick_hz >= 1.0) || cfg.tick_hz > 4.0e9) {
    throw std::invalid_argument("tick_hz out of range");
  }
  mcsim::StepperPowerStageParams sp;
  sp.motor = cfg.motor;
  sp.t_pwm_s = cfg.t_pwm_s;
  sp.vbus_v = cfg.vbus_v;
  sp.substeps = cfg.substeps;
  sp.theta_m0_rad = cfg.theta_m0_rad;
  check_config(stage_.configure(sp), "power stage");
  if (cfg.common_leg) {
    mcsim::StepperCommonLegStageParams cp;
    cp.motor = cfg.motor;
    cp.inverter.t_pwm_s = cfg.t_pwm_s;
    cp.inverter.t_dead_s = cfg.dead_time_s;
    cp.vbus_v = cfg.vbus_v;
    cp.substeps = cfg.substeps;
    cp.theta_m0_rad = cfg.theta_m0_rad;
    check_config(stage3_.configure(cp), "common-leg power stage");
  }
  encoder_.reset(cfg.theta_m0_rad);
  adc_dev_ = {&Binding::kAdc, this};
  pwm_dev_ = {&Binding::kPwm2, this};
  enc_dev_ = {&Binding::kEncoder, this};
  tick_dev_ = {&Binding::kTick, this};
  fault_dev_ = {&Binding::kFault, this};
  hal_.adc = &adc_dev_;
  hal_.pwm3 = nullptr;
  hal_.pwm2 = &pwm_dev_;
  hal_.encoder = &enc_dev_;
  hal_.can = nullptr;
  hal_.tick = &tick_dev_;
  hal_.fault = &fault_dev_;
}

uint32_t StepperBoard::ticks_now() const {
  const double ticks = std::floor(t_s() * cfg_.tick_hz + 0.5);
  return static_cast<uint32_t>(static_cast<uint64_t>(std::fmod(ticks, 4294967296.0)));
}

void StepperBoard::sample() {
  const State& x = state();
  adc_.ia_a = static_cast<float>(isense_[0].sample_a(x(mcsim::Stepper2Ph::kIa)));
  adc_.ib_a = static_cast<float>(isense_[1].sample_a(x(mcsim::Stepper2Ph::kIb)));
  adc_.ic_a = 0.0f;
  adc_.vbus_v = static_cast<float>(vsense_.sample_v(cfg_.vbus_v));
  adc_.valid_mask = MC_HAL_ADC_VALID_IA | MC_HAL_ADC_VALID_IB | MC_HAL_ADC_VALID_VBUS;
  adc_.timestamp_ticks = ticks_now();
  adc_.seq = ++adc_seq_;
  adc_fresh_ = true;
  const mcsim::EncoderReading r = encoder_.sample(x(mcsim::Stepper2Ph::kThetaM));
  enc_.count = static_cast<uint32_t>(r.count_in_rev);
  enc_.counts_per_rev = static_cast<uint32_t>(cfg_.encoder.counts_per_rev);
  enc_.flags = MC_HAL_ENCODER_FLAG_VALID | (r.index_seen ? MC_HAL_ENCODER_FLAG_INDEX : 0U);
  enc_.timestamp_ticks = adc_.timestamp_ticks;
}

void StepperBoard::advance() {
  // Duties after the computation delay; a disable acts at once.
  const Eigen::Vector2d duty = delay_.push(duty_cmd_);
  const bool on = pwm_enabled_ && !fault_line_.killed;
  if (cfg_.common_leg) {
    advance_common_leg(duty, on);
  } else {
    check_config(stage_.advance(duty, on), "integrator");
  }
}

// The pwm2 duties on three legs (stepper_board.hpp): leg 3 centred, the
// request outside the hexagon clamped by the stage and counted here.
void StepperBoard::advance_common_leg(const Eigen::Vector2d& duty, bool switching) {
  const double hi = std::max({duty(0), duty(1), 0.0});
  const double lo = std::min({duty(0), duty(1), 0.0});
  const double c = 0.5 * (1.0 - hi - lo);
  const Eigen::Vector3d legs(c + duty(0), c + duty(1), c);
  if (switching) {
    constexpr double kTol = 1.0e-9;  // float duties: rounding is not a clip
    if (hi - lo > 1.0 + kTol) ++clipped_;
    max_req_v_ = std::max(max_req_v_, duty.norm() * cfg_.vbus_v);
  }
  check_config(stage3_.advance(legs, switching), "integrator");
}

int StepperBoard::adc_read(mc_hal_adc_sample_t* s) noexcept {
  if (!adc_fresh_) return -EAGAIN;
  *s = adc_;
  adc_fresh_ = false;
  return 0;
}

int StepperBoard::adc_read_temp(mc_hal_adc_temp_t* t) noexcept {
  t->power_stage_temp_c = 25.0f;
  t->motor_temp_c = 25.0f;
  t->valid_mask = MC_HAL_ADC_TEMP_VALID_ALL;
  t->absent_mask = 0u;
  return 0;
}

int StepperBoard::pwm_set_duty(float a, float b) noexcept {
  if (!mc_hal_pwm2_duty_valid(a) || !mc_hal_pwm2_duty_valid(b)) return -EINVAL;
  duty_cmd_ << a, b;
  return 0;
}

int StepperBoard::pwm_enable() noexcept {
  if (fault_line_.killed) return -EBUSY;
  pwm_enabled_ = true;
  return 0;
}

int StepperBoard::pwm_disable() noexcept {
  pwm_enabled_ = false;
  return 0;
}

int StepperBoard::pwm_get_state(mc_hal_pwm2_state_t* st) noexcept {
  st->duty_a = static_cast<float>(duty_cmd_(0));
  st->duty_b = static_cast<float>(duty_cmd_(1));
  st->period_s = static_cast<float>(cfg_.t_pwm_s);
  st->enabled = pwm_enabled_ && !fault_line_.killed;
  return 0;
}

int StepperBoard::encoder_read(mc_hal_encoder_sample_t* s) noexcept {
  *s = enc_;
  return 0;
}

int StepperBoard::tick_read(uint32_t* ticks) const noexcept {
  *ticks = ticks_now();
  return 0;
}

int StepperBoard::tick_freq(uint32_t* hz) const noexcept {
  *hz = static_cast<uint32_t>(cfg_.tick_hz);
  return 0;
}

int StepperBoard::fault_read(mc_hal_fault_status_t* st) noexcept {
  fault_line_.read(st);
  return 0;
}

void StepperBoard::fault_gate_kill() noexcept {
  fault_line_.killed = true;
}

int StepperBoard::fault_gate_release() noexcept {
  if (!fault_line_.release()) return -EBUSY;
  pwm_enabled_ = false;
  return 0;
}

}  // namespace hal_host
