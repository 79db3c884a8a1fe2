// commission: any motor, the drive application's commissioning
// (firmware/app/commission: mc_comm_can, bound as the images bind it) run
// through the AppTarget (issue 29 item 3): on the SIL or with --pil the
// board's whole image on QEMU, the same CSV and summary on both.
//
// The application boots the table of the files (app_params.hpp). The
// sequence reads none of its motor values (it starts from the board: PWM
// period, dead time, shunts; mc_comm_can_cfg_for_board), only the drive's
// limits: i_max_a bounds the test current, speed_max_rad_s and the
// over-speed trip the spin-up; what it identifies replaces the motor
// values. (A table with placeholder motor values instead refused to boot
// many of the campaign's random boards: its derived current limit and PWM
// ripple checks then judge the board against a motor it does not drive.)
// The plant has the sensor offsets, noise, encoder direction and start
// angle of the parameters.
// The scenario sends COMMISSION_CMD START (i_test_a; 0: the drive's
// default, a quarter of the sense range within i_max_a), keeps the host
// alive (HOST_HEARTBEAT: the application times a run out as an enabled
// drive), follows COMMISSION_STATUS and reads what the drive identified
// from its COMMISSION_RESULT frames (every item, IEEE 754 bits), as a
// user's tool does (mdtool calibrate). The run ends when every result has
// arrived, when the status says FAILED, or after t_max_s.
// With angle_ref index (board.encoder=abi_index's default) the drive
// searches the index first (the image's search at an enable at 0 A;
// index_search_s in the summary), so the offset it measures and --flash
// stores is relative to the index and holds after any power-up; the CSV's
// rows start after the search, duration_s from START.
//
// verify=1: the drive reboots on the identified values, as after the
// host's APPLY and SAVE (the booted table with the values commissioning
// stages: r, ld, lq, flux, pole pairs, encoder offset and direction, the
// sensor offsets, J and B with the speed gains derived from them), and runs
// a speed step to half the rated speed on the sensored speed law
// (speed_law 0) and on the sensorless law (speed_law 2, its I-f start from
// verify_sensorless_theta_e_rad), each on a fresh plant with the same
// imperfections. A law the table refuses for this motor (the sensorless law
// a salient machine) is reported, not run; without an encoder
// (board.encoder_cpr 0) the sensored law is not run.
//
// encoder_cpr 0: commissioning without an encoder (README "Without an
// encoder"): R, Ld, Lq and the flux from an I-f spin on the table's pole
// pairs; no encoder offset or direction, no J or B ("identified" leaves
// them out, the verdict does not judge them).
//
// CSV: the commissioning run, the generic scenarios' columns
// (app_scenario.hpp), one row every max(1, t_max_s / T / 20000) periods.
// Summary: "true", "identified", "error" as before the move, duration_s
// (when the last result arrived), verify.* (the final speed error of each
// step as a fraction of its target).
//
// The run itself (START, the keep-alive, the frames, the staging, the speed
// steps) is generic_commission.cpp's, which the SIL tests of
// tests/sil/commission run too; this file adds the parameters, the CSV and
// the summary.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>

#include "app_params.hpp"
#include "app_scenario.hpp"
#include "generic_commission.hpp"
#include "hal_host/file_flash.hpp"
#include "scenario.hpp"
#include "verdict.hpp"
extern "C" {
#include "config/mc_cfg_store.h"
#include "mc_drive.h"
#include "config/mc_law_cfg.h"
}

