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

// Amplitude-invariant inverse Clarke.
Eigen::Vector3d abc_from_ab(double a, double b) {
  const double s3 = std::sqrt(3.0) / 2.0;
  return {a, -0.5 * a + s3 * b, -0.5 * a - s3 * b};
}

}  // namespace

PmsmBoard::PmsmBoard(const PmsmBoardConfig& cfg) : cfg_(cfg) {
  check_config(plant_.configure(cfg.motor), "motor");
  check_config(inverter_.configure(cfg.inverter), "inverter");
  for (int k = 0; k < 3; ++k) {
    mcsim::CurrentSensorParams p = cfg.current_sensor;
    p.seed = cfg.current_sensor.seed + static_cast<uint64_t>(k) * 7919U;
    check_config(isense_[k].configure(p), "current_sensor");
  }
  check_config(vsense_.configure(cfg.vbus_sensor), "vbus_sensor");
  check_config(encoder_.configure(cfg.encoder), "encoder");
  if (cfg.substeps < 1) throw std::invalid_argument("substeps must be >= 1");
  if (cfg.delay_periods < 0) throw std::invalid_argument("delay_periods must be >= 0");
  check_config(delay_.configure(static_cast<std::size_t>(cfg.delay_periods), duty_cmd_), "delay_periods");
  if (!(cfg.vbus_v > 0.0) || !std::isfinite(cfg.vbus_v)) throw std::invalid_argument("vbus_v must be > 0");
  if (!(cfg.tick_hz >= 1.0) || cfg.tick_hz > 4.0e9) throw std::invalid_argument("tick_hz out of range");

  x_ = plant_.make_state(0.0, 0.0, cfg.omega_m0_rad_s, cfg.theta_m0_rad);
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
  hal_.can = nullptr;
  hal_.tick = &tick_dev_;
  hal_.fault = &fault_dev_;
}

uint32_t PmsmBoard::ticks_now() const {
  // Modulo 2^32, like a free-running hardware counter: the conversion of
  // the (integral) tick count to int64_t is exact below 2^63 ticks (29 000
  // years at 10 MHz), and to uint32_t keeps the count modulo 2^32.
  const double ticks = std::floor((t_s_ + tick_offset_s_) * cfg_.tick_hz + 0.5);
  if (!(std::fabs(ticks) < 9.2e18)) return 0U;  // not reachable with a valid config
  return static_cast<uint32_t>(static_cast<int64_t>(ticks));
}

Eigen::Vector3d PmsmBoard::phase_currents_a() const {
  const Eigen::Vector2d iab = mcsim::PmsmRotorFrame::i_alpha_beta_a(x_);
  return abc_from_ab(iab(0), iab(1));
}

Eigen::Vector3d PmsmBoard::phase_currents_true_a() const {
  if (inj_.open_phase >= 0 && !open_fresh_) {
    mcsim::PmsmOpenPhase::State xo = mcsim::PmsmOpenPhase::State::Zero();
    xo(mcsim::PmsmOpenPhase::kI) = open_i_a_;
    return open_plant_.phase_currents_a(xo);
  }
  return phase_currents_a();
}

PmsmBoard::State PmsmBoard::state() const {
  const Eigen::Vector2d iab = mcsim::PmsmRotorFrame::i_alpha_beta_a(x_);
  State s;
  s << iab(0), iab(1), x_(2), x_(3);
  return s;
}

void PmsmBoard::true_dq_a(double* id_a, double* iq_a) const {
  *id_a = x_(0);
  *iq_a = x_(1);
}

void PmsmBoard::sample() {
  const Eigen::Vector3d i = phase_currents_a();
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

  const mcsim::EncoderReading r = encoder_.sample(x_(3));
  if (!inj_.encoder_frozen) enc_.count = static_cast<uint32_t>(r.count_in_rev);
  enc_.counts_per_rev = static_cast<uint32_t>(cfg_.encoder.counts_per_rev);
  enc_.flags = inj_.encoder_dead
                   ? 0U
                   : (MC_HAL_ENCODER_FLAG_VALID | (r.index_seen ? MC_HAL_ENCODER_FLAG_INDEX : 0U));
  enc_.timestamp_ticks = adc_.timestamp_ticks;
  // The fast step that follows this sample reads the tick this much later.
  tick_offset_s_ = inj_.compute_delay_s;
}

