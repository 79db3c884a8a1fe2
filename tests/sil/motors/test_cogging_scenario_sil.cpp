// The cogging scenario (issue 35 item 4, sim/cli/scenarios/cogging.cpp) on
// the library's D5065 on the 24 V ODrive with the cogging figure proposed
// for it (sim/motors/README.md: 12 slots, 14 poles; 2 % of its rated torque
// 1.5 p flux i_rated = 0.92 N m as the fundamental's peak): the speed ripple of the speed PI against the loop's analytic
// rejection of a sinusoidal disturbance, the hold figure, the refusal of a
// motor without cogging, and the anticogging key following the table.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <map>
#include <string>

#include "motor_library.hpp"
#include "scenario.hpp"
#include "mcsim/cogging.hpp"
extern "C" {
#include "commission/mc_comm_cog.h"
#include "mc_app.h"
#include "mc_params.h"
}

namespace mcsim {
namespace {

using cd = std::complex<double>;

const testlib::Case kD5065{"odrive-d5065", "odrive-v36-24v"};

MotorFiles d5065_cogging() {
  MotorFiles f = testlib::files(kD5065);
  f.motor.slots = 12;
  f.motor.cogging_nm = 0.02 * 1.5 * f.motor.pole_pairs * f.motor.flux_wb * f.motor.i_rated_a;
  return f;
}

std::map<std::string, double> run_cog(const MotorFiles& f, double frac, const std::string& tag,
                                      std::map<std::string, std::string>* txt) {
  return testlib::run_scenario("cogging", f, {{"speed_frac", std::to_string(frac)}}, tag, txt);
}

// Peak-to-peak speed ripple of the speed loop rejecting the cogging torque
// A sin(N th): the rotor J s w = tau_cog - B w - kt C(s) L(s) H(s) w at
// s = j N w, with
//   C(s) = kp + ki / s   the speed PI [A s/rad, A/rad],
//   H(s) = (3 bw^2 s + bw^3) / (s + bw)^3   the drive's encoder tracking
//          loop's speed (mc_enctrack.h: triple pole at bw),
//   L(s) = e^{-1.5 s T} / (1 + s / cur_bw)   the current loop (first order
//          by design, mc_gains.h) behind one sample and the PWM's half
//          period of delay,
//   pp = 2 A / |J s + B + kt C L H|.
double ripple_estimate(const std::map<std::string, double>& s, const MotorFiles& f) {
  const double w = s.at("cogging_freq_rad_s");
  const cd jw(0.0, w);
  const double kt = s.at("gain.kt_nm_a"), bw = s.at("gain.enc_pll_bw_rad_s");
  const double t = 1.0 / s.at("board.pwm_hz");
  const cd c = kt * (s.at("param.speed_kp_a_s_rad") + s.at("param.speed_ki_a_rad") / jw);
  const cd h = (3.0 * bw * bw * jw + bw * bw * bw) / ((jw + bw) * (jw + bw) * (jw + bw));
  const cd l = std::exp(-1.5 * t * jw) / (1.0 + jw / s.at("gain.cur_bw_rad_s"));
  const cd d = f.motor.j_kgm2 * jw + f.motor.b_nm_s_rad + c * l * h;
  return 2.0 * f.motor.cogging_nm / std::abs(d);
}

TEST(CoggingScenarioSil, SpeedRippleIsTheLoopsRejectionOfTheCoggingTorque) {
  const MotorFiles f = d5065_cogging();
  // The floor: the same runs with a cogging torque a million times smaller:
  // the ripple the encoder's counts leave through the loop (quantised
  // angle -> tracking loop -> PI -> current) without cogging.
  MotorFiles quiet = f;
  quiet.motor.cogging_nm *= 1e-6;
  double ripple[2] = {0, 0};
  int i = 0;
  for (const double frac : {0.02, 0.10}) {
    std::map<std::string, std::string> txt, txt0;
    const std::string tag = std::to_string(i);
    const auto s = run_cog(f, frac, tag, &txt);
    const auto s0 = run_cog(quiet, frac, tag + "q", &txt0);
    ASSERT_EQ(txt.at("verdict"), "pass") << txt.at("verdict_detail");
    ASSERT_EQ(txt0.at("verdict"), "pass") << txt0.at("verdict_detail");
    EXPECT_EQ(s.at("faults"), 0.0);
    EXPECT_EQ(s.at("cogging_order"), 84.0);  // lcm(12, 14)
    EXPECT_NEAR(s.at("speed_target_rad_s"), frac * s.at("gain.speed_rated_eff_rad_s"), 1e-9);
    // The settled mean is the target (the PI's integral): within 1 %.
    EXPECT_NEAR(s.at("speed_mean_rad_s"), s.at("speed_target_rad_s"),
                0.01 * s.at("speed_target_rad_s"));
    const double est = ripple_estimate(s, f);
    const double floor = s0.at("speed_ripple_pp_rad_s");
    const double meas = s.at("speed_ripple_pp_rad_s");
    ripple[i++] = meas;
    // Tolerance: the floor (the quantisation ripple adds at most its own
    // peak-to-peak to the sum's) plus 5 % of the estimate: the delay taken
    // anywhere from 0 to 2 periods moves the estimate by 0.5 % at these
    // gains; the rotor's speed, and with it the disturbance's frequency,
    // swings by half the ripple over the mean (2 % at 2 % of rated speed),
    // moving |J s| by as much; the peak sampled at 24 kHz misses the crest
    // by 1 - cos(N w T / 2) < 0.4 %.
    RecordProperty("speed_ripple_pp_rad_s_" + tag, std::to_string(meas));
    RecordProperty("speed_ripple_estimate_rad_s_" + tag, std::to_string(est));
    RecordProperty("speed_ripple_floor_pp_rad_s_" + tag, std::to_string(floor));
    EXPECT_NEAR(meas, est, floor + 0.05 * est)
        << "speed_frac " << frac << ": floor " << floor << " rad/s";
    // The cogging is what the ripple measures: well above the floor.
    EXPECT_GT(meas, 1.5 * floor) << "speed_frac " << frac;
  }
  // Faster: a higher disturbance frequency the inertia filters more.
  EXPECT_LT(ripple[1], 0.5 * ripple[0]);
}

TEST(CoggingScenarioSil, HoldUnderAStepLoadIsMeasured) {
  const MotorFiles f = d5065_cogging();
  std::map<std::string, std::string> txt;
  const auto s = run_cog(f, 0.10, "", &txt);
  ASSERT_EQ(txt.at("verdict"), "pass") << txt.at("verdict_detail");
  // The step is hold_load_frac (5 %) of the rated torque.
  EXPECT_NEAR(s.at("hold_load_nm"), 0.05 * s.at("gain.torque_rated_nm"), 1e-12);
  // The load pushes the rotor off the held angle and the cascade's
  // integral brings it back: a non-zero excursion, and less than one
  // cogging period (2 pi / 84 = 0.075 rad): the hold does not slip a detent.
  EXPECT_GT(s.at("hold_err_max_rad"), 0.0);
  EXPECT_LT(s.at("hold_err_pp_rad"), 2.0 * M_PI / 84.0);
  EXPECT_LE(s.at("hold_err_max_rad"), s.at("hold_err_pp_rad") + 1e-12);
}

TEST(CoggingScenarioSil, MotorWithoutCoggingIsRefused) {
  const MotorFiles f = testlib::files(kD5065);  // the file as shipped: no cogging
  ASSERT_EQ(f.motor.cogging_nm, 0.0);
  try {
    (void)run_cog(f, 0.10, "", nullptr);
    FAIL() << "expected a refusal";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("cogging needs a motor with cogging_nm > 0"),
              std::string::npos)
        << e.what();
  }
}

// anticogging=1: the drive calibrates its own map first (mc_app.h,
// anticogging 2 written and applied over CAN in SPEED at rest; the turns of
// firmware/app/commission/mc_comm_cog.h), then the same two measurements.
// On the SK3 (library cogging, 2 % of rated torque, order 84) on the VESC 6.
TEST(CoggingScenarioSil, TheDriveCalibratesItsMapThroughTheApplication) {
  const MotorFiles f = testlib::files({"turnigy-sk3-6374-149kv", "vesc6-48v"});
  ASSERT_GT(f.motor.cogging_nm, 0.0);
  std::map<std::string, std::string> txt0, txt1;
  const auto s0 = testlib::run_scenario("cogging", f, {{"anticogging", "0"}}, "off", &txt0);
  const auto s1 = testlib::run_scenario("cogging", f, {{"anticogging", "1"}}, "on", &txt1);
  ASSERT_EQ(txt0.at("verdict"), "pass") << txt0.at("verdict_detail");
  ASSERT_EQ(txt1.at("verdict"), "pass") << txt1.at("verdict_detail");
  EXPECT_EQ(s1.at("cog_cal_status"), static_cast<double>(MC_COMM_COG_DONE));
  EXPECT_EQ(s1.at("faults"), 0.0);
  // The calibration's time: MC_APP_COG_CAL_PASSES passes of three ramps,
  // two settles and two turns (plus MC_COMM_COG_MARGIN_BINS bins) at
  // MC_APP_COG_CAL_SPEED_RAD_S; up to 5 % more: the drive's shaped
  // reference reaches the speed after the ramp, each pass's stop settles,
  // and the status is read every 50 ms.
  const double t_nom =
      MC_APP_COG_CAL_PASSES *
      (3.0 * MC_APP_COG_CAL_RAMP_S + 2.0 * MC_APP_COG_CAL_SETTLE_S +
       2.0 * 2.0 * M_PI * (1.0 + MC_COMM_COG_MARGIN_BINS / 1024.0) / MC_APP_COG_CAL_SPEED_RAD_S);
  EXPECT_GE(s1.at("cog_cal_s"), t_nom - 0.05);
  EXPECT_LE(s1.at("cog_cal_s"), 1.05 * t_nom);
  // The hold under the step load: the map takes the detent torque off the
  // position loop: the excursion at most 0.75 of the one without the map
  // (measured 0.68; 0.49 with the unfiltered map of the earlier builder,
  // which the filter to multiples of lcm(slots, 2 p) gave up for the speed
  // ripple below: the hold's excursion, a few bins wide, sees the map's
  // bin-scale content, which the filter drops; not understood further).
  RecordProperty("hold_err_pp_rad_off", std::to_string(s0.at("hold_err_pp_rad")));
  RecordProperty("hold_err_pp_rad_on", std::to_string(s1.at("hold_err_pp_rad")));
  EXPECT_LT(s1.at("hold_err_pp_rad"), 0.75 * s0.at("hold_err_pp_rad"));
  // The speed ripple at 10 % of rated speed: the 5x on the
  // peak-to-peak (measured 5.5x: 0.0801 -> 0.0145 rad/s; 8.6x before the
  // one-pass series, whose feed-forward differs by 1e-4 of its rate term).
  // That figure sits on a floor: the same motor without cogging (the
  // plant's a million times smaller, no map) ripples 0.0223 rad/s p-p here,
  // ripple not locked to the angle (the encoder's and the ADC's counts
  // through the loops) whose peaks fall differently with any change. What
  // the map is for is asserted apart: the line at the cogging order
  // (speed_ripple_cog_amp_rad_s) falls at least the 5x (measured
  // 21x: the cogging at 2.1 times the current loop's bandwidth, where the
  // feed-forward's loop model of mc_cog_loop_t matters), and the
  // peak-to-peak stays within 1.3 times the cogging-free motor's (measured
  // 0.65; the margin: those peaks).
  MotorFiles quiet = f;
  quiet.motor.cogging_nm *= 1e-6;
  std::map<std::string, std::string> txtq;
  const auto sq = testlib::run_scenario("cogging", quiet, {{"anticogging", "0"}}, "quiet", &txtq);
  ASSERT_EQ(txtq.at("verdict"), "pass") << txtq.at("verdict_detail");
  const double r10 = s0.at("speed_ripple_pp_rad_s") / s1.at("speed_ripple_pp_rad_s");
  const double line = s0.at("speed_ripple_cog_amp_rad_s") / s1.at("speed_ripple_cog_amp_rad_s");
  const double to_floor = s1.at("speed_ripple_pp_rad_s") / sq.at("speed_ripple_pp_rad_s");
  RecordProperty("speed_ripple_pp_rad_s_off", std::to_string(s0.at("speed_ripple_pp_rad_s")));
  RecordProperty("speed_ripple_pp_rad_s_on", std::to_string(s1.at("speed_ripple_pp_rad_s")));
  RecordProperty("speed_ripple_pp_rad_s_floor", std::to_string(sq.at("speed_ripple_pp_rad_s")));
  RecordProperty("cog_line_ratio", std::to_string(line));
  EXPECT_GE(r10, 5.0);
  EXPECT_GE(line, 5.0);
  EXPECT_LE(to_floor, 1.3);
}

// The slots unknown (cog_slots 0): the calibration finds the order in its
// currents (mc_cog_find_order: 84 on the SK3, the strongest of the
// lcm(Q, 14) a three-phase stator gives), builds the same map as with the
// slots given, and the run is that one, bit for bit (deterministic runs).
// Two calibrations: in the release suite only (the ASan preset leaves out
// TheMapCuts*).
TEST(CoggingScenarioSil, TheMapCutsTheSameWithTheSlotsFoundAsGiven) {
  const MotorFiles f = testlib::files({"turnigy-sk3-6374-149kv", "vesc6-48v"});
  std::map<std::string, std::string> txt1, txt2;
  const auto s1 = testlib::run_scenario("cogging", f, {{"anticogging", "1"}, {"cog_slots", "12"}},
                                        "given", &txt1);
  const auto s2 = testlib::run_scenario("cogging", f, {{"anticogging", "1"}, {"cog_slots", "0"}},
                                        "found", &txt2);
  ASSERT_EQ(txt1.at("verdict"), "pass") << txt1.at("verdict_detail");
  ASSERT_EQ(txt2.at("verdict"), "pass") << txt2.at("verdict_detail");
  EXPECT_EQ(s2.at("speed_ripple_pp_rad_s"), s1.at("speed_ripple_pp_rad_s"));
  EXPECT_EQ(s2.at("speed_ripple_cog_amp_rad_s"), s1.at("speed_ripple_cog_amp_rad_s"));
  EXPECT_EQ(s2.at("cog_ff_pp_a"), s1.at("cog_ff_pp_a"));
  EXPECT_EQ(s2.at("hold_err_pp_rad"), s1.at("hold_err_pp_rad"));
}

// The ripple's reduction by the calibrated map (anticogging 0 against 1,
// the map calibrated by the drive, filtered to the multiples of lcm(slots,
// 2 p): the scenario sets cog_slots from the motor file).
double ripple_ratio(const MotorFiles& f, double frac, const std::string& tag) {
  std::map<std::string, std::string> txt0, txt1;
  const std::string fr = std::to_string(frac);
  const auto s0 = testlib::run_scenario("cogging", f, {{"anticogging", "0"}, {"speed_frac", fr}},
                                        tag + "0", &txt0);
  const auto s1 = testlib::run_scenario("cogging", f, {{"anticogging", "1"}, {"speed_frac", fr}},
                                        tag + "1", &txt1);
  EXPECT_EQ(txt0.at("verdict"), "pass") << txt0.at("verdict_detail");
  EXPECT_EQ(txt1.at("verdict"), "pass") << txt1.at("verdict_detail");
  EXPECT_EQ(s1.at("cog_cal_status"), static_cast<double>(MC_COMM_COG_DONE));
  ::testing::Test::RecordProperty("speed_ripple_pp_rad_s_off_" + tag,
                                  std::to_string(s0.at("speed_ripple_pp_rad_s")));
  ::testing::Test::RecordProperty("speed_ripple_pp_rad_s_on_" + tag,
                                  std::to_string(s1.at("speed_ripple_pp_rad_s")));
  return s0.at("speed_ripple_pp_rad_s") / s1.at("speed_ripple_pp_rad_s");
}

// At 2 % of rated speed the SK3 reaches 13x (0.346 -> 0.027 rad/s; 22x
// before the one-pass series; bound the 5x). The GM4108 (24 slots,
// 22 poles: order 264, its map's series, not its bins, which would keep
// 0.69 of the amplitude at mid-bin) measured 8.9x at 10 % and 4.3x at 2 %
// from this power-up angle (5.3x and 3.8x before the one-pass series); from
// others (with an index: the test below) 4.7x to 5.2x at 10 %. What limits
// it is not the map: the same motor without cogging ripples at a fifth to
// a third of the cogging's ripple (0.025 to 0.037 rad/s against 0.12 to
// 0.14), the 12-bit current ADC's counts (2.4 mA, half the cogging's
// 5.2 mA of q current) through the current loop (with a 16-bit ADC it
// falls to 0.012 to 0.013), and the map brings the ripple down to that.
// Bounds 4.0x and 3.0x: under the lowest this test has measured (5.3x,
// 3.8x), for a change that moves the ripple not locked to the angle.
TEST(CoggingScenarioSil, TheMapCutsTheSpeedRippleAtTwoAndTenPercent) {
  const MotorFiles sk3 = testlib::files({"turnigy-sk3-6374-149kv", "vesc6-48v"});
  const MotorFiles gm = testlib::files({"gimbal-gm4108", "gimbal-24v"});
  EXPECT_GE(ripple_ratio(sk3, 0.02, "sk3_2"), 5.0);
  EXPECT_GE(ripple_ratio(gm, 0.10, "gm_10"), 4.0);
  EXPECT_GE(ripple_ratio(gm, 0.02, "gm_2"), 3.0);
}

// The GM4108 from three power-up angles, its angle known after each (an
// index, angle_ref 1: found at the first enable): the map takes the line at
// the cogging order (speed_ripple_cog_amp_rad_s) down at least the issue's
// 5x (measured 11x, 6.4x and 9.5x at 0.1, 0.5 and 2.9 rad; 6.9x, 7.1x and
// 13x with the two-pass series before), and the ripple's peak-to-peak to
// that of the same motor without cogging (the plant's cogging a million
// times smaller, no map): measured 0.66, 1.10 and 1.07 of it; bound 1.3:
// the ripple that is not locked to the angle (the ADC's counts through the
// loop) peaks differently from run to run (the SK3's peak-to-peak ratio
// moved from 8.6x to 5.5x with a 1e-4 change of its feed-forward). The runs at 0.1 and
// 0.5 rad that once measured 2.1x and 2.6x had the stored offset of an
// incremental encoder, 1.1 and 5.5 rad (electrical) wrong after that
// power-up (the scenario warns of it now).
TEST(CoggingScenarioSil, TheMapCutsTheGm4108sLineFromAnyPowerUpAngle) {
  MotorFiles gm = testlib::files({"gimbal-gm4108", "gimbal-24v"});
  gm.board.encoder = kEncoderAbiIndex;
  MotorFiles quiet = gm;
  quiet.motor.cogging_nm *= 1e-6;
  for (const char* th : {"0.1", "0.5", "2.9"}) {
    const testlib::Sets keys = {{"speed_frac", "0.1"},
                                {"theta_m0_rad", th},
                                {"angle_ref", "1"},
                                {"angle_find_at_enable", "1"}};
    auto k0 = keys, k1 = keys;
    k0.emplace_back("anticogging", "0");
    k1.emplace_back("anticogging", "1");
    std::map<std::string, std::string> t0, t1, tq;
    const std::string tag = std::string("gm_th") + th;
    const auto s0 = testlib::run_scenario("cogging", gm, k0, tag + "_off", &t0);
    const auto s1 = testlib::run_scenario("cogging", gm, k1, tag + "_on", &t1);
    const auto sq = testlib::run_scenario("cogging", quiet, k0, tag + "_quiet", &tq);
    ASSERT_EQ(t0.at("verdict"), "pass") << t0.at("verdict_detail");
    ASSERT_EQ(t1.at("verdict"), "pass") << t1.at("verdict_detail");
    ASSERT_EQ(tq.at("verdict"), "pass") << tq.at("verdict_detail");
    EXPECT_EQ(t1.count("warning"), 0u) << th;  // the angle is found, not assumed
    EXPECT_EQ(s1.at("cog_cal_status"), static_cast<double>(MC_COMM_COG_DONE)) << th;
    const double line = s0.at("speed_ripple_cog_amp_rad_s") / s1.at("speed_ripple_cog_amp_rad_s");
    const double to_floor = s1.at("speed_ripple_pp_rad_s") / sq.at("speed_ripple_pp_rad_s");
    RecordProperty("cog_line_ratio_" + tag, std::to_string(line));
    RecordProperty("pp_over_floor_" + tag, std::to_string(to_floor));
    RecordProperty("pp_ratio_" + tag,
                   std::to_string(s0.at("speed_ripple_pp_rad_s") / s1.at("speed_ripple_pp_rad_s")));
    EXPECT_GE(line, 5.0) << th;
    EXPECT_LE(to_floor, 1.3) << th;
  }
}

// A power-up away from the calibrated angle with an incremental encoder
// and the offset taken as stored (angle_ref 0) is named: the summary's
// warning gives the electrical error, p theta_m0 wrapped (11 x 0.1 rad).
TEST(CoggingScenarioSil, AStoredOffsetAfterAPowerUpElsewhereIsWarnedOf) {
  const MotorFiles gm = testlib::files({"gimbal-gm4108", "gimbal-24v"});
  std::map<std::string, std::string> txt;
  (void)testlib::run_scenario("cogging", gm, {{"theta_m0_rad", "0.1"}, {"angle_ref", "0"}}, "warn",
                              &txt);
  ASSERT_EQ(txt.count("warning"), 1u);
  EXPECT_NE(txt.at("warning").find("1.100 rad (electrical) off"), std::string::npos)
      << txt.at("warning");
  std::map<std::string, std::string> txt0;
  (void)testlib::run_scenario("cogging", gm, {{"angle_ref", "0"}}, "nowarn", &txt0);
  EXPECT_EQ(txt0.count("warning"), 0u);
}

// At 80 % of rated speed the SK3's cogging order is at 17 times the current
// loop's bandwidth: the loop's inverse would ask for a reference many times
// the map's current (before the fade: 27.9 A peak-to-peak against 0.2 A
// without the map, and no less ripple), so the feed-forward fades out
// (MC_COG_FADE_START, MC_COG_FADE_END) and the run is the one without a
// map in what the drive asks (measured 0.18 A against 0.20 A; bound 1.5x:
// the runs differ by the calibration before the window) and in the ripple
// (not above it by more than the same 1.5x: the peaks of the ripple that is
// not locked to the angle fall differently from run to run).
TEST(CoggingScenarioSil, AtHighSpeedTheFeedForwardFadesOut) {
  const MotorFiles f = testlib::files({"turnigy-sk3-6374-149kv", "vesc6-48v"});
  std::map<std::string, std::string> txt0, txt1;
  const auto s0 = testlib::run_scenario("cogging", f, {{"anticogging", "0"}, {"speed_frac", "0.8"}},
                                        "off80", &txt0);
  const auto s1 = testlib::run_scenario("cogging", f, {{"anticogging", "1"}, {"speed_frac", "0.8"}},
                                        "on80", &txt1);
  ASSERT_EQ(txt0.at("verdict"), "pass") << txt0.at("verdict_detail");
  ASSERT_EQ(txt1.at("verdict"), "pass") << txt1.at("verdict_detail");
  RecordProperty("iq_ref_pp_a_off", std::to_string(s0.at("iq_ref_pp_a")));
  RecordProperty("iq_ref_pp_a_on", std::to_string(s1.at("iq_ref_pp_a")));
  EXPECT_LT(s1.at("iq_ref_pp_a"), 1.5 * s0.at("iq_ref_pp_a"));
  EXPECT_LT(s1.at("speed_ripple_pp_rad_s"), 1.5 * s0.at("speed_ripple_pp_rad_s"));
}

// --set anticogging is the table's parameter when the firmware has one, and
// an unknown key (named) while it does not.
TEST(CoggingScenarioSil, AnticoggingKeyFollowsTheParameterTable) {
  const MotorFiles f = testlib::files(kD5065);
  const Scenario* s = find_scenario("cogging");
  ASSERT_NE(s, nullptr);
  bool listed = false;
  for (const auto& p : s->motor_params(f)) listed = listed || p.key == "anticogging";
  EXPECT_EQ(listed, mc_param_find_name("anticogging") >= 0);
  if (!listed) {
    EXPECT_THROW(Params(s->motor_params(f), {{"anticogging", "1"}}), UsageError);
  }
}

}  // namespace
}  // namespace mcsim
