#include "observer_sil.hpp"

#include <cmath>
#include <stdexcept>

#include "hal_host/sil_rig.hpp"

namespace mcsim {
namespace observer {

namespace {
constexpr double kPi = 3.14159265358979323846;

double load_fn(double t_s, double /*theta_m_rad*/, double /*omega_m_rad_s*/, const void* ctx) {
  return static_cast<const LoadSteps*>(ctx)->eval(t_s);
}
}  // namespace

double LoadSteps::eval(double t_s) const {
  double v = 0.0;
  for (const auto& s : steps) {
    if (t_s >= s.first) v = s.second;
  }
  return v;
}

Machine table1_40kw() {
  Machine m;
  m.name = "paper002-table1-40kW";
  m.motor.R_ohm = 0.065;
  m.motor.Ld_h = 0.655e-3;
  m.motor.Lq_h = 0.655e-3;
  m.motor.flux_wb = 0.146;
  m.motor.pole_pairs = 3;
  // Our choice (not in the paper): a 40 kW, 180 N m machine of this size
  // has a rotor of about 0.05 kg m^2; with its load, 0.1 kg m^2 (rated
  // torque accelerates it at 1800 rad/s^2). Friction 0.02 N m s/rad:
  // 4.6 N m, 2.6 % of rated torque, at rated speed.
  m.motor.J_kgm2 = 0.1;
  m.motor.B_nms_rad = 0.02;
  m.vbus_v = 240.0;
  m.rated_torque_nm = 180.0;
  m.rated_speed_rpm = 2200.0;
  m.rated_current_a = 216.0;
  m.i_full_scale_a = 800.0;
  return m;
}

Machine test_motor_300w() {
  Machine m;
  m.name = "paper002-table1-test-motor-0.3kW";
  m.motor.R_ohm = 0.675;
  m.motor.Ld_h = 1.14e-3;
  m.motor.Lq_h = 1.14e-3;
  m.motor.flux_wb = 0.11;
  m.motor.pole_pairs = 4;
  // Our choice: the test motor is coupled to a 1 kW dynamometer motor; the
  // pair with the coupler is taken as 5e-3 kg m^2 (about 3x the rotors of
  // motors of this size). Friction 1e-3 N m s/rad (0.1 N m, 3 % of rated
  // torque, at 1000 r/min).
  m.motor.J_kgm2 = 5.0e-3;
  m.motor.B_nms_rad = 1.0e-3;
  m.vbus_v = 200.0;
  m.rated_torque_nm = 3.0;
  m.rated_speed_rpm = 1000.0;
  m.rated_current_a = 3.0;  // rms in the paper; peak 4.24 A gives 2.8 N m
  m.i_full_scale_a = 20.0;
  return m;
}

mc_ctrl_sls_cfg_t default_ctrl_cfg(const Machine& m, const SilOptions& o) {
  const double pp = m.motor.pole_pairs, kt = 1.5 * pp * m.motor.flux_wb;
  const double w_rated = m.rated_speed_rpm * 2 * kPi / 60.0;
  mc_ctrl_sls_cfg_t c{};
  c.r_ohm = static_cast<float>(m.motor.R_ohm * (1.0 + o.r_error));
  c.l_h = static_cast<float>(m.motor.Ld_h);
  c.flux_wb = static_cast<float>(m.motor.flux_wb * (1.0 + o.flux_error));
  c.pole_pairs = static_cast<uint32_t>(m.motor.pole_pairs);
  c.dt_s = static_cast<float>(1.0 / o.pwm_hz);
  c.pwm_delay_periods = static_cast<uint32_t>(o.delay_periods);
  c.speed_div = o.speed_div;
  c.dead_time_s = static_cast<float>(o.dead_time_s * o.dead_comp_frac);
  c.dead_band_a = static_cast<float>(0.01 * m.rated_current_a);
  c.dead_comp_duty = o.dead_comp_duty;
  // Observer: critical speed 2 % of rated by default (44 r/min for the
  // 40 kW machine, 20 r/min for the test motor, below the paper's 50 r/min
  // trouble zone).
  c.omega_crit_m_rad_s = static_cast<float>(o.crit_frac * w_rated);
  c.resid_tol = 0.3f;
  c.resid_time_s = 0.05f;
  c.pll_bw_rad_s = 300.0f;
  // Current loop: 2 pi 100 Hz, 2 pi bw / f_pwm = 0.08 (within 20 % of first
  // order with the one-period delay, see foc-current-step).
  c.cur_bw_rad_s = static_cast<float>(2 * kPi * 100.0);
  c.v_limit_ratio = 0.95f;
  c.vbus_max_v = static_cast<float>(m.vbus_v * 1.5);
  // Speed loop: crossover wc (default 100 rad/s: 1/8 of the 800 Hz speed
  // loop rate; the sampling and the PLL cost about 14 deg there) on the
  // plant kt/(J s), PI zero at wc/4.
  const double wc = o.speed_wc_rad_s;
  c.speed_kp_a_s_rad = static_cast<float>(m.motor.J_kgm2 * wc / kt);
  c.speed_ki_a_rad = static_cast<float>(c.speed_kp_a_s_rad * wc / 4.0);
  // torque limit: 1.5x rated torque
  c.iq_max_a = static_cast<float>(1.5 * m.rated_torque_nm / kt);
  c.speed_slew_rad_s2 = static_cast<float>(0.5 * m.rated_torque_nm / m.motor.J_kgm2);
  c.speed_max_rad_s = static_cast<float>(1.2 * w_rated);
  // Start-up: I-f at 60 % of rated torque current, hand-over at 10 % of
  // rated speed (5x the critical speed), back to I-f below 7 %.
  c.if_current_a = static_cast<float>(0.6 * m.rated_torque_nm / kt);
  c.align_time_s = 0.05f;
  c.if_accel_rad_s2 = static_cast<float>(0.2 * m.rated_torque_nm / m.motor.J_kgm2);
  c.handover_speed_rad_s = static_cast<float>(0.1 * w_rated);
  c.handover_hyst = 0.3f;
  c.lock_tol = 0.2f;
  c.if_lock_timeout_s = 0.5f;
  c.blend_time_s = 0.05f;
  c.lowspeed_fallback = o.lowspeed_fallback;
  c.if_damping = o.if_damping;
  return c;
}

mc_ctrl_sls_q31_cfg_t q31_ctrl_cfg(const Machine& m, const mc_ctrl_sls_cfg_t& f) {
  mc_ctrl_sls_q31_cfg_t q{};
  q.f = f;
  q.i_base_a = static_cast<float>(m.i_full_scale_a);
  q.v_base_v = static_cast<float>(2.0 * m.vbus_v);
  const double w_pll = 2.0 * f.speed_max_rad_s * f.pole_pairs;
  q.omega_base_e_rad_s = static_cast<float>(std::exp2(std::ceil(std::log2(1.2 * w_pll))));
  q.flux_base_wb = static_cast<float>(
      std::exp2(std::ceil(std::log2(1.5 * (f.flux_wb + f.l_h * m.i_full_scale_a)))));
  return q;
}

Sil::Sil(const Machine& m, const SilOptions& o, const mc_ctrl_sls_cfg_t& cfg, LoadSteps load)
    : m_(m), o_(o), load_(std::move(load)) {
  hal_host::PmsmBoardConfig bc;
  bc.motor = m.motor;
  bc.motor.load.kind = LoadKind::kFunction;
  bc.motor.load.fn = &load_fn;
  bc.motor.load.fn_ctx = &load_;
  bc.inverter.t_pwm_s = 1.0 / o.pwm_hz;
  bc.inverter.t_dead_s = o.dead_time_s;
  bc.inverter.i_dead_band_a = 0.01 * m.rated_current_a;
  bc.vbus_v = m.vbus_v;
  bc.current_sensor.full_scale_a = m.i_full_scale_a;
  bc.current_sensor.bits = 12;
  bc.current_sensor.noise_rms_a = o.noise_rms_a;
  bc.vbus_sensor.full_scale_v = 2.0 * m.vbus_v;
  bc.encoder.counts_per_rev = o.encoder_cpr;  // present on the board, unused by the law
  bc.substeps = o.substeps;
  bc.delay_periods = o.delay_periods;
  board_ = std::make_unique<hal_host::PmsmBoard>(bc);

  const uint32_t cerr = mc_ctrl_sls_init(&ctrl_, &cfg);
  if (cerr != 0u) {
    throw std::invalid_argument("sensorless controller rejected its configuration: bits " +
                                std::to_string(cerr) + " (decimal)");
  }
  // The drive's current loop runs the f32 law's references (the q31 twin
  // runs its own): kp = L bw, ki = R bw at the law's bandwidth, and the
  // law's duty-side dead-time correction.
  mc_drive_cfg_t dc{};
  float kp = 0.0f, ki = 0.0f;
  (void)mc_foc_f32_gains_from_bandwidth(cfg.r_ohm, cfg.l_h, cfg.cur_bw_rad_s, &kp, &ki);
  dc.foc.r_ohm = cfg.r_ohm;
  dc.foc.ld_h = cfg.l_h;
  dc.foc.lq_h = cfg.l_h;
  dc.foc.flux_wb = cfg.flux_wb;
  dc.foc.kp_d_v_per_a = kp;
  dc.foc.ki_d_v_per_as = ki;
  dc.foc.kp_q_v_per_a = kp;
  dc.foc.ki_q_v_per_as = ki;
  dc.dead_time_comp = cfg.dead_comp_duty && cfg.dead_time_s > 0.0f;
  dc.dead_time_s = cfg.dead_time_s;
  dc.dead_band_a = cfg.dead_band_a;
  dc.foc.dt_s = cfg.dt_s;
  dc.foc.aw = MC_PI_AW_CLAMP;
  dc.foc.limit_mode = MC_SVPWM_LIMIT_CIRCLE;
  dc.foc.v_limit_ratio = cfg.v_limit_ratio;
  dc.foc.v_abs_max_v = cfg.vbus_max_v;
  dc.foc.decouple = true;
  dc.pole_pairs = cfg.pole_pairs;
  dc.speed_pll_bw_rad_s = 500.0f;
  dc.slow_loop_div = o.speed_div;
  // The drive's current limits (references, not used in CTRL mode) and the
  // instantaneous trip: 1.9 x the torque limit, inside the sensor range.
  dc.i_max_a = static_cast<float>(1.5 * cfg.iq_max_a);
  dc.i_trip_a = static_cast<float>(std::min(1.9 * cfg.iq_max_a, 0.98 * m.i_full_scale_a));
  dc.vbus_min_v = static_cast<float>(0.5 * m.vbus_v);
  dc.vbus_max_v = static_cast<float>(1.5 * m.vbus_v);
  dc.omega_max_rad_s = static_cast<float>(2.0 * cfg.speed_max_rad_s);
  const uint32_t derr = mc_drive_init(&drive_, &dc, board_->hal());
  if (derr != MC_DRIVE_CFG_OK) {
    throw std::invalid_argument("drive configuration rejected, MC_DRIVE_CFG bits " +
                                std::to_string(derr) + " (decimal)");
  }
  if (o.q31) {
    const mc_ctrl_sls_q31_cfg_t qc = q31_ctrl_cfg(m, cfg);
    const uint32_t qerr = mc_ctrl_sls_q31_init(&ctrl_q31_, &qc);
    if (qerr != 0u) {
      throw std::invalid_argument("q31 sensorless controller rejected its configuration: bits " +
                                  std::to_string(qerr) + " (decimal)");
    }
    mc_ctrl_sls_q31_get_tm_f32(&ctrl_q31_, &tm_q31_);
  }
  const mc_drive_ctrl_t* table = o.q31 ? mc_ctrl_sls_q31_ops(&ctrl_q31_) : mc_ctrl_sls_ops(&ctrl_);
  if (mc_drive_attach_ctrl(&drive_, table) != 0) {
    throw std::runtime_error("drive refused the sensorless control law");
  }
  if (mc_drive_set_mode(&drive_, MC_DRIVE_MODE_CTRL) != 0) {
    throw std::runtime_error("drive refused CTRL mode");
  }
}

void Sil::step() {
  (void)hal_host::sil_period(
      *board_, drive_,
      [this] {
        theta_e_sampled_ = std::remainder(m_.motor.pole_pairs * board_->state()(3), 2 * kPi);
      },
      [this] {
        if (o_.q31) mc_ctrl_sls_q31_get_tm_f32(&ctrl_q31_, &tm_q31_);
      });
}

uint32_t Sil::set_speed_ref(float omega_m_rad_s) {
  return o_.q31 ? mc_ctrl_sls_q31_set_speed_ref(&ctrl_q31_, omega_m_rad_s)
                : mc_ctrl_sls_set_speed_ref(&ctrl_, omega_m_rad_s);
}

void Sil::flux_hat_wb(double* p_alpha, double* p_beta) const {
  if (o_.q31) {
    float a = 0.0f, b = 0.0f;
    mc_ctrl_sls_q31_get_flux_wb(&ctrl_q31_, &a, &b);
    *p_alpha = a;
    *p_beta = b;
  } else {
    *p_alpha = ctrl_.obs.x_alpha_wb;
    *p_beta = ctrl_.obs.x_beta_wb;
  }
}

double Sil::angle_error() const {
  return std::remainder(static_cast<double>(tm().theta_hat_e_rad) - theta_e_true(), 2 * kPi);
}

void Sil::record(Summary& s) const {
  const auto& p = m_.motor;
  const auto& c = ctrl_.cfg;
  s.set_text("machine", m_.name);
  s.set_text("kernels", o_.q31 ? "q31" : "f32");
  if (o_.q31) {
    const auto& q = ctrl_q31_.cfg;
    s.set("q31_i_base_a", q.i_base_a);
    s.set("q31_v_base_v", q.v_base_v);
    s.set("q31_omega_base_e_rad_s", q.omega_base_e_rad_s);
    s.set("q31_flux_base_wb", q.flux_base_wb);
  }
  s.set("motor_R_ohm", p.R_ohm);
  s.set("motor_L_h", p.Ld_h);
  s.set("motor_flux_wb", p.flux_wb);
  s.set("motor_pole_pairs", p.pole_pairs);
  s.set("motor_J_kgm2", p.J_kgm2);
  s.set("motor_B_nms_rad", p.B_nms_rad);
  s.set("rated_torque_nm", m_.rated_torque_nm);
  s.set("rated_speed_rpm", m_.rated_speed_rpm);
  s.set("vbus_v", m_.vbus_v);
  s.set("inverter_pwm_hz", o_.pwm_hz);
  s.set("inverter_dead_time_s", o_.dead_time_s);
  s.set("inverter_dead_band_a", 0.01 * m_.rated_current_a);
  s.set("ctrl_dead_time_s", c.dead_time_s);
  s.set("ctrl_dead_comp_duty", c.dead_comp_duty ? 1.0 : 0.0);
  s.set("board_delay_periods", o_.delay_periods);
  s.set("encoder_cpr", o_.encoder_cpr);
  s.set("ctrl_r_error", o_.r_error);
  s.set("ctrl_flux_error", o_.flux_error);
  s.set("plant_rk4_substeps", o_.substeps);
  s.set("current_sensor_full_scale_a", m_.i_full_scale_a);
  s.set("current_sensor_bits", 12);
  s.set("current_sensor_noise_rms_a", o_.noise_rms_a);
  s.set("ctrl_R_ohm", c.r_ohm);
  s.set("ctrl_L_h", c.l_h);
  s.set("ctrl_flux_wb", c.flux_wb);
  s.set("obs_gamma_per_wb2_s", ctrl_.gamma);
  s.set("obs_omega_crit_m_rad_s", c.omega_crit_m_rad_s);
  s.set("obs_omega_crit_rpm", c.omega_crit_m_rad_s * 60.0 / (2 * kPi));
  s.set("obs_time_scale_s", 2.0 / (ctrl_.gamma * c.flux_wb * c.flux_wb));
  s.set("obs_resid_tol", c.resid_tol);
  s.set("obs_resid_time_s", c.resid_time_s);
  s.set("pll_bw_rad_s", c.pll_bw_rad_s);
  s.set("current_loop_rate_hz", 1.0 / c.dt_s);
  s.set("current_loop_bw_rad_s", c.cur_bw_rad_s);
  s.set("current_kp_v_per_a", drive_.cfg.foc.kp_d_v_per_a);
  s.set("current_ki_v_per_as", drive_.cfg.foc.ki_d_v_per_as);
  s.set("speed_loop_rate_hz", 1.0 / (c.dt_s * static_cast<float>(c.speed_div)));
  s.set("speed_wc_rad_s", o_.speed_wc_rad_s);
  s.set("speed_kp_a_s_rad", c.speed_kp_a_s_rad);
  s.set("speed_ki_a_rad", c.speed_ki_a_rad);
  s.set("iq_max_a", c.iq_max_a);
  s.set("speed_slew_rad_s2", c.speed_slew_rad_s2);
  s.set("if_current_a", c.if_current_a);
  s.set("if_accel_rad_s2", c.if_accel_rad_s2);
  s.set("handover_speed_rad_s", c.handover_speed_rad_s);
  s.set("handover_hyst", c.handover_hyst);
  s.set("blend_time_s", c.blend_time_s);
  s.set("if_damping", c.if_damping ? 1.0 : 0.0);
  s.set("lowspeed_fallback", c.lowspeed_fallback ? 1.0 : 0.0);
}

}  // namespace observer
}  // namespace mcsim
