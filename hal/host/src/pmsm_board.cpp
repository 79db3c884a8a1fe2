// See pmsm_board.hpp.
#include "hal_host/pmsm_board.hpp"
#include "hal_host/hal_binding.hpp"

#include <cerrno>
#include <cmath>
#include <stdexcept>
#include <string>

#include "mcsim/status.hpp"

namespace hal_host {

namespace {

using Binding = HalBinding<PmsmBoard>;

}  // namespace

PmsmBoard::PmsmBoard(const PmsmBoardConfig& cfg) : cfg_(cfg) {
  check_config(cfg.motor.validate(), "motor");
  check_config(cfg.inverter.validate(), "inverter");
  for (int k = 0; k < 3; ++k) {
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
  if (!(cfg.vbus_v > 0.0) || !std::isfinite(cfg.vbus_v))
    throw std::invalid_argument("vbus_v must be > 0");
  if (!(cfg.tick_hz >= 1.0) || cfg.tick_hz > 4.0e9)
    throw std::invalid_argument("tick_hz out of range");
  mcsim::PmsmPowerStageParams sp;
  sp.motor = cfg.motor;
  sp.inverter = cfg.inverter;
  sp.vbus_v = cfg.vbus_v;
  sp.substeps = cfg.substeps;
  sp.theta_m0_rad = cfg.theta_m0_rad;
  sp.omega_m0_rad_s = cfg.omega_m0_rad_s;
  sp.thermal_enabled = cfg.thermal_enabled;
  sp.thermal = cfg.thermal;
  check_config(stage_.configure(sp), "power stage");
  if (cfg.dc_link_shared && !cfg.dc_link_enabled) {
    throw std::invalid_argument("dc_link_shared needs dc_link_enabled (the shared link's values)");
  }
  if (cfg.dc_link_enabled) {
    check_config(link_.configure(cfg.dc_link), "dc_link");
    if (cfg.vbus_v != cfg.dc_link.source_v) {
      throw std::invalid_argument("vbus_v must equal dc_link.source_v with the DC link on");
    }
  }
  encoder_.reset(cfg.theta_m0_rad);

  adc_dev_ = {&Binding::kAdc, this};
  pwm_dev_ = {&Binding::kPwm3, this};
  enc_dev_ = {&Binding::kEncoder, this};
  tick_dev_ = {&Binding::kTick, this};
  fault_dev_ = {&Binding::kFault, this};
  hal_.adc = &adc_dev_;
  hal_.pwm3 = &pwm_dev_;
  hal_.pwm2 = nullptr;
  hal_.encoder = &enc_dev_;
  if (cfg.spi_encoder.type != SpiEncoderType::kNone) {
    spi_enc_ = std::make_unique<SpiEncoder>(cfg.spi_encoder, cfg.theta_m0_rad, cfg.omega_m0_rad_s);
    hal_.encoder = spi_enc_->encoder();
  }
  hal_.can = nullptr;
  hal_.tick = &tick_dev_;
  hal_.fault = &fault_dev_;
  brake_dev_ = {&Binding::kBrake, this};
  hal_.brake = (cfg.dc_link_enabled && cfg.dc_link.brake_r_ohm > 0.0) ? &brake_dev_ : nullptr;
}

uint32_t PmsmBoard::ticks_now() const {
  // Modulo 2^32, like a free-running hardware counter: the conversion of
  // the (integral) tick count to int64_t is exact below 2^63 ticks (29 000
  // years at 10 MHz), and to uint32_t keeps the count modulo 2^32.
  const double ticks = std::floor((stage_.t_s() + tick_offset_s_) * cfg_.tick_hz + 0.5);
  if (!(std::fabs(ticks) < 9.2e18)) return 0U;  // not reachable with a valid config
  return static_cast<uint32_t>(static_cast<int64_t>(ticks));
}

PmsmBoard::State PmsmBoard::state() const {
  const mcsim::PmsmRotorFrame::State& x = stage_.rotor_frame_state();
  const Eigen::Vector2d iab = mcsim::PmsmRotorFrame::i_alpha_beta_a(x);
  State s;
  s << iab(0), iab(1), x(2), x(3);
  return s;
}

void PmsmBoard::true_dq_a(double* id_a, double* iq_a) const {
  *id_a = stage_.rotor_frame_state()(0);
  *iq_a = stage_.rotor_frame_state()(1);
}

void PmsmBoard::sample() {
  const Eigen::Vector3d i = stage_.phase_currents_a();
  adc_.ia_a = static_cast<float>(isense_[0].sample_a(i(0)));
  adc_.ib_a = static_cast<float>(isense_[1].sample_a(i(1)));
  adc_.ic_a = cfg_.three_shunts ? static_cast<float>(isense_[2].sample_a(i(2))) : 0.0f;
  adc_.vbus_v = static_cast<float>(vsense_.sample_v(cfg_.vbus_v));
  adc_.valid_mask = MC_HAL_ADC_VALID_IA | MC_HAL_ADC_VALID_IB | MC_HAL_ADC_VALID_VBUS |
                    (cfg_.three_shunts ? MC_HAL_ADC_VALID_IC : 0U);
  // Injected sensor faults.
  float* ch[3] = {&adc_.ia_a, &adc_.ib_a, &adc_.ic_a};
  for (int k = 0; k < 3; ++k) *ch[k] += static_cast<float>(inj_.offset_a[k]);
  if (inj_.stuck_phase >= 0 && inj_.stuck_phase < 3) {
    *ch[inj_.stuck_phase] = static_cast<float>(inj_.stuck_value_a);
  }
  if (inj_.nan_ia) adc_.ia_a = std::nanf("");
  tick_offset_s_ = 0.0;
  adc_.timestamp_ticks = ticks_now();
  adc_.seq = ++adc_seq_;
  adc_fresh_ = true;

  if (spi_enc_) {
    const mcsim::PmsmRotorFrame::State& x = stage_.rotor_frame_state();
    spi_enc_->observe(stage_.t_s(), x(3), x(2));
  }
  const mcsim::EncoderReading r = encoder_.sample(stage_.rotor_frame_state()(3));
  if (!inj_.encoder_frozen) enc_.count = static_cast<uint32_t>(r.count_in_rev);
  enc_.counts_per_rev = static_cast<uint32_t>(cfg_.encoder.counts_per_rev);
  enc_.flags = inj_.encoder_dead
                   ? 0U
                   : (MC_HAL_ENCODER_FLAG_VALID | (r.index_seen ? MC_HAL_ENCODER_FLAG_INDEX : 0U));
  enc_.timestamp_ticks = adc_.timestamp_ticks;
  // The fast step that follows this sample reads the tick this much later.
  tick_offset_s_ = inj_.compute_delay_s;
}

void PmsmBoard::inject(const Injection& inj) {
  if (inj.open_phase < -1 || inj.open_phase > 2) {
    throw std::invalid_argument("open_phase must be -1 (none) or 0..2");
  }
  check_config(stage_.set_open_phase(inj.open_phase), "open_phase");
  stage_.set_disconnected(inj.motor_disconnected);
  inj_ = inj;
}

void PmsmBoard::advance() {
  tick_offset_s_ = 0.0;
  // The duty register and the enable take effect after the computation
  // delay; a disable (safe torque off) acts at once, as on hardware where it
  // forces the outputs through the timer's break/MOE path.
  const Eigen::Vector3d duty = delay_.push(duty_cmd_);
  const bool enabled = pwm_enabled_ && !fault_line_.killed;
  if (!cfg_.dc_link_enabled) {
    check_config(stage_.advance(duty, enabled), "integrator");
    return;
  }
  // DC link: the power into the motor over the period (trapezoid of the
  // currents at its ends, the alpha-beta voltage held), drawn from the bus
  // as i_inv = P / vbus; the bus voltage after the period is in force for
  // the next one (and is what the ADC samples).
  const Eigen::Vector2d i0 = mcsim::PmsmRotorFrame::i_alpha_beta_a(stage_.rotor_frame_state());
  check_config(stage_.advance(duty, enabled), "integrator");
  const Eigen::Vector2d i1 = mcsim::PmsmRotorFrame::i_alpha_beta_a(stage_.rotor_frame_state());
  const double T = cfg_.inverter.t_pwm_s;
  const double p_w = 0.75 * stage_.v_alpha_beta_applied().dot(i0 + i1);
  motor_in_j_ += p_w * T;
  inverter_a_ = p_w / stage_.vbus_v();
  if (cfg_.dc_link_shared) return;  // the owner advances the link and sets the bus
  link_.advance(T, cfg_.substeps, inverter_a_, brake_duty_);
  cfg_.vbus_v = link_.v();
  stage_.set_vbus_v(link_.v());
}

int PmsmBoard::brake_set_duty(float duty) noexcept {
  if (!(duty >= 0.0f && duty <= 1.0f)) return -EINVAL;
  brake_duty_ = duty;
  return 0;
}

int PmsmBoard::adc_read(mc_hal_adc_sample_t* s) noexcept {
  if (!adc_fresh_) return -EAGAIN;
  *s = adc_;
  adc_fresh_ = false;
  return 0;
}

int PmsmBoard::adc_read_temp(mc_hal_adc_temp_t* t) noexcept {
  t->power_stage_temp_c = 25.0f;
  t->motor_temp_c = 25.0f;
  t->valid_mask = MC_HAL_ADC_TEMP_VALID_ALL;
  t->absent_mask = cfg_.thermal_enabled ? MC_HAL_ADC_TEMP_VALID_MOTOR : 0u;
  if (cfg_.thermal_enabled && cfg_.motor_thermistor) {
    t->motor_temp_c = static_cast<float>(stage_.thermal()->winding_c());
    t->absent_mask = 0u;
  } else if (cfg_.thermal_enabled) {
    t->valid_mask = MC_HAL_ADC_TEMP_VALID_POWER_STAGE;
    t->motor_temp_c = 0.0f;
  }
  return 0;
}

int PmsmBoard::pwm_set_duty(float a, float b, float c) noexcept {
  if (!mc_hal_pwm3_duty_valid(a) || !mc_hal_pwm3_duty_valid(b) || !mc_hal_pwm3_duty_valid(c)) {
    return -EINVAL;
  }
  duty_cmd_ << a, b, c;
  return 0;
}

int PmsmBoard::pwm_enable() noexcept {
  if (fault_line_.killed) return -EBUSY;
  pwm_enabled_ = true;
  return 0;
}

int PmsmBoard::pwm_disable() noexcept {
  pwm_enabled_ = false;
  return 0;
}

int PmsmBoard::pwm_get_state(mc_hal_pwm3_state_t* st) noexcept {
  st->duty_a = static_cast<float>(duty_cmd_(0));
  st->duty_b = static_cast<float>(duty_cmd_(1));
  st->duty_c = static_cast<float>(duty_cmd_(2));
  st->period_s = static_cast<float>(cfg_.inverter.t_pwm_s);
  st->enabled = pwm_enabled_ && !fault_line_.killed;
  return 0;
}

int PmsmBoard::encoder_read(mc_hal_encoder_sample_t* s) noexcept {
  // the SPI encoder's driver makes its frame now (the PIL link asks here;
  // the SIL's drive reads the driver's device itself)
  if (spi_enc_) return mc_hal_encoder_read(spi_enc_->encoder(), s);
  *s = enc_;
  return 0;
}

int PmsmBoard::tick_read(uint32_t* ticks) const noexcept {
  *ticks = ticks_now();
  return 0;
}

int PmsmBoard::tick_freq(uint32_t* hz) const noexcept {
  *hz = static_cast<uint32_t>(cfg_.tick_hz);
  return 0;
}

void PmsmBoard::set_load(const mcsim::LoadTorque& load) {
  check_config(stage_.set_load(load), "load");
}

void PmsmBoard::set_fault_inputs(uint32_t active_mask) {
  fault_line_.set_inputs(active_mask);
}

int PmsmBoard::fault_read(mc_hal_fault_status_t* st) noexcept {
  fault_line_.read(st);
  return 0;
}

void PmsmBoard::fault_gate_kill() noexcept {
  fault_line_.killed = true;
}

int PmsmBoard::fault_gate_release() noexcept {
  if (!fault_line_.release()) return -EBUSY;
  pwm_enabled_ = false;
  return 0;
}

}  // namespace hal_host
