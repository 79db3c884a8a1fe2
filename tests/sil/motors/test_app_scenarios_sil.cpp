// The generic scenarios run the drive application (issue 29 item 3): what
// the application's parameter table says changes what the scenario measures,
// and the application's own output (its CAN telemetry) is there. A scenario
// that ran another loop (as the deleted C++ speed PI did) would keep its own
// ramp and send no frame.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "app_cmd.hpp"
#include "app_params.hpp"
#include "app_target.hpp"
#include "plant_from_files.hpp"
#include "motor_library.hpp"

namespace mcsim {
namespace {

const testlib::Case kD5065{"odrive-d5065", "odrive-v36-24v"};
constexpr double kTwoPi = 6.283185307179586476925;

std::map<std::string, double> speed_step(const testlib::Sets& sets, const std::string& tag) {
  return testlib::run_scenario("speed-step", testlib::files(kD5065), sets, tag);
}

// speed_ramp_rad_s2 (--set speed_ramp_rad_s2, the parameter) a quarter of its derived
// value: the application slews the reference at it, so the rotor passes
// half the target after about half the ramp's time. Tolerance 10 % of that
// plus 3 ms: the command waits for the application's slow step (1 ms) and
// the speed loop follows the ramp with a lag of about 1 / speed_bw (0.5 ms
// at 192 rad/s here, the feed-forward taking most of it).
TEST(AppScenarios, SpeedRampParameterSetsTheRotorsAcceleration) {
  const auto d = speed_step({{"speed_rad_s", "200"}}, "_derived");
  const double ramp = d.at("param.speed_ramp_rad_s2");
  ASSERT_GT(ramp, 0.0);
  const double slow = 0.25 * ramp;
  const auto r =
      speed_step({{"speed_rad_s", "200"}, {"speed_ramp_rad_s2", std::to_string(slow)}}, "_slow");
  EXPECT_NEAR(r.at("param.speed_ramp_rad_s2"), slow, 1e-3 * slow);
  for (const auto* x : {&d, &r}) {
    const double a = x->at("param.speed_ramp_rad_s2");
    const double expect = 0.5 * 200.0 / a;
    EXPECT_NEAR(x->at("half_speed_time_s"), expect, 0.1 * expect + 3e-3) << "ramp " << a;
  }
  EXPECT_EQ(r.at("settled"), 1.0);
}

// i_max_a lowered (the motor's, --set motor.i_max_a): the application's limit holds the
// speed law's current (|i_q| at most the limit plus 5 % for the current
// loop's overshoot and the PWM ripple), and the derived ramp follows it
// (0.5 kt i_limit / J: a third of the current, a third of the ramp).
TEST(AppScenarios, CurrentLimitParameterHoldsTheSpeedLawsCurrent) {
  const auto d = speed_step({{"speed_rad_s", "200"}}, "_derived");
  const double i_lim = d.at("gain.i_limit_a") / 3.0;
  MotorFiles f = testlib::files(kD5065);
  f.motor.i_max_a = i_lim;
  const auto r = testlib::run_scenario("speed-step", f, {{"speed_rad_s", "200"}}, "_limited");
  EXPECT_NEAR(r.at("gain.i_limit_a"), i_lim, 1e-3 * i_lim);
  EXPECT_NEAR(r.at("param.speed_ramp_rad_s2"), d.at("param.speed_ramp_rad_s2") / 3.0,
              1e-3 * d.at("param.speed_ramp_rad_s2"));
  EXPECT_LE(r.at("iq_abs_max_a"), 1.05 * i_lim);
  EXPECT_EQ(r.at("faults"), 0.0);
  EXPECT_EQ(r.at("settled"), 1.0);
}

// The application's telemetry: HEARTBEAT at its table rate (10 Hz) and the
// other default messages, so at least one frame per 100 ms of the run.
TEST(AppScenarios, TheApplicationSendsItsTelemetry) {
  const auto r = speed_step({{"speed_rad_s", "200"}}, "_tm");
  EXPECT_GE(r.at("app_tx_frames"), 1.0);
  EXPECT_GE(r.at("app_tx_frames"), r.at("duration_s") * 10.0 - 1.0);
}

// The gain keys of the generic scenarios are the parameter table's, by name,
// their defaults what the C derivation (mc_params_resolve) resolves for the
// files, bit for bit (the float the table holds); a key set to another value
// reaches the drive and the later gains follow it (the speed PI from a set
// speed_bw_rad_s: kp = J wc / kt, mc_gains_speed_pi); a value outside the
// table's range or an old C++ key is refused.
TEST(AppScenarios, GainKeysAreTheTablesParametersWithTheCDerivedDefaults) {
  const MotorFiles f = testlib::files(kD5065);
  const std::vector<ParamSpec> specs = app_gain_params(f);
  const mc_params_eff_t e = files_params_eff(f);
  int gains = 0;
  for (const ParamSpec& s : specs) {
    if (s.key.rfind("model_", 0) == 0) continue;
    const int32_t i = mc_param_find_name(s.key.c_str());
    ASSERT_GE(i, 0) << s.key << " is no parameter of the table";
    mc_param_value_t v;
    v.u = mc_param_get_raw(&e.p, &mc_param_table[i]);
    EXPECT_EQ(s.default_value, static_cast<double>(v.f)) << s.key;
    EXPECT_GT(s.default_value, 0.0) << s.key << ": derived";
    ++gains;
  }
  EXPECT_EQ(gains, 21);
  for (const char* old : {"cur_bw_rad_s", "speed_wc_rad_s", "i_limit_a", "speed_accel_rad_s2"}) {
    EXPECT_EQ(
        std::find_if(specs.begin(), specs.end(), [&](const ParamSpec& s) { return s.key == old; }),
        specs.end())
        << old;
  }
  const mc_params_t p = params_from_files(f, Params(specs, {{"speed_bw_rad_s", "100"}}));
  const mc_params_eff_t r = resolve_params(p);
  float kp = 0, ki = 0;
  ASSERT_EQ(mc_gains_speed_pi(r.m.j_kgm2, r.g.kt_nm_a, 100.0, &kp, &ki), MC_GAINS_OK);
  EXPECT_EQ(p.speed_bw_rad_s, 100.0f);
  EXPECT_EQ(p.speed_kp_a_s_rad, 0.0f) << "not set: stays derived";
  EXPECT_EQ(r.p.speed_kp_a_s_rad, kp);
  EXPECT_EQ(r.p.speed_ki_a_rad, ki);
  EXPECT_EQ(r.p.current_bw_rad_s, static_cast<float>(e.g.cur_bw_rad_s));
  EXPECT_THROW(Params(specs, {{"speed_bw_rad_s", "-1"}}), UsageError);
  EXPECT_THROW(Params(specs, {{"cur_bw_rad_s", "1000"}}), UsageError);
  // the table's cross check: a bandwidth above 0.3 pwm_hz (7.2 kHz here)
  try {
    params_from_files(f, Params(specs, {{"current_bw_rad_s", "15000"}}));
    FAIL() << "expected a refusal";
  } catch (const UsageError& x) {
    EXPECT_NE(std::string(x.what()).find("MC_PARAMS_ERR BANDWIDTH"), std::string::npos) << x.what();
  }
}

// The summary's gain records are the C derivation's: every field of the
// resolved mc_gains_t under its C name (gain.NAME) and each gain parameter's
// resolved value (param.NAME).
TEST(AppScenarios, SummaryGainRecordsAreTheCDerivations) {
  const MotorFiles f = testlib::files(kD5065);
  const mc_params_eff_t e = files_params_eff(f);
  const auto r = testlib::run_scenario("current-step", f, {{"csv_every", "1000"}});
  EXPECT_EQ(r.at("gain.cur_bw_rad_s"), e.g.cur_bw_rad_s);
  EXPECT_EQ(r.at("gain.i_limit_a"), e.g.i_limit_a);
  EXPECT_EQ(r.at("gain.speed_wc_rad_s"), e.g.speed_wc_rad_s);
  EXPECT_EQ(r.at("gain.speed_kp_a_s_rad"), e.g.speed_kp_a_s_rad);
  EXPECT_EQ(r.at("gain.pi2d_coupling"), e.g.pi2d_coupling);
  EXPECT_EQ(r.at("gain.speed_limit_rad_s"), e.g.speed_limit_rad_s);
  EXPECT_EQ(r.at("param.speed_bw_rad_s"), static_cast<double>(e.p.speed_bw_rad_s));
  EXPECT_EQ(r.at("param.traj_v_max_rad_s"), static_cast<double>(e.p.traj_v_max_rad_s));
}

// An encoder mounted the other way (the plant's encoder counts down as the
// rotor turns positive) with encoder_reversed = 1: POSITION moves the rotor
// one turn forward, as it does with the encoder the right way round. The
// position law counts turns on the drive's count, which has the direction
// applied (it counted the encoder's own count before: its feedback then had
// the wrong sign). Tolerance: 3 counts of the 8192 (the loop's settling and
// the load-free rotor's ripple at rest; SET_POSITION_REF's 1e-4 rad
// resolution is under one count).
TEST(AppScenarios, PositionWithAReversedEncoderMovesTheWayCommanded) {
  const MotorFiles f = testlib::files(kD5065);
  for (const int dir : {+1, -1}) {
    AppSetup s;
    s.board = build_board_cfg(f);
    s.board.encoder.direction = dir;
    s.defaults = params_from_files(f, Params(app_gain_params(f), {}));
    s.defaults.encoder_reversed = dir < 0 ? 1u : 0u;
    const std::unique_ptr<AppTarget> t = make_app_target_sil(s);
    AppRunner run(*t);
    run.start(MC_CAN_CTRL_POSITION);
    const double T = run.board().period_s();
    const double cpr = static_cast<double>(s.defaults.encoder_cpr);
    const double theta0 = run.board().state()(3);
    const auto steps = [&](double secs) {
      for (long k = std::lround(secs / T); k > 0; --k) run.step();
    };
    steps(0.01);
    run.send(run.cmd().position_ref(kTwoPi));
    steps(0.6);
    const double moved = run.board().state()(3) - theta0;
    EXPECT_NEAR(moved, kTwoPi, 3.0 * kTwoPi / cpr) << "encoder direction " << dir;
    EXPECT_EQ(run.probe().faults, 0u) << "encoder direction " << dir;
  }
}

}  // namespace
}  // namespace mcsim
