// The library's motors (sim/motors) through the scenarios for any motor,
// with the firmware in the loop: the criteria of issue 16 (deliverable 5),
// and the errors of bad motor/board files.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "app_params.hpp"
#include "motor_library.hpp"

namespace mcsim {
namespace {

using testlib::Case;
using testlib::files;

std::map<std::string, double> run(const std::string& scen, const MotorFiles& f,
                                  const testlib::Sets& sets) {
  return testlib::run_scenario(scen, f, sets);
}

class MotorSil : public ::testing::TestWithParam<Case> {};

// Deliverable 5: 10-90 % rise within 25 % of the design ln 9 / bw.
TEST_P(MotorSil, CurrentStepRiseWithin25PercentOfDesign) {
  const auto r = run("current-step", files(GetParam()), {});
  EXPECT_EQ(r.at("faults"), 0.0);
  EXPECT_NEAR(r.at("iq_rise_time_ratio"), 1.0, 0.25);
  EXPECT_NEAR(r.at("id_rise_time_ratio"), 1.0, 0.25);
}

// Sensored speed step (speed PI) settles to 2 % without fault; |i_d| stays
// below 10 % of rated in steady state. Overshoot: the law compares the
// speed with its reference through the feed-forward's lag
// (mc_ctrl_speed_cfg_t.ref_lag_s), so a ramp longer than the encoder
// tracking loop's settling (3 / bw) ends without overshoot: below 0.3 %
// (measured at most 0.06 % over the library; without the lag the
// integrator winds up on the ramp's tracking error: 0.9 % on the D5065).
// A shorter ramp (the
// gimbal's 2.3 ms) meets the tracking loop's transient, which the lag does
// not model: below 12 % (measured 9.5 %).
TEST_P(MotorSil, SpeedStepPiSettles) {
  const auto r = run("speed-step", files(GetParam()), {});
  EXPECT_EQ(r.at("faults"), 0.0);
  EXPECT_EQ(r.at("settled"), 1.0);
  EXPECT_LT(r.at("id_abs_max_steady_frac_rated"), 0.10);
  const double ramp_s = r.at("omega_final_rad_s") / r.at("gain.speed_accel_rad_s2");
  const bool long_ramp = ramp_s > 3.0 / r.at("gain.enc_pll_bw_rad_s");
  EXPECT_LT(r.at("overshoot_frac"), long_ramp ? 0.003 : 0.12) << "ramp " << ramp_s << " s";
}

// PI2D: settles and keeps |i_d| < 10 % of rated in steady state, or is
// refused with its reason (never a generic fault).
TEST_P(MotorSil, SpeedStepPi2dSettlesWithSmallIdOrRefuses) {
  const MotorFiles f = files(GetParam());
  if (files_params_eff(f).g.pi2d_coupling > MC_GAINS_PI2D_COUPLING_MAX) {
    try {
      run("speed-step", f, {{"law", "pi2d"}});
      FAIL() << "expected a refusal";
    } catch (const UsageError& e) {
      EXPECT_NE(std::string(e.what()).find("PI2D refuses this motor"), std::string::npos);
    }
    return;
  }
  const auto r = run("speed-step", f, {{"law", "pi2d"}});
  EXPECT_EQ(r.at("faults"), 0.0);
  EXPECT_EQ(r.at("settled"), 1.0);
  EXPECT_LT(r.at("id_abs_max_steady_frac_rated"), 0.10);
}

// PI2D on a low-inertia rotor (issue 31 item 4; the maxon EC 45 flat 50 W
// class, sim/motors/maxon-ec45flat-class-24v.toml, on the 24 V ODrive
// v3.6). With the catalogue's rotor (135 g cm2, coupling 184 rad/s) the
// derived gains are damped: overshoot below 3 % (measured 0.8 %), the
// residual oscillation in the steady window below 0.5 % of the target
// (measured 0.17 %: the encoder's quantisation through the tracking loop),
// the mean steady error below 0.05 % (measured 0.005 %). With the light
// rotor of the library file (13.5 g cm2, coupling 1837 rad/s above
// MC_GAINS_PI2D_COUPLING_MAX), where the law rang at 40 Hz before the
// bound, the application refuses the law by name, and the speed PI runs
// the same step without a fault.
TEST(MotorSilLowInertia, Pi2dDampedOnTheCatalogueRotorRefusedOnTheLightOne) {
  const std::string dir = MCSIM_MOTORS_DIR;
  const std::string motor = dir + "/maxon-ec45flat-class-24v.toml";
  const std::string board = dir + "/odrive-v36-24v.toml";
  const MotorFiles heavy = load_motor_files(motor, board, {{"motor.j_kgm2", "1.35e-5"}});
  ASSERT_LT(files_params_eff(heavy).g.pi2d_coupling, MC_GAINS_PI2D_COUPLING_MAX);
  const auto r = run("speed-step", heavy, {{"law", "pi2d"}});
  const double target = r.at("omega_final_rad_s");
  EXPECT_EQ(r.at("faults"), 0.0);
  EXPECT_EQ(r.at("settled"), 1.0);
  EXPECT_LT(r.at("overshoot_frac"), 0.03);
  EXPECT_LT(r.at("omega_pp_steady_rad_s"), 0.005 * target);
  EXPECT_LT(std::fabs(r.at("omega_err_mean_steady_rad_s")), 5e-4 * target);

  const MotorFiles light = load_motor_files(motor, board);
  EXPECT_GT(files_params_eff(light).g.pi2d_coupling, MC_GAINS_PI2D_COUPLING_MAX);
  try {
    run("speed-step", light, {{"law", "pi2d"}});
    ADD_FAILURE() << "PI2D ran on the light rotor";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("PI2D_COUPLING"), std::string::npos) << e.what();
  }
  const auto pi = run("speed-step", light, {});
  EXPECT_EQ(pi.at("faults"), 0.0);
  EXPECT_EQ(pi.at("settled"), 1.0);
}

// Load step under the speed PI: the speed returns within 2 %.
TEST_P(MotorSil, LoadStepRecovers) {
  const auto r = run("load-step", files(GetParam()), {});
  EXPECT_EQ(r.at("faults"), 0.0);
  EXPECT_EQ(r.at("settled"), 1.0);
}

// Sensorless start from standstill under 30 % rated load: locks, tracks
// (within 5 % of the target at the end, after a further 30 % load step),
// angle error below 0.2 rad electrical after the lock (the observer's
// steady error here is under 0.08 rad; 0.2 rad costs 2 % of torque).
// The rms angle error is the observer's own, compared with the true angle
// at the sample it was computed from: below a quarter of omega_e T at the
// end speed (measured 0.007 to 0.11 of it over the library; against the
// angle one period later, as before issue 31, it read omega_e T itself).
TEST_P(MotorSil, SensorlessStartUnderLoadLocksAndTracks) {
  const MotorFiles f = files(GetParam());
  const auto r = run("sensorless-speed-step", f, {});
  EXPECT_EQ(r.at("faults"), 0.0);
  EXPECT_EQ(r.at("locked"), 1.0);
  EXPECT_EQ(r.at("tracks"), 1.0);
  EXPECT_LT(r.at("angle_err_max_rad"), 0.2);
  const double we_t = f.motor.pole_pairs * std::abs(r.at("omega_final_rad_s")) / f.board.pwm_hz;
  EXPECT_LT(r.at("angle_err_rms_rad"), 0.25 * we_t);
}

// The alignment does not turn the rotor backwards beyond what the load
// alone does before the drive's torque can hold it (issue 31). The active
// load (30 % rated, against the run) turns the rotor at standstill
// backwards at tau_L / J from t = 0: until the application enables the
// drive (t_enable_s), then while the first hold's current ramps (0 to
// if_current over half the align time) and its torque, with the current
// pi/4 ahead of the rotor at rest (mc_ctrl_sensorless.c ALIGN_LEAD1),
// kt I(t) sin(pi/4), is below tau_L: t_c = (align_time / 2) tau_L /
// (kt if_current sin(pi/4)). The backward speed is at most the load's over
// t_enable + t_c (the drive's torque only slows it; friction ignored, which
// only slows it too); measured 0.60 to 0.80 of it over the library. Before,
// the first hold's current lay along the rotor's d axis (no torque until
// the rotor had turned) and the second pulled the rotor a quarter turn
// against a negative run: 1.26 to 1.63 times this bound (D5065 8.1 rad/s
// against 5.7), 31.6 rad/s on the D5065 at -250 rad/s.
constexpr double kPi = 3.14159265358979323846;

double align_backwards_bound(const MotorFiles& f, const std::map<std::string, double>& r) {
  const mc_gains_t g = files_params_eff(f).g;
  const double tau_l = 0.3 * g.torque_rated_nm;  // the scenario's load_frac
  const double t_c =
      0.5 * g.align_time_s * tau_l / (g.kt_nm_a * g.if_current_a * std::sin(kPi / 4));
  return tau_l / f.motor.j_kgm2 * (r.at("t_enable_s") + t_c);
}

TEST_P(MotorSil, SensorlessAlignDoesNotPullTheRotorBack) {
  const MotorFiles f = files(GetParam());
  const auto r = run("sensorless-speed-step", f, {});
  EXPECT_EQ(r.at("faults"), 0.0);
  EXPECT_LE(r.at("align_backwards_rad_s"), align_backwards_bound(f, r));
}

// The same in the other direction on the D5065 (the second hold turned the
// rotor against a negative run: 31.6 rad/s backwards before issue 31).
TEST(MotorSilAlign, NegativeRunD5065AlignsForwards) {
  const MotorFiles f = files({"odrive-d5065", "odrive-v36-24v"});
  const auto r = run("sensorless-speed-step", f, {{"speed_rad_s", "-250"}});
  EXPECT_EQ(r.at("faults"), 0.0);
  EXPECT_EQ(r.at("locked"), 1.0);
  EXPECT_LE(r.at("align_backwards_rad_s"), align_backwards_bound(f, r));
}

// The salient machine (sim/motors/ipm-representative-48v.toml: Ld 0.2 mH,
// Lq 0.4 mH, its own 48 V 20 kHz board with its one-period delay) under the
// sensorless law: the active-flux observer and MTPA's d current
// (mc_ctrl_sensorless.h), refused before issue 31. The scenario's own
// verdict passes (lock, tracking within 5 %, angle error after the lock
// below 0.2 rad). At the end (the last tenth after the load step, 60 %
// rated torque):
// - the observer's own angle error (same-instant comparison, as the
//   scenario's) below a quarter of omega_e T, the library's criterion for
//   the observer's own error (measured 1.3e-3 rad against 5.4e-3; the
//   one-step-late i_d alone accounts for 4.6e-4 rad,
//   tests/unit/observer/test_fluxobs_salient.cpp);
// - MTPA: i_d negative, within 0.05 A of MTPA's for the current magnitude
//   (the law's MTPA uses the plant's own Ld, Lq and flux; the current loop
//   integrates its error away; 0.05 A covers the end window's mean of a
//   current with PWM ripple and 12-bit samples of 0.06 A: measured 0.005 A);
// - the torque per ampere: the current magnitude for the electrical torque
//   delivered (from the true dq currents) within 0.1 % of the MTPA optimum
//   for that torque (the curve is flat there: an i_d error is second order
//   in |i|; measured 2e-8) and at least 2 % below the i_d = 0 current for
//   the same torque (the optimum's gain here is 2.5 %).
double ipm_mtpa_id(const MotorFiles& f, double i) {
  const double dl = f.motor.lq_h - f.motor.ld_h, psi = f.motor.flux_wb;
  return (psi - std::sqrt(psi * psi + 8.0 * dl * dl * i * i)) / (4.0 * dl);
}

double ipm_torque(const MotorFiles& f, double id, double iq) {
  return 1.5 * f.motor.pole_pairs * iq * (f.motor.flux_wb + (f.motor.ld_h - f.motor.lq_h) * id);
}

TEST(MotorSilIpm, SensorlessSpeedStepRunsWithMtpa) {
  const MotorFiles f = files({"ipm-representative-48v", ""});
  std::map<std::string, std::string> texts;
  const auto r = testlib::run_scenario("sensorless-speed-step", f, {}, "", &texts);
  EXPECT_EQ(texts["verdict"], "pass") << texts["verdict_detail"];
  EXPECT_EQ(r.at("board.delay_periods"), 1.0);  // the board's delay, not an ideal one
  EXPECT_EQ(r.at("faults"), 0.0);
  EXPECT_EQ(r.at("locked"), 1.0);
  EXPECT_EQ(r.at("tracks"), 1.0);
  EXPECT_EQ(r.at("fallbacks"), 0.0);
  const double we_t = f.motor.pole_pairs * std::abs(r.at("omega_final_rad_s")) / f.board.pwm_hz;
  EXPECT_LT(r.at("angle_err_max_end_rad"), 0.25 * we_t);
  const double id = r.at("id_mean_end_a"), iq = r.at("iq_mean_end_a");
  const double i = std::hypot(id, iq);
  EXPECT_LT(id, 0.0);
  EXPECT_NEAR(id, ipm_mtpa_id(f, i), 0.05);
  // the MTPA current for the torque delivered, by bisection on the
  // MTPA curve's torque (increasing in |i|)
  const double t_e = ipm_torque(f, id, iq);
  double lo = 0.0, hi = f.motor.i_max_a;
  for (int k = 0; k < 60; ++k) {
    const double m = 0.5 * (lo + hi), d = ipm_mtpa_id(f, m);
    (ipm_torque(f, d, std::sqrt(m * m - d * d)) < t_e ? lo : hi) = m;
  }
  const double i_id0 = t_e / (1.5 * f.motor.pole_pairs * f.motor.flux_wb);
  std::printf("IPM sensorless: id %.3f A, |i| %.3f A, MTPA %.3f A, id=0 %.3f A, angle %.2e rad\n",
              id, i, lo, i_id0, r.at("angle_err_max_end_rad"));
  EXPECT_NEAR(i / lo, 1.0, 1e-3);
  EXPECT_LT(i, 0.98 * i_id0);
}

INSTANTIATE_TEST_SUITE_P(Library, MotorSil, ::testing::ValuesIn(testlib::library()),
                         testlib::case_name);

// ------------------------------------------------------------ bad files
std::string write(const std::string& name, const std::string& text) {
  const std::string p = ::testing::TempDir() + "/motors_sil_" + name;
  std::ofstream(p) << text;
  return p;
}

std::string error_of(const std::string& motor, const std::string& board = "") {
  try {
    load_motor_files(motor, board);
  } catch (const UsageError& e) {
    return e.what();
  }
  return "";
}

const char* kGood =
    "[motor]\nname = \"m\"\nr_ohm = 0.1\nld_h = 1e-4\nlq_h = 1e-4\nflux_wb = 0.01\n"
    "pole_pairs = 7\nj_kgm2 = 1e-4\nb_nm_s_rad = 0\ni_max_a = 20\nspeed_max_rad_s = 500\n"
    "[board]\nname = \"b\"\nvbus_v = 24\npwm_hz = 20000\ndead_time_s = 0\ncurrent_sensors = 2\n"
    "i_sense_max_a = 40\nadc_bits = 12\nencoder_cpr = 4096\n";

TEST(MotorFile, GoodFileParses) {
  const MotorFiles f = load_motor_files(write("good.toml", kGood), "");
  EXPECT_EQ(f.motor.pole_pairs, 7);
  EXPECT_EQ(f.board.encoder_cpr, 4096);
  EXPECT_DOUBLE_EQ(f.motor.i_rated_a, 10.0);  // default i_max_a / 2
}

TEST(MotorFile, MissingKeyNamesFileLineAndKey) {
  std::string t = kGood;
  t.replace(t.find("r_ohm = 0.1\n"), 12, "");
  const std::string p = write("missing.toml", t);
  EXPECT_EQ(error_of(p), p + ":1: [motor] is missing the required key 'r_ohm'");
}

TEST(MotorFile, UnknownKeyNamesItsLine) {
  std::string t = kGood;
  t.replace(t.find("pole_pairs"), 0, "R_ohm = 3\n");  // line 7
  const std::string p = write("unknown.toml", t);
  EXPECT_EQ(error_of(p).rfind(p + ":7: unknown key 'R_ohm' in [motor]", 0), 0u) << error_of(p);
}

TEST(MotorFile, OutOfRangeNamesItsLine) {
  std::string t = kGood;
  t.replace(t.find("current_sensors = 2"), 19, "current_sensors = 4");  // line 17
  const std::string p = write("range.toml", t);
  EXPECT_EQ(error_of(p).rfind(p + ":17: 'current_sensors' = 4 is out of range [2, 3]", 0), 0u)
      << error_of(p);
}

TEST(MotorFile, MalformedTomlNamesItsLine) {
  const std::string p = write("malformed.toml", "[motor]\nname = \"m\"\nr_ohm = = 1\n");
  EXPECT_EQ(error_of(p).rfind(p + ":3: malformed TOML", 0), 0u) << error_of(p);
}

TEST(MotorFile, MissingBoardTable) {
  std::string t = kGood;
  t = t.substr(0, t.find("[board]"));
  const std::string p = write("noboard.toml", t);
  EXPECT_EQ(error_of(p).rfind(p + ":1: no [board] table here and no --board FILE given", 0), 0u);
}

// No safe gains: the PWM rate too low for L/R.
TEST(MotorFile, PwmTooSlowForLOverRIsRefused) {
  std::string t = kGood;
  const std::string l_old = "ld_h = 1e-4\nlq_h = 1e-4", pwm_old = "pwm_hz = 20000";
  t.replace(t.find(l_old), l_old.size(), "ld_h = 1e-5\nlq_h = 1e-5");  // L/R = 0.1 ms
  t.replace(t.find(pwm_old), pwm_old.size(), "pwm_hz = 5000");         // 2 T = 0.4 ms
  const MotorFiles f = load_motor_files(write("slow.toml", t), "");
  try {
    files_params_eff(f);  // the C derivation's refusal, named
    FAIL() << "expected a refusal";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("shorter than two PWM periods"), std::string::npos);
  }
}