namespace mcsim {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::vector<ParamSpec> commission_params(const MotorFiles& f) {
  const CommissionSetup d = default_commission_setup(f);
  return {
      {"encoder_offset_rad", d.encoder_offset_rad, "rad",
       "plant: electrical angle of the d axis at encoder count 0", -100.0, 100.0},
      {"theta_m0_rad", d.encoder_offset_rad / f.motor.pole_pairs, "rad",
       "plant: the rotor's mechanical angle at power-up (the same as encoder_offset_rad / "
       "pole_pairs: set one)",
       -100.0, 100.0},
      {"encoder_direction", 1.0, "1", "plant: encoder counting direction (+1 or -1)", -1.0, 1.0},
      {"adc_offset_a", d.adc_offset_a, "A",
       "plant: current-sensor offsets (x, -0.7 x, 0.4 x) on phases a, b, c", -1e4, 1e4},
      {"noise_rms_a", d.noise_rms_a, "A", "plant: current-sensor noise per channel", 0.0, 1e4},
      {"i_test_a", 0.0, "A",
       "commissioning test current (COMMISSION_CMD; 0: the drive's default, a quarter of the "
       "current-sense range within i_max_a)",
       0.0, 65.535},
      {"t_max_s", d.t_max_s, "s", "give up after this much simulated time", 1e-3, 100.0},
      {"verify", 0.0, "1",
       "1: then run sensored and sensorless speed steps on the identified values (the drive "
       "rebooted on them)",
       0.0, 1.0},
      {"verify_sensorless_theta_e_rad", 0.0, "rad",
       "verify=1: the rotor's electrical angle when the sensorless run starts", -100.0, 100.0},
      {"seed", 1.0, "1", "plant: current-noise generator seed", 0.0, 4294967295.0},
  };
}

// The plant's side of the setup, and its sensor offsets once built.
CommissionSetup plant_setup(const RunContext& ctx) {
  CommissionSetup s = default_commission_setup(*ctx.files);
  s.encoder_offset_rad = ctx.params.get("encoder_offset_rad");
  // theta_m0_rad is the same power-up angle, mechanical (configure_plant)
  const double pp = ctx.files->motor.pole_pairs;
  const double off_dflt = default_commission_setup(*ctx.files).encoder_offset_rad;
  const double th = ctx.params.get("theta_m0_rad");
  if (th != off_dflt / pp) {
    if (s.encoder_offset_rad != off_dflt) {
      throw UsageError(
          "theta_m0_rad and encoder_offset_rad both set the rotor's angle at "
          "power-up: set one");
    }
    s.encoder_offset_rad = th * pp;
  }
  s.encoder_direction = ctx.params.get("encoder_direction") < 0 ? -1 : 1;
  s.adc_offset_a = ctx.params.get("adc_offset_a");
  s.noise_rms_a = ctx.params.get("noise_rms_a");
  s.i_test_a = ctx.params.get("i_test_a");
  s.t_max_s = ctx.params.get("t_max_s");
  s.seed = static_cast<std::uint64_t>(ctx.params.get("seed"));
  s.sensorless_start_theta_e_rad = ctx.params.get("verify_sensorless_theta_e_rad");
  return s;
}

// The run's target: the files' plant, the SIL or with --pil the image.
// boot_flash false: the verification boots the staged table, not --flash.
CommissionTargetFactory target_factory(RunContext& ctx, bool boot_flash = true) {
  return [&ctx, boot_flash](const mc_params_t& p, const std::function<void(AppSetup&)>& adjust) {
    return make_file_target(ctx, *ctx.files, p, nullptr, [&](AppSetup& su) {
      if (!boot_flash) {
        su.flash = nullptr;
        su.flash_must_boot = false;
      }
      if (adjust) adjust(su);
    });
  };
}

// --flash: the staged table (what commissioning staged in the parameter
// service, checked as a whole as APPLY does) saved in the configuration
// store on the file, by the image's store code (mc_cfg_store_save, what
// SAVE runs).
void save_to_flash(RunContext& ctx, const mc_params_t& staged) {
  const uint32_t err = mc_params_validate(&staged);
  if (err != MC_PARAMS_OK) {
    throw std::runtime_error("--flash: the staged table is invalid (MC_PARAMS_ERR " +
                             params_err_names(err) + "): nothing saved");
  }
  mc_cfg_store_t st{};
  mc_cfg_store_cfg_t sc{};
  sc.flash = ctx.flash->hal();
  sc.sector[0] = 0u;
  sc.sector[1] = 1u;
  mc_params_t old{};
  if (mc_cfg_store_init(&st, &sc) != 0) throw std::runtime_error("--flash: no store on the file");
  (void)mc_cfg_store_load(&st, &old);
  if (mc_cfg_store_save(&st, &staged) != 0) {
    throw std::runtime_error("--flash: the store's save failed");
  }
  ctx.summary.set("cfg_saved_seq", st.seq);
  ctx.summary.set("cfg_saves", 1.0);
}

// The commissioning run on the application (generic_commission.hpp), its
// CSV rows and progress.
CommissionRun run_app_commission(RunContext& ctx, const CommissionSetup& s, const mc_params_t& p) {
  const MotorFiles& f = *ctx.files;
  std::unique_ptr<AppRecorder> rec;
  const CommissionObserver observe = [&](AppRunner& run, long k) {
    hal_host::PmsmBoard& board = run.board();
    if (!rec) {
      const long n = step_count(s.t_max_s, board.period_s());
      rec = std::make_unique<AppRecorder>(
          AppRecorder{ctx, run, f.motor.pole_pairs, false, std::max(1L, n / 20000)});
      rec->header();
    }
    const double t = board.t_s();
    double id = 0, iq = 0;
    board.true_dq_a(&id, &iq);
    rec->row(t, id, iq, board.state()(2));
    if ((k & 1023) == 0) ctx.progress.update(t, s.t_max_s);
  };
  const CommissionRun r = run_commission(f, s, p, target_factory(ctx), observe);
  ctx.summary.set("commission_faults", r.drive_faults);
  ctx.summary.set("app_tx_frames", static_cast<double>(r.tx_frames));
  return r;
}

// verify=1: both laws on the staged table (see the file comment).
void run_verify(RunContext& ctx, const CommissionSetup& s, const mc_params_t& p,
                CommissionFigures& fig) {
  double w = 0;
  const auto verify = [&](uint32_t law, const char* name) {
    const std::string key = std::string("verify.") + name;
    try {
      const double e = verify_speed_step(*ctx.files, s, p, law, &w, target_factory(ctx, false));
      ctx.summary.set(key + "_speed_err_frac", e);
      ctx.summary.set(key + "_faulted", std::isnan(e) ? 1.0 : 0.0);
    } catch (const UsageError& e) {
      // the table refuses this law for the identified motor
      ctx.summary.set(key + "_speed_err_frac", std::nan(""));
      ctx.summary.set_text(key + "_refused", e.what());
      if (law == MC_LAW_SPEED_SENSORLESS) {
        fig.sensorless_refused = true;
      } else {
        fig.sensored_refused = true;
      }
    }
  };
  if (ctx.files->board.encoder_cpr != 0) {
    verify(MC_LAW_SPEED_PI, "sensored");
  } else {  // no encoder: the sensored law has no angle (judge_commission notes it)
    ctx.summary.set("verify.sensored_speed_err_frac", std::nan(""));
    ctx.summary.set_text("verify.sensored_refused", "no encoder");
    fig.sensored_refused = true;
  }
  verify(MC_LAW_SPEED_SENSORLESS, "sensorless");
  ctx.summary.set("verify.speed_target_rad_s", w);
  const auto& n = ctx.summary.numbers();
  fig.verify = true;
  fig.verify_sensored_err_frac = n.at("verify.sensored_speed_err_frac");
  fig.verify_sensorless_err_frac = n.at("verify.sensorless_speed_err_frac");
}

void record_truth(RunContext& ctx, const CommissionSetup& s, double true_off, const double adc[3]) {
  const MotorSpec& m = ctx.files->motor;
  ctx.summary.set_object("true", {{"r_ohm", m.r_ohm},
                                  {"ld_h", m.ld_h},
                                  {"lq_h", m.lq_h},
                                  {"flux_wb", m.flux_wb},
                                  {"pole_pairs", m.pole_pairs},
                                  {"encoder_offset_rad", true_off},
                                  {"encoder_direction", s.encoder_direction},
                                  {"adc_offset_a_a", adc[0]},
                                  {"adc_offset_b_a", adc[1]},
                                  {"adc_offset_c_a", adc[2]},
                                  {"j_kgm2", m.j_kgm2},
                                  {"b_nm_s_rad", m.b_nm_s_rad}});
}

void run_commission_scenario(RunContext& ctx) {
  const MotorFiles& f = *ctx.files;
  // encoder_cpr 0: without an encoder (R, L, flux; the pole pairs the table's)
  const bool sls = f.board.encoder_cpr == 0;
  const CommissionSetup s = plant_setup(ctx);
  mc_params_t p = commission_booted_params(f);
  p.angle_ref = static_cast<uint32_t>(ctx.params.get("angle_ref"));
  p.angle_find_at_enable = static_cast<uint32_t>(ctx.params.get("angle_find_at_enable"));
  const CommissionRun c = run_app_commission(ctx, s, p);
  if (c.done && ctx.flash != nullptr) save_to_flash(ctx, c.staged);
  const double true_off = c.true_encoder_offset_rad;
  const double* adc = c.true_adc_offset_a;
  ctx.summary.set("duration_s", c.duration_s);
  ctx.summary.set("index_search_s", c.index_search_s);
  ctx.summary.set("error_bits", c.err);
  ctx.summary.set_text("fault", c.err ? commission_error_names(c.err) +
                                            (c.detail ? " " + commission_detail_name(c.detail) : "")
                                      : "");
  ctx.summary.set_text("motor", f.motor.name);
  ctx.summary.set_text("board", f.board.name);
  record_truth(ctx, s, true_off, adc);
  CommissionFigures fig;
  fig.duration_s = c.duration_s;
  if (f.board.encoder == kEncoderHall) fig.duration_max_s += MC_COMM_HALL_STEP_S;
  fig.error_names = commission_error_names(c.err);
  if (!c.done) return write_verdict(ctx.summary, judge_commission(fig));
  const mc_comm_result_t& v = c.res;
  const double r = v.r_ohm, ld = v.ld_h, lq = v.lq_h, flux = v.flux_wb;
  const double pp = v.pole_pairs;
  const double off = v.encoder_offset_rad;
  const double dir = v.encoder_direction;
  const double adc_id[3] = {v.adc_offset_a[0], v.adc_offset_a[1], v.adc_offset_a[2]};
  std::map<std::string, double> id = {{"r_ohm", r},
                                      {"ld_h", ld},
                                      {"lq_h", lq},
                                      {"flux_wb", flux},
                                      {"pole_pairs", pp},
                                      {"encoder_offset_rad", off},
                                      {"encoder_direction", dir},
                                      {"adc_offset_a_a", adc_id[0]},
                                      {"adc_offset_b_a", adc_id[1]},
                                      {"adc_offset_c_a", adc_id[2]},
                                      {"saliency", lq / ld}};
  if (sls) {  // no encoder: no offset or direction measured
    id.erase("encoder_offset_rad");
    id.erase("encoder_direction");
  }
  if ((v.valid & MC_COMM_HAVE_MECH) != 0u) {
    id["j_kgm2"] = v.j_kgm2;
    id["b_nm_s_rad"] = v.b_nm_s_rad;
  }
  ctx.summary.set_object("identified", id);
  const double e_off = sls ? 0.0 : std::remainder(off - true_off, 2 * kPi);
  double e_adc = 0;  // the largest current-sensor offset error
  for (int k = 0; k < 3; ++k) e_adc = std::max(e_adc, std::abs(adc_id[k] - adc[k]));
  const bool dir_right = sls || (dir < 0) == (s.encoder_direction < 0);
  ctx.summary.set_object("error", {{"r_frac", r / f.motor.r_ohm - 1},
                                   {"ld_frac", ld / f.motor.ld_h - 1},
                                   {"lq_frac", lq / f.motor.lq_h - 1},
                                   {"flux_frac", flux / f.motor.flux_wb - 1},
                                   {"encoder_offset_deg", e_off * 180 / kPi},
                                   {"pole_pairs_diff", pp - f.motor.pole_pairs},
                                   {"direction_wrong", dir_right ? 0.0 : 1.0},
                                   {"adc_offset_max_a", e_adc},
                                   {"adc_offset_max_frac", e_adc / f.board.i_sense_max_a}});
  if (ctx.params.get("verify") > 0.5) run_verify(ctx, s, c.staged, fig);
  fig.done = true;
  fig.r_frac = r / f.motor.r_ohm - 1;
  fig.ld_frac = ld / f.motor.ld_h - 1;
  fig.lq_frac = lq / f.motor.lq_h - 1;
  fig.flux_frac = flux / f.motor.flux_wb - 1;
  fig.pole_pairs_diff = pp - f.motor.pole_pairs;
  fig.sensorless = sls;
  fig.encoder_offset_deg = sls ? 0.0 : e_off * 180 / kPi;
  fig.adc_offset_max_frac = e_adc / f.board.i_sense_max_a;
  fig.direction_right = dir_right;
  write_verdict(ctx.summary, judge_commission(fig));
}

const Registrar reg_commission(on_app_target(
    {"commission",
     "any motor: the drive application's commissioning over CAN (COMMISSION_CMD), from the "
     "board alone: current-sensor offsets, R, Ld, Lq, pole pairs, encoder direction and offset, "
     "flux (and J, B) read back from its COMMISSION_RESULT frames; JSON with 'identified' and "
     "'true'; verify=1 then reboots the drive on the identified values and runs speed steps",
     0.0,
     {},
     run_commission_scenario,
     commission_params,
     /*takes_flash=*/true,
     /*motor_optional=*/false,
     /*takes_duration=*/false}));

}  // namespace
}  // namespace mcsim
