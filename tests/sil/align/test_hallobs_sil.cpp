// Hall + observer in the SIL (issue 32 item 6): the drive's hand-over from
// the Hall angle to the flux observer's above a speed
// (firmware/app/drive/mc_drive_hallobs.h), through the path of `mcsim run`
// (the image's application, its parameter table, the plant's three Hall
// sensors with placement errors read through the board's Hall inputs).
//
// The hub motor of the library (15 pole pairs) on the ODrive v3.6 56 V
// description, the sensors where the table's default puts them
// (board.hall_offset_e_rad 0: no commissioning needed) with each edge off by
// kEdgeErr (alternately early and late: mounting, magnet asymmetry) and a
// 0.05 rad el. band. The sensored speed step to kTarget (mechanical; 15 x
// that electrical, well above the hand-over's end): the angle the drive
// used (the column theta_e_used_rad, from the same period's probe) against
// the plant's true electrical angle (theta_e_rad) in the same row.
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "app_params.hpp"
#include "app_scenario.hpp"
#include "motor_file.hpp"
#include "powerup_run.hpp"
#include "run.hpp"
#include "scenario.hpp"
extern "C" {
#include "config/mc_params.h"
#include "mc_drive_hallobs.h"
}

namespace mcsim {
namespace {

const std::string kMotor = std::string(MCSIM_MOTORS_DIR) + "/hub-6p5in-15pp.toml";
const std::string kBoard = std::string(MCSIM_MOTORS_DIR) + "/odrive-v36-56v.toml";
constexpr double kPolePairs = 15.0;
constexpr double kTarget = 40.0;  // rad/s mech.: 600 rad/s el.
// the hand-over from 150 to 300 rad/s el. (10 to 20 rad/s mech.)
constexpr double kStart = 150.0;
constexpr double kEnd = 300.0;

using powerup::kPi;
using powerup::RunResult;
using powerup::Sets;

double wrap_pi(double x) {
  return std::remainder(x, 2.0 * kPi);
}

Sets hall_sets(bool handover, const Sets& extra = {}) {
  Sets s = {{"board.encoder", "hall"},
            {"board.hall_edge_error_e_rad", "0.06"},
            {"board.hall_hysteresis_e_rad", "0.05"},
            {"speed_rad_s", std::to_string(kTarget)}};
  if (handover) {
    s.emplace_back("hall_obs_start_e_rad_s", std::to_string(kStart));
    s.emplace_back("hall_obs_end_e_rad_s", std::to_string(kEnd));
  }
  s.insert(s.end(), extra.begin(), extra.end());
  return s;
}

RunResult run(const Sets& sets) {
  return powerup::run("speed-step", kMotor, kBoard, sets, "");
}

// A run up and back down, commanded as a host would (SET_SPEED_REF over
// CAN): kTarget, then kBack (below the hand-over's start), sampled every
// period. Returns the rows' figures for the high-speed hold and the
// hand-over band both ways.
struct UpDown {
  double err_max_fast = 0.0, err_rms_fast = 0.0;    // hold at kTarget, settled [rad el.]
  double jump_band_up = 0.0, jump_band_down = 0.0;  // max |change of (used - true)| [rad el.]
  double w_fast = 0.0, w_back = 0.0;                // speeds reached [rad/s mech.]
  uint32_t faults = 0, hall_error = 0;
};
constexpr double kBack = 4.0;  // rad/s mech.: 60 rad/s el., below kStart

UpDown up_down(bool handover, double flux_scale = 1.0) {
  const MotorFiles f = load_motor_files(kMotor, kBoard,
                                        {{"board.encoder", "hall"},
                                         {"board.hall_edge_error_e_rad", "0.06"},
                                         {"board.hall_hysteresis_e_rad", "0.05"}});
  std::vector<ParamSpec> keys = app_gain_params(f);
  mc_params_t p =
      params_from_files(f, Params(keys, {{"model_flux_scale", std::to_string(flux_scale)}}));
  if (handover) {
    p.hall_obs_start_e_rad_s = static_cast<float>(kStart);
    p.hall_obs_end_e_rad_s = static_cast<float>(kEnd);
  }
  EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_OK);
  const mc_params_eff_t e = resolve_params(p);
  const std::unique_ptr<AppTarget> target = make_file_target(f, p, nullptr);
  AppRunner run(*target);
  hal_host::PmsmBoard& b = run.board();
  const double T = b.period_s();
  // each leg: the ramp (speed_ramp_rad_s2) plus 40 / wc to settle
  const double t_leg = kTarget / e.p.speed_ramp_rad_s2 + 40.0 / e.g.speed_wc_rad_s;
  UpDown u;
  double prev = std::nan("");
  double sum2 = 0.0;
  long n2 = 0;
  run.start(MC_CAN_CTRL_SPEED);
  for (int leg = 0; leg < 2; ++leg) {
    run.send(run.cmd().speed_ref(leg == 0 ? kTarget : kBack));
    const long n = std::lround(t_leg / T);
    for (long k = 0; k < n; ++k) {
      run.step();
      const mc_app_probe_t& pr = run.probe();
      const double th = kPolePairs * b.rotor_frame_state()(3);
      const double err = wrap_pi(static_cast<double>(pr.theta_e_rad) - th);
      const double w_e = std::abs(b.state()(2)) * kPolePairs;
      if (!std::isnan(prev) && w_e >= kStart && w_e <= kEnd) {
        double& j = leg == 0 ? u.jump_band_up : u.jump_band_down;
        j = std::max(j, std::abs(wrap_pi(err - prev)));
      }
      prev = err;
      // the hold: the last quarter of the first leg
      if (leg == 0 && k >= 3 * n / 4) {
        u.err_max_fast = std::max(u.err_max_fast, std::abs(err));
        sum2 += err * err;
        ++n2;
      }
    }
    (leg == 0 ? u.w_fast : u.w_back) = b.state()(2);
  }
  u.err_rms_fast = std::sqrt(sum2 / static_cast<double>(std::max(1L, n2)));
  u.faults = run.probe().faults;
  u.hall_error = run.probe().hall_error;
  return u;
}

// Up through the hand-over to kTarget and back down below it. Measured
// (this plant, these files): at the 40 rad/s hold the Hall angle alone errs
// by up to 0.22 rad el. (its placement errors, 0.06 each way, the band and
// the interpolation over uneven sectors), the blend by up to 0.03 (the
// observer's: the voltage's one-period delay and its model), a factor 7.6:
// N = 5 leaves a third of it for a change of step or plant. In the
// hand-over's band ([kStart, kEnd] on the plant's speed) the error moves
// from one period to the next by no more than the Hall angle's own in the
// same band of the run without the hand-over (+0.01 rad el.: the
// observer's noise): the blend adds no jump; the Hall's own is up to 30
// degrees going up (its interpolation restarts at an edge while the speed
// ramps) and a few hundredths going down. No fault, no fallback.
TEST(HallObsSil, HandOverCutsTheAngleErrorAtSpeedAndIsContinuousBothWays) {
  const UpDown h = up_down(false), o = up_down(true);
  EXPECT_EQ(h.faults, 0u);
  EXPECT_EQ(o.faults, 0u);
  EXPECT_EQ(o.hall_error, 0u);
  // both reached their speeds (the hold and the return): within 2 %
  for (const UpDown* u : {&h, &o}) {
    EXPECT_NEAR(u->w_fast, kTarget, 0.02 * kTarget);
    EXPECT_NEAR(u->w_back, kBack, 0.02 * kBack + 0.05);  // + a 0.05 rad/s floor near rest
  }
  EXPECT_GE(h.err_max_fast, 5.0 * o.err_max_fast)
      << "Hall " << h.err_max_fast << " hand-over " << o.err_max_fast;
  EXPECT_GE(h.err_rms_fast, 4.0 * o.err_rms_fast)  // measured 4.9
      << "Hall " << h.err_rms_fast << " hand-over " << o.err_rms_fast;
  EXPECT_LE(o.jump_band_up, h.jump_band_up + 0.01);
  EXPECT_LE(o.jump_band_down, h.jump_band_down + 0.01);
  EXPECT_LT(o.jump_band_up, kPi / 6.0);  // 30 degrees el.
  EXPECT_LT(o.jump_band_down, 0.05);
}

// The sensored speed step (the scenario's verdict: within 2 % of the
// target in the steady window, |i_d| below 10 % of rated) to kTarget: the
// Hall angle alone misses the d-current bound (0.14 of rated: the
// placement errors turn the current vector at each edge); with the
// hand-over it passes.
TEST(HallObsSil, SpeedStepPassesItsVerdictWithTheHandOver) {
  const RunResult h = run(hall_sets(false));
  const RunResult o = run(hall_sets(true));
  EXPECT_EQ(o.out.kind, RunOutcome::Kind::kPass) << o.out.message;
  EXPECT_EQ(o.num.at("faults"), 0.0);
  EXPECT_EQ(o.num.at("hall_error"), 0.0);
  EXPECT_EQ(h.out.kind, RunOutcome::Kind::kFailed) << h.out.message;
  EXPECT_NE(h.out.message.find("d current not held"), std::string::npos) << h.out.message;
  EXPECT_EQ(h.num.at("faults"), 0.0);
}

// A faulty set-up: the drive's flux linkage a quarter of the motor's (the
// observer then disagrees with the Hall angle once it carries weight; a
// smaller model error, 0.35 to 2 times, stays inside the 45-degree bound
// here: the blend then errs by up to 0.29 rad el., the bound is for a
// gross error, not a tuning check), or the Hall
// table 60 degrees el. off the sensors (the Hall angle wrong, the observer
// right): hall_error names OBS_DISAGREE, the drive does not fault and
// runs on the Hall angle alone (documented fallback, mc_drive_hallobs.h).
// With the wrong flux the angle at the hold is then the Hall angle's: its
// largest error equals the run without the hand-over's to 0.01 rad el.
// (the edge timing of slightly different speed histories).
TEST(HallObsSil, DisagreementIsNamedAndFallsBackToTheHallAngle) {
  const UpDown h = up_down(false);
  const UpDown bad = up_down(true, 0.25);
  EXPECT_EQ(bad.faults, 0u);
  EXPECT_EQ(bad.hall_error, MC_DRIVE_HALL_ERR_OBS_DISAGREE);
  EXPECT_NEAR(bad.err_max_fast, h.err_max_fast, 0.01);
  EXPECT_NEAR(bad.w_fast, kTarget, 0.02 * kTarget);
  const RunResult off = run(hall_sets(true, {{"board.hall_offset_e_rad", "1.0472"}}));
  EXPECT_EQ(off.num.at("faults"), 0.0) << off.out.message;
  EXPECT_EQ(off.num.at("hall_error"), static_cast<double>(MC_DRIVE_HALL_ERR_OBS_DISAGREE));
  EXPECT_EQ(off.txt.at("hall_error_names"), "OBS_DISAGREE");
}

// Bad hand-over sets are refused before anything runs, by name.
TEST(HallObsSil, BadParameterSetsAreRefusedByName) {
  struct Case {
    Sets sets;
    const char* name;
  };
  const Case cases[] = {
      {hall_sets(true, {{"hall_obs_start_e_rad_s", "400"}}), "BLEND"},  // start above end
      {hall_sets(true, {{"hall_obs_disagree_e_rad", "0"}}), "BLEND"},
      {{{"board.encoder", "abi"},
        {"hall_obs_start_e_rad_s", "150"},
        {"hall_obs_end_e_rad_s", "300"}},
       "NOT_HALL"},
  };
  for (const Case& c : cases) {
    const RunResult r = run(c.sets);
    EXPECT_EQ(r.out.kind, RunOutcome::Kind::kRefused) << c.name;
    EXPECT_NE(r.out.message.find("MC_PARAMS_ERR HALL_OBS"), std::string::npos) << r.out.message;
    EXPECT_NE(r.out.message.find(c.name), std::string::npos) << r.out.message;
  }
}

}  // namespace
}  // namespace mcsim