// Cogging keys (issue 35): parsed, handed to the plant, a torque without
// slots refused with its line.
TEST(MotorFile, CoggingKeysReachThePlant) {
  std::string t = kGood;
  t.replace(t.find("[board]"), 0,
            "slots = 12\ncogging_nm = 0.02\ncogging_phase_rad = 0.5\ncogging_h3_nm = 0.004\n");
  const MotorFiles f = load_motor_files(write("cog.toml", t), "");
  EXPECT_EQ(f.motor.slots, 12);
  const hal_host::PmsmBoardConfig bc = build_board_cfg(f);
  EXPECT_EQ(bc.motor.cogging.slots, 12);
  EXPECT_EQ(bc.motor.cogging.amplitude_nm, 0.02);
  EXPECT_EQ(bc.motor.cogging.phase_rad, 0.5);
  EXPECT_EQ(bc.motor.cogging.harmonic_nm[1], 0.004);
  EXPECT_EQ(bc.motor.cogging.harmonic_nm[0], 0.0);
  EXPECT_EQ(mcsim::cogging_order(bc.motor.cogging.slots, bc.motor.pole_pairs), 84);
  // The default file: none.
  EXPECT_FALSE(
      build_board_cfg(load_motor_files(write("good2.toml", kGood), "")).motor.cogging.active());
  std::string u = kGood;
  u.replace(u.find("[board]"), 0, "cogging_nm = 0.02\n");  // line 12, no slots
  const std::string pu = write("cog_noslots.toml", u);
  EXPECT_EQ(error_of(pu).rfind(pu + ":12: a cogging torque needs 'slots'", 0), 0u) << error_of(pu);
  std::string v = kGood;
  v.replace(v.find("[board]"), 0, "slots = 12\ncogging_nm = -1\n");  // line 13
  const std::string pv = write("cog_neg.toml", v);
  EXPECT_EQ(error_of(pv).rfind(pv + ":13: 'cogging_nm' = -1 N m is out of range", 0), 0u)
      << error_of(pv);
}

