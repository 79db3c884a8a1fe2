#include "app_scenario.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "board_hall.hpp"
#include "hal_host/file_flash.hpp"
#include "verdict.hpp"

namespace mcsim {

Scenario on_app_target(Scenario s) {
  s.takes_pil = true;
  s.takes_flash = true;
  if (s.motor_params) {
    const auto own = s.motor_params;
    s.motor_params = [own](const MotorFiles& f) {
      std::vector<ParamSpec> v = own(f);
      for (const ParamSpec& k : app_powerup_params(f)) {
        if (std::none_of(v.begin(), v.end(), [&](const ParamSpec& x) { return x.key == k.key; })) {
          v.push_back(k);
        }
      }
      return v;
    };
  }
  return s;
}

void set_board_sensor(const MotorFiles& f, hal_host::PmsmBoardConfig& bc) {
  bc.encoder.has_index = f.board.encoder == kEncoderAbiIndex;
  bc.encoder.index_angle_rad = bc.encoder.has_index ? f.board.encoder_index_rad : 0.0;
  set_board_spi_encoder(f, bc);
}

namespace {

const char* const kBootNames[] = {"STORED", "MIGRATED", "EMPTY", "CORRUPT",
                                  "LAYOUT", "INVALID",  "FLASH"};
const char* const kBootWhy[] = {
    "",
    "",
    "",
    "no valid record, and the sectors are not erased: not a configuration this drive wrote",
    "the newest record has another format or layout: a foreign image's",
    "the newest record fails the drive's validation or another board's PWM rate",
    "the flash could not be read"};

// The board's own quantities: a stored set that differs in one was saved
// on another board (the simulated board is the files').
void refuse_foreign(const std::string& file, const mc_params_t& stored, const mc_params_t& board) {
  const char* const keys[] = {"pwm_hz",        "dead_time_s", "vbus_v",     "current_sensors",
                              "i_sense_max_a", "adc_bits",    "encoder_cpr"};
  for (const char* k : keys) {
    const mc_param_info_t& info = mc_param_table[mc_param_find_name(k)];
    const uint32_t a = mc_param_get_raw(&stored, &info), b = mc_param_get_raw(&board, &info);
    if (a == b) continue;
    mc_param_value_t va, vb;
    va.u = a;
    vb.u = b;
    const bool f32 = info.type == MC_PARAM_TYPE_F32;
    const auto txt = [f32](mc_param_value_t v) {
      char buf[32];
      if (f32) {
        std::snprintf(buf, sizeof buf, "%.6g", static_cast<double>(v.f));
      } else {
        std::snprintf(buf, sizeof buf, "%u", static_cast<unsigned>(v.u));
      }
      return std::string(buf);
    };
    throw UsageError(file + ": the stored configuration is another board's: " + k + " " + txt(va) +
                     " stored, " + txt(vb) + " on this board (--board); nothing run, " +
                     "the file unchanged");
  }
}

// The parameters the scenario or the user chose over the files' plain
// table (its law, fw_enable, a table key given with --set, even at its
// default): written over a stored set.
std::vector<uint32_t> chosen_over_files(const MotorFiles& f, const mc_params_t& p,
                                        const Params& P) {
  const mc_params_t plain = params_from_files(f, Params(app_gain_params(f), {}), p.speed_law);
  std::vector<uint32_t> ids;
  for (const mc_param_info_t& info : mc_param_table) {
    if (info.offset == MC_PARAM_NO_FIELD) continue;
    const bool set = P.was_set(mc_param_names[&info - mc_param_table]);
    if (set || mc_param_get_raw(&p, &info) != mc_param_get_raw(&plain, &info)) {
      ids.push_back(info.id);
    }
  }
  ids.push_back(MC_PARAM_ID_SPEED_LAW);  // SPEED's law is the scenario's
  return ids;
}

AppSetup file_setup(const MotorFiles& plant, const mc_params_t& p,
                    const std::function<double(double)>* load_nm) {
  AppSetup s;
  s.board = build_board_cfg(plant);
  set_board_sensor(plant, s.board);
  set_board_hall(plant, s);
  attach_load(s.board, load_nm);
  s.defaults = p;
  return s;
}

// A power-up elsewhere (theta_m0) with an incremental encoder and the
// offset taken as stored (angle_ref 0): the encoder counts from 0 where the
// rotor stands, so the stored offset is off by pole_pairs theta_m0 and the
// drive runs with that angle error, which nothing on the drive can see (on
// the bench: an absolute encoder's stored offset, or an index or an
// alignment at power-up). Said once, in the summary and on stderr.
void warn_stored_offset(const RunContext& ctx, const MotorFiles& plant, const mc_params_t& p,
                        double theta_m0) {
  const bool incremental =
      plant.board.encoder == kEncoderAbi || plant.board.encoder == kEncoderAbiIndex;
  const double e = std::remainder(theta_m0 * plant.motor.pole_pairs, 2.0 * M_PI);
  if (!incremental || p.angle_ref != 0u || std::abs(e) < 1e-9 ||
      ctx.summary.texts().count("warning") != 0) {
    return;
  }
  char msg[400];
  std::snprintf(msg, sizeof msg,
                "theta_m0_rad %g with an incremental encoder ('%s') and angle_ref 0 (the offset "
                "stored): the encoder counts from 0 where the rotor powers up, so the stored "
                "encoder_offset_rad is %.3f rad (electrical) off and the drive runs misaligned; "
                "a drive that finds its angle: angle_ref=1 with board.encoder=abi_index, or "
                "angle_ref=2",
                theta_m0, plant.board.encoder.c_str(), e);
  ctx.summary.set_text("warning", msg);
  std::fprintf(stderr, "mcsim: warning: %s\n", msg);
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
  const auto& keys = ctx.params.values();
  if (const auto it = keys.find("theta_m0_rad"); it != keys.end()) {
    s.board.theta_m0_rad = it->second;
    warn_stored_offset(ctx, plant, p, it->second);
  }
  if (ctx.flash != nullptr) {
    ctx.summary.set_text("flash_file", ctx.flash->path());
    s.flash = ctx.flash->hal();
    s.flash_must_boot = true;
    s.over_stored = chosen_over_files(plant, p, ctx.params);
  }
  if (adjust) adjust(s);
  if (ctx.pil == nullptr) {
    std::unique_ptr<AppTarget> t = make_app_target_sil(s);
    if (ctx.flash != nullptr && s.flash != nullptr && s.flash_must_boot) {
      check_flash_boot(*t, ctx.flash->path(), p);
      ctx.summary.set_text("cfg_boot_status", flash_boot_name(t->probe().boot_status));
    }
    return t;
  }
  std::unique_ptr<AppTarget> t = make_app_target_pil(s, *ctx.pil);
  std::fprintf(stderr, "mcsim: target %s\n", t->name().c_str());
  if (ctx.flash != nullptr && s.flash != nullptr && s.flash_must_boot) {
    // the image's boot of the file's content (FLASH frames), checked as the SIL's
    check_flash_boot(*t, ctx.flash->path(), p);
    ctx.summary.set_text("cfg_boot_status", flash_boot_name(t->probe().boot_status));
  }
  return t;
}

void check_flash_boot(const AppTarget& t, const std::string& file, const mc_params_t& board) {
  const uint32_t b = std::min<uint32_t>(t.probe().boot_status, 6u);
  if (b != MC_CFG_BOOT_STORED && b != MC_CFG_BOOT_MIGRATED && b != MC_CFG_BOOT_EMPTY) {
    throw UsageError(file + ": refused, boot status " + kBootNames[b] + " (" + kBootWhy[b] +
                     "); nothing run, the file unchanged");
  }
  if (b != MC_CFG_BOOT_EMPTY) refuse_foreign(file, t.params(), board);
}

std::string align_err_names(uint32_t bits) {
  static const char* const names[] = {"NULL",      "CFG",         "FOC",       "MEAS",
                                      "TRAVEL",    "NOT_SETTLED", "DIRECTION", "LOAD",
                                      "NO_MOTION", "NOT_FOUND",   "ENCODER",   "SLIP"};
  std::string s;
  for (uint32_t i = 0; i < 12u; ++i) {
    if ((bits & (1u << i)) != 0u) s += (s.empty() ? "" : "|") + std::string(names[i]);
  }
  return s.empty() ? "none" : s;
}

std::string flash_boot_name(uint32_t boot_status) {
  return kBootNames[std::min<uint32_t>(boot_status, 6u)];
}

double AppRecorder::theta_e_true() {
  constexpr double kTwoPi = 6.28318530717958647692;
  return std::remainder(pole_pairs * run.board().rotor_frame_state()(3), kTwoPi);
}

void AppRecorder::header() {
  std::vector<std::string> c = {"t",         "i_d_a",         "i_q_a",           "i_d_ref_a",
                                "i_q_ref_a", "omega_m_rad_s", "omega_ref_rad_s", "theta_e_rad"};
  if (hat) c.insert(c.end(), {"theta_e_hat_rad", "omega_if_rad_s"});
  if (used) c.emplace_back("theta_e_used_rad");
  c.insert(c.end(), {"v_d_v", "v_q_v", "fault_1"});
  ctx.csv.columns(c);
}

void AppRecorder::row(double t, double id, double iq, double w) {
  if (k++ % every != 0) return;
  const mc_app_probe_t& p = run.probe();
  const double th = theta_e_true();
  const Eigen::Vector2d& v = run.board().v_alpha_beta_applied();
  const double c = std::cos(th), s = std::sin(th);
  double r[14];
  size_t n = 0;
  for (double x : {t, id, iq, static_cast<double>(p.id_ref_a), static_cast<double>(p.iq_ref_a), w,
                   static_cast<double>(p.omega_ref_rad_s), th}) {
    r[n++] = x;
  }
  if (hat) {
    r[n++] = std::remainder(static_cast<double>(p.sls_theta_hat_e_rad), 6.283185307179586);
    // The I-f frame's speed while the law turns that frame (0 in ALIGN, the
    // ramp in IF); NaN once CLOSED (the frame is then the observer's; its
    // speed is not the I-f's, and the plot leaves a gap).
    r[n++] = p.sls_phase == MC_CTRL_SLS_CLOSED ? std::nan("")
                                               : static_cast<double>(p.sls_omega_if_rad_s);
  }
  if (used) r[n++] = std::remainder(static_cast<double>(p.theta_e_rad), 6.283185307179586);
  r[n++] = c * v(0) + s * v(1);
  r[n++] = -s * v(0) + c * v(1);
  r[n++] = static_cast<double>(p.faults);
  ctx.csv.row(r, n);
}

std::string AppWatch::operator()(const mc_app_probe_t& p) {
  if (p.faults != 0u) {
    std::string s = drive_fault_names(p.faults);
    if (p.hall_error != 0u) {
      s += " (the Hall sensors: MC_HALL_ERR " + hall_err_names(p.hall_error) + ")";
    } else if (p.angle_error != 0u) {
      s += " (the power-up angle find failed: MC_CTRL_ALIGN_ERR " + align_err_names(p.angle_error) +
           ")";
    } else if ((p.faults & MC_DRIVE_FAULT_CONTROL) != 0u) {
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