void PmsmBoard::integrate_open_switches(double h_s, int n) {
  const double vbus = cfg_.vbus_v;
  const double p = cfg_.motor.pole_pairs;
  for (int k = 0; k < n; ++k) {
    const double t = t_s_ + k * h_s;
    if (open_circuit_) {
      // Open circuit: currents stay zero unless the back-EMF exceeds vbus,
      // in which case the diode bridge conducts again.
      const double emf_ll_peak = std::sqrt(3.0) * std::abs(p * x_(2)) * cfg_.motor.flux_wb;
      if (emf_ll_peak <= vbus) {
        x_(0) = x_(1) = 0.0;
        const mcsim::PmsmRotorFrame::Input u = mcsim::PmsmRotorFrame::Input::Zero();
        // Mechanics only: with zero current there is no torque, and the
        // electrical equations are not integrated (open terminals).
        const mcsim::PmsmRotorFrame::State x1 = mcsim::rk4_step(plant_, t, x_, u, h_s);
        x_.tail<4>() = x1.tail<4>();
        continue;
      }
      open_circuit_ = false;
    }
    // Diode freewheeling: pole at 0 V for current into the motor, at vbus
    // for current out of it; a phase with no current sits at mid-bus.
    const Eigen::Vector3d i = phase_currents_a();
    Eigen::Vector3d duty;
    for (int j = 0; j < 3; ++j) duty(j) = (i(j) > 0.0) ? 0.0 : ((i(j) < 0.0) ? 1.0 : 0.5);
    const Eigen::Vector2d v = inverter_.alpha_beta_v(duty, vbus, Eigen::Vector3d::Zero());
    const mcsim::PmsmRotorFrame::State before = x_;
    mcsim::PmsmRotorFrame::State x1 = mcsim::rk4_step(plant_, t, x_, v, h_s);
    // The diodes block reverse current: if the current vector reversed
    // within the sub-step, it reached zero inside it.
    if (x1(0) * before(0) + x1(1) * before(1) <= 0.0) {
      x1(0) = x1(1) = 0.0;
      open_circuit_ = true;
    }
    x_ = x1;
    v_ab_applied_ = v;
  }
}

namespace {

// The open-phase plant with the series current held at zero: open terminals
// (no current, no torque), only the mechanics move.
struct OpenPhaseNoCurrent {
  using State = mcsim::PmsmOpenPhase::State;
  using Input = mcsim::PmsmOpenPhase::Input;
  const mcsim::PmsmOpenPhase* plant;
  State deriv(double t_s, const State& x, const Input& u) const {
    State x0 = x;
    x0(mcsim::PmsmOpenPhase::kI) = 0.0;
    State dx = plant->deriv(t_s, x0, u);
    dx(mcsim::PmsmOpenPhase::kI) = 0.0;
    return dx;
  }
};

}  // namespace

void PmsmBoard::inject(const Injection& inj) {
  if (inj.open_phase < -1 || inj.open_phase > 2) {
    throw std::invalid_argument("open_phase must be -1 (none) or 0..2");
  }
  if (inj.open_phase >= 0) {
    check_config(open_plant_.configure(plant_.params(), inj.open_phase), "open_phase");
  }
  if (inj.open_phase != inj_.open_phase) open_fresh_ = true;
  inj_ = inj;
}

