#include "app_scenario.hpp"

#include <cmath>
#include <cstdio>

#include "verdict.hpp"

namespace mcsim {

namespace {

AppSetup file_setup(const MotorFiles& plant, const mc_params_t& p,
                    const std::function<double(double)>* load_nm) {
  AppSetup s;
  s.board = build_board_cfg(plant);
  attach_load(s.board, load_nm);
  s.defaults = p;
  return s;
}

}  // namespace

std::unique_ptr<AppTarget> make_file_target(const MotorFiles& plant, const mc_params_t& p,
                                            const std::function<double(double)>* load_nm,
                                            const std::function<void(AppSetup&)>& adjust) {
  AppSetup s = file_setup(plant, p, load_nm);
  if (adjust) adjust(s);
  return make_app_target_sil(s);
}

std::unique_ptr<AppTarget> make_file_target(const RunContext& ctx, const MotorFiles& plant,
                                            const mc_params_t& p,
                                            const std::function<double(double)>* load_nm,
                                            const std::function<void(AppSetup&)>& adjust) {
  AppSetup s = file_setup(plant, p, load_nm);
  if (adjust) adjust(s);
  if (ctx.pil == nullptr) return make_app_target_sil(s);
  std::unique_ptr<AppTarget> t = make_app_target_pil(s, *ctx.pil);
  std::fprintf(stderr, "mcsim: target %s\n", t->name().c_str());
  return t;
}

double AppRecorder::theta_e_true() {
  constexpr double kTwoPi = 6.28318530717958647692;
  return std::remainder(pole_pairs * run.board().rotor_frame_state()(3), kTwoPi);
}

void AppRecorder::header() {
  std::vector<std::string> c = {"t",         "i_d_a",         "i_q_a",           "i_d_ref_a",
                                "i_q_ref_a", "omega_m_rad_s", "omega_ref_rad_s", "theta_e_rad"};
  if (hat) c.emplace_back("theta_e_hat_rad");
  c.insert(c.end(), {"v_d_v", "v_q_v", "fault_1"});
  ctx.csv.columns(c);
}

void AppRecorder::row(double t, double id, double iq, double w) {
  if (k++ % every != 0) return;
  const mc_app_probe_t& p = run.probe();
  const double th = theta_e_true();
  const Eigen::Vector2d& v = run.board().v_alpha_beta_applied();
  const double c = std::cos(th), s = std::sin(th);
  double r[12];
  size_t n = 0;
  for (double x : {t, id, iq, static_cast<double>(p.id_ref_a), static_cast<double>(p.iq_ref_a), w,
                   static_cast<double>(p.omega_ref_rad_s), th}) {
    r[n++] = x;
  }
  if (hat) r[n++] = std::remainder(static_cast<double>(p.sls_theta_hat_e_rad), 6.283185307179586);
  r[n++] = c * v(0) + s * v(1);
  r[n++] = -s * v(0) + c * v(1);
  r[n++] = static_cast<double>(p.faults);
  ctx.csv.row(r, n);
}

std::string AppWatch::operator()(const mc_app_probe_t& p) {
  if (p.faults != 0u) {
    std::string s = drive_fault_names(p.faults);
    if ((p.faults & MC_DRIVE_FAULT_CONTROL) != 0u) {
      s += " (law error bits " + std::to_string(p.ctrl_err) + ")";
    }
    return s;
  }
  if (p.cmd_enabled != 0u) was_enabled_ = true;
  if (was_enabled_ && p.cmd_enabled == 0u) {
    return "the application stopped the drive (stop_reason " + std::to_string(p.cmd_stop_reason) +
           ", stop cause " + std::to_string(p.stop_cause) + ")";
  }
  return "";
}

}  // namespace mcsim