// Every bad cogging key refused with its line and a named reason (issue 35
// item 1): slots not an integer or negative, a negative, NaN or infinite
// amplitude, a NaN phase, a harmonic order the plant does not have (the
// fundamental is cogging_nm; harmonics are the orders 2 to 4 times it).
TEST(MotorFile, BadCoggingKeysAreRefusedByName) {
  const struct {
    const char* keys;  // inserted before [board]: the first at line 12
    const char* error;
  } cases[] = {
      {"slots = 12.5\n", ":12: 'slots' must be an integer"},
      {"slots = -1\n", ":12: 'slots' = -1 is out of range [0, 1000]"},
      {"slots = 12\ncogging_nm = nan\n", ":13: 'cogging_nm' = nan N m is out of range"},
      {"slots = 12\ncogging_nm = inf\n", ":13: 'cogging_nm' = inf N m is out of range"},
      {"slots = 12\ncogging_nm = 0.01\ncogging_phase_rad = nan\n",
       ":14: 'cogging_phase_rad' = nan rad is out of range"},
      {"slots = 12\ncogging_h2_nm = -0.001\n", ":13: 'cogging_h2_nm' = -0.001 N m is out of range"},
      {"slots = 12\ncogging_h1_nm = 0.01\n", ":13: unknown key 'cogging_h1_nm' in [motor]"},
      {"slots = 12\ncogging_h5_nm = 0.01\n", ":13: unknown key 'cogging_h5_nm' in [motor]"},
      {"cogging_h3_nm = 0.01\n", ":12: a cogging torque needs 'slots'"},
  };
  int i = 0;
  for (const auto& c : cases) {
    std::string t = kGood;
    t.replace(t.find("[board]"), 0, c.keys);
    const std::string p = write("cog_bad" + std::to_string(i++) + ".toml", t);
    const std::string e = error_of(p);
    EXPECT_EQ(e.rfind(p + c.error, 0), 0u) << c.keys << " -> " << e;
  }
}

}  // namespace
}  // namespace mcsim