void PmsmBoard::advance_open_phase(const Eigen::Vector3d& duty, bool enabled) {
  using OP = mcsim::PmsmOpenPhase;
  const double T = cfg_.inverter.t_pwm_s;
  const int n = cfg_.substeps;
  const double h = T / n;
  const double vbus = cfg_.vbus_v;
  // Mechanics and (cos, sin) from x_ (re-synced there); the series current
  // carried over, or projected at the break.
  OP::State xo = open_plant_.from_rotor_frame(x_);
  if (!open_fresh_) xo(OP::kI) = open_i_a_;
  open_fresh_ = false;
  const int y = open_plant_.phase_y();
  const int z = open_plant_.phase_z();
  if (enabled) {
    // The pair sees the difference of its two pole voltages (held over the
    // period, dead time evaluated at the period's start as on the healthy path).
    const Eigen::Vector3d i = open_plant_.phase_currents_a(xo);
    const Eigen::Vector3d vp = inverter_.pole_voltages_v(duty, vbus, i);
    const OP::Input u(vp(y) - vp(z));
    duty_applied_ = duty;
    v_ab_applied_ = inverter_.alpha_beta_v(duty, vbus, i);  // commanded; the
                                                            // motor sees its part along the pair
    check_config(mcsim::advance_zoh(open_plant_, u, t_s_, T, n, &xo), "integrator");
  } else {
    duty_applied_ = Eigen::Vector3d::Constant(0.5);
    v_ab_applied_ = Eigen::Vector2d::Zero();
    for (int k = 0; k < n; ++k) {
      const double t = t_s_ + k * h;
      const double i0 = xo(OP::kI);
      const double e = open_plant_.line_emf_v(xo);
      if (i0 == 0.0 && std::abs(e) <= vbus) {
        // Diodes blocking: no current, mechanics only.
        const OpenPhaseNoCurrent nc{&open_plant_};
        xo = mcsim::rk4_step(nc, t, xo, OP::Input::Zero(), h);
        xo(OP::kI) = 0.0;
        continue;
      }
      // Current i > 0 flows into y (its lower diode: pole at 0 V) and out of
      // z (upper diode: vbus): v_yz = -vbus; reversed for i < 0. From zero,
      // a line back-EMF beyond vbus drives the current the way it points.
      const double dir = (i0 != 0.0) ? i0 : -e;
      const OP::Input u((dir > 0.0) ? -vbus : vbus);
      OP::State x1 = mcsim::rk4_step(open_plant_, t, xo, u, h);
      if (i0 != 0.0 && x1(OP::kI) * i0 <= 0.0) x1(OP::kI) = 0.0;  // diodes block reversal
      xo = x1;
    }
  }
  open_i_a_ = xo(OP::kI);
  open_circuit_ = (open_i_a_ == 0.0);
  x_ = open_plant_.to_rotor_frame(xo);
}

void PmsmBoard::advance() {
  tick_offset_s_ = 0.0;
  const double T = cfg_.inverter.t_pwm_s;
  const int n = cfg_.substeps;
  // The duty register and the enable take effect after the computation
  // delay; a disable (safe torque off) acts at once, as on hardware where it
  // forces the outputs through the timer's break/MOE path.
  const Eigen::Vector3d duty = delay_.push(duty_cmd_);
  const bool enabled = pwm_enabled_ && !fault_line_.killed;
  if (inj_.open_phase >= 0) {
    advance_open_phase(duty, enabled);
  } else if (!enabled) {
    integrate_open_switches(T / n, n);
    duty_applied_ = Eigen::Vector3d::Constant(0.5);
  } else {
    open_circuit_ = false;
    duty_applied_ = duty;
    // The inverter uses the phase currents only for the dead-time error.
    const Eigen::Vector3d i =
        (cfg_.inverter.t_dead_s > 0.0) ? phase_currents_a() : Eigen::Vector3d::Zero();
    const Eigen::Vector2d v = inverter_.alpha_beta_v(duty, cfg_.vbus_v, i);
    v_ab_applied_ = v;
    check_config(plant_.advance_zoh(v, t_s_, T, n, &x_), "integrator");
  }
  // (cos, sin) of the electrical angle are integrated as states; re-derive
  // them from theta_m every 32 periods (drift per period is O(h^5)).
  if ((++period_count_ & 31U) == 0U) plant_.resync(&x_);
  t_s_ += T;
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
  mcsim::PmsmParams p = plant_.params();
  p.load = load;
  check_config(plant_.configure(p), "load");
  if (inj_.open_phase >= 0) check_config(open_plant_.configure(p, inj_.open_phase), "load");
}

void PmsmBoard::set_fault_inputs(uint32_t active_mask) { fault_line_.set_inputs(active_mask); }

int PmsmBoard::fault_read(mc_hal_fault_status_t* st) noexcept {
  fault_line_.read(st);
  return 0;
}

void PmsmBoard::fault_gate_kill() noexcept { fault_line_.killed = true; }

int PmsmBoard::fault_gate_release() noexcept {
  if (!fault_line_.release()) return -EBUSY;
  pwm_enabled_ = false;
  return 0;
}

}  // namespace hal_host
