// Commissioning (issue 18) in the loop: the drive application's
// commissioning over CAN (sim/cli/scenarios/generic_commission.hpp: the
// image's mc_comm_can, its configuration from mc_comm_can_cfg_for_board,
// the application booted from the files' parameter table) identifies the
// motor of a file; the runs on the identified values reboot the application
// on the table commissioning staged. Accuracy asked: R 2 %, Ld and Lq 5 %,
// flux 3 %, pole pairs exact, encoder offset 1 deg electrical, direction
// right, under 10 s simulated. Each accuracy test prints one
// machine-readable line "COMMISSION_ACCURACY {json}" (quoted by
// firmware/app/commission/README.md).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "motor_file.hpp"
#include "motor_library.hpp"
#include "scenarios/generic_commission.hpp"
extern "C" {
#include "config/mc_law_cfg.h"
}

namespace mcsim {
namespace {

constexpr double kPi = 3.14159265358979323846;
using testlib::Case;
const std::vector<Case>& kCases = testlib::library();

MotorFiles load(const Case& c) {
  return testlib::files(c);
}

double off_err_deg(const CommissionRun& r) {
  return std::remainder(r.res.encoder_offset_rad - r.true_encoder_offset_rad, 2 * kPi) * 180 / kPi;
}

void expect_accurate(const MotorFiles& f, const CommissionRun& r, const std::string& tag) {
  ASSERT_TRUE(r.done) << tag << ": " << commission_error_names(r.err);
  const MotorSpec& m = f.motor;
  const double er = r.res.r_ohm / m.r_ohm - 1, ed = r.res.ld_h / m.ld_h - 1,
               eq = r.res.lq_h / m.lq_h - 1, ef = r.res.flux_wb / m.flux_wb - 1;
  std::printf(
      "COMMISSION_ACCURACY {\"case\": \"%s\", \"r_frac\": %.5f, \"ld_frac\": %.5f, "
      "\"lq_frac\": %.5f, \"flux_frac\": %.5f, \"pole_pairs\": %u, \"pole_pairs_true\": %d, "
      "\"encoder_offset_deg\": %.4f, \"direction_ok\": %d, \"duration_s\": %.3f}\n",
      tag.c_str(), er, ed, eq, ef, r.res.pole_pairs, m.pole_pairs, off_err_deg(r),
      r.res.encoder_direction == r.true_encoder_direction ? 1 : 0, r.duration_s);
  // The flux step's own checks (mc_comm_check.h) passed: their figures
  const mc_comm_flux_chk_t& fc = r.flux_chk;
  const mc_comm_mech_chk_t& mc = r.mech_chk;
  std::printf(
      "COMMISSION_CHECKS {\"case\": \"%s\", \"flux_dev\": %.5f, \"flux_tol\": %.5f, "
      "\"j_dev\": %.5f, \"j_tol\": %.5f, \"fit_rms\": %.5f, \"fit_tol\": %.5f, "
      "\"j_frac\": %.5f, \"b_frac\": %.5f}\n",
      tag.c_str(), fc.dev, fc.tol, mc.j_dev, mc.j_tol, mc.fit_rms, mc.fit_tol,
      r.res.j_kgm2 / m.j_kgm2 - 1, r.res.b_nm_s_rad / m.b_nm_s_rad - 1);
  EXPECT_LT(std::abs(er), 0.02) << tag;
  EXPECT_LT(std::abs(ed), 0.05) << tag;
  EXPECT_LT(std::abs(eq), 0.05) << tag;
  EXPECT_LT(std::abs(ef), 0.03) << tag;
  EXPECT_EQ(r.res.pole_pairs, static_cast<uint32_t>(m.pole_pairs)) << tag;
  EXPECT_LT(std::abs(off_err_deg(r)), 1.0) << tag;
  EXPECT_EQ(r.res.encoder_direction, r.true_encoder_direction) << tag;
  EXPECT_LT(r.duration_s, 10.0) << tag;
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(r.res.adc_offset_a[k], r.true_adc_offset_a[k], 0.002 * f.board.i_sense_max_a)
        << tag << " phase " << k;
  }
}

class LibraryMotor : public ::testing::TestWithParam<int> {};

TEST_P(LibraryMotor, IdentifiesWithinBounds) {
  const int i = GetParam();
  const MotorFiles f = load(kCases[i]);
  CommissionSetup s = default_commission_setup(f);
  // Both encoder directions over the library, different offsets.
  s.encoder_direction = (i % 2 == 0) ? 1 : -1;
  s.encoder_offset_rad = 0.7 + 0.9 * i;
  expect_accurate(f, run_commission(f, s), kCases[i].motor);
}

INSTANTIATE_TEST_SUITE_P(Library, LibraryMotor,
                         ::testing::Range(0, static_cast<int>(testlib::library().size())));

// Motors drawn from ranges that cover the library (log-uniform), on a board
// sized for each (its sensor range, bus and PWM from the motor).
TEST(CommissionRandom, RandomisedMotorsFixedSeed) {
  std::mt19937_64 rng(20240518u);
  auto logu = [&](double lo, double hi) {
    std::uniform_real_distribution<double> u(std::log(lo), std::log(hi));
    return std::exp(u(rng));
  };
  for (int n = 0; n < 6; ++n) {
    MotorFiles f;
    MotorSpec& m = f.motor;
    BoardSpec& b = f.board;
    m.name = "random-" + std::to_string(n);
    m.file = m.name;
    m.pole_pairs = std::uniform_int_distribution<int>(1, 14)(rng);
    m.r_ohm = logu(0.02, 5.0);
    const double tau = logu(4e-4, 1e-2);  // L/R of the library: 0.4 .. 10 ms
    m.ld_h = m.r_ohm * tau;
    m.lq_h = m.ld_h * std::uniform_real_distribution<double>(1.0, 1.6)(rng);  // saliency
    m.flux_wb = logu(2e-3, 0.15);
    m.i_rated_a = std::min(300.0, 2.0 / m.r_ohm);
    // Inertia from the rated acceleration kt i_rated / J, 500 .. 10^4
    // rad/s^2 as in the library (560 for the 0.3 kW machine on its
    // dynamometer, 10^4 for the low-inductance outrunner); B / J as there.
    m.j_kgm2 = 1.5 * m.pole_pairs * m.flux_wb * m.i_rated_a / logu(500.0, 1.0e4);
    m.b_nm_s_rad = m.j_kgm2 * logu(0.05, 0.5);
    m.i_max_a = 2 * m.i_rated_a;
    m.speed_max_rad_s = 500;
    m.speed_rated_rad_s = 400;
    b.name = "random-board";
    b.file = b.name;
    b.vbus_v = std::max(24.0, std::min(400.0, 20.0 * m.r_ohm * m.i_rated_a));
    // a whole number of kHz: the application's CAN tick (pwm_hz /
    // slow_loop_div, the slow loop at about 1 kHz) must be a whole rate
    b.pwm_hz = 1000.0 * std::round(std::max(8000.0, std::min(48000.0, 20.0 / tau)) / 1000.0);
    b.dead_time_s = std::uniform_real_distribution<double>(0.0, 3e-7)(rng);
    b.current_sensors = (n % 2) ? 3 : 2;
    b.i_sense_max_a = 2.0 * m.i_rated_a;
    b.adc_bits = 12;
    b.encoder_cpr = (n % 3 == 0) ? 4096 : 16384;
    CommissionSetup s = default_commission_setup(f);
    s.encoder_direction = (n % 2) ? -1 : 1;
    s.encoder_offset_rad = std::uniform_real_distribution<double>(0, 2 * kPi)(rng);
    s.seed = 100u + static_cast<unsigned>(n);
    SCOPED_TRACE(m.name + ": R " + std::to_string(m.r_ohm) + " L " + std::to_string(m.ld_h) + "/" +
                 std::to_string(m.lq_h) + " flux " + std::to_string(m.flux_wb) + " p " +
                 std::to_string(m.pole_pairs) + " J " + std::to_string(m.j_kgm2) + " vbus " +
                 std::to_string(b.vbus_v) + " pwm " + std::to_string(b.pwm_hz));
    expect_accurate(f, run_commission(f, s), m.name);
  }
}

// --------------------------------------------------------- refusals
void expect_refused(const CommissionRun& r, uint32_t bit, const char* what) {
  EXPECT_FALSE(r.done) << what;
  EXPECT_NE(r.err & bit, 0u) << what << ": got " << commission_error_names(r.err);
  EXPECT_TRUE(r.bridge_off) << what;
  EXPECT_EQ(r.res.valid, 0u) << what << ": nothing to store";
}

MotorFiles d5065() {
  return load(kCases[2]);
}

TEST(CommissionRefuses, NoMotorConnected) {
  const MotorFiles f = d5065();
  CommissionSetup s = default_commission_setup(f);
  s.inject = [](hal_host::PmsmBoard& b) {
    hal_host::PmsmBoard::Injection inj;
    inj.motor_disconnected = true;
    b.inject(inj);
  };
  expect_refused(run_commission(f, s), MC_COMM_ERR_NO_MOTOR, "no motor");
}

TEST(CommissionRefuses, OpenPhaseEachPhase) {
  const MotorFiles f = d5065();
  for (int ph = 0; ph < 3; ++ph) {
    CommissionSetup s = default_commission_setup(f);
    s.inject = [ph, &s](hal_host::PmsmBoard& b) {
      hal_host::PmsmBoard::Injection inj;
      inj.offset_a[0] = s.adc_offset_a;
      inj.offset_a[1] = -0.7 * s.adc_offset_a;
      inj.offset_a[2] = 0.4 * s.adc_offset_a;
      inj.open_phase = ph;
      b.inject(inj);
    };
    expect_refused(run_commission(f, s), MC_COMM_ERR_OPEN_PHASE,
                   ("open phase " + std::to_string(ph)).c_str());
  }
}

// The salient interior-magnet motor (Lq/Ld = 2, its board in the file).
// Issue 31: its commissioning stopped at the connection check with a false
// OPEN_PHASE: the alpha try alone was judged per phase, and with Ld != Lq
// the alpha try's current leans off alpha (toward d), so at theta_e = 1 rad
// phase b carried 0.195 of phase a's ripple (< 0.2). The check now takes
// each phase over both tries (mc_commission.c connection_check).
MotorFiles ipm() {
  const std::string dir = MCSIM_MOTORS_DIR;
  return load_motor_files(dir + "/ipm-representative-48v.toml", "");
}

TEST(CommissionSalient, IpmIdentifiesAtTheAngleThatFailed) {
  const MotorFiles f = ipm();
  ASSERT_NEAR(f.motor.lq_h / f.motor.ld_h, 2.0, 1e-9);  // the file is salient
  // theta_e = 1 rad (the scenario's default, where the old check failed)
  // and 2.6 rad (phase c the weak one of the alpha try: 2 theta past pi).
  for (double th : {1.0, 2.6}) {
    CommissionSetup s = default_commission_setup(f);
    s.encoder_offset_rad = th;
    const CommissionRun r = run_commission(f, s);
    const std::string tag = "ipm theta_e " + std::to_string(th);
    // R 2 %, Ld/Lq 5 %, flux 3 %, p exact, offset 1 deg: the accuracy asked
    // of every motor (header); measured at 1 rad: R -0.03 %, Ld -0.2 %,
    // Lq -0.03 %, flux -0.03 %.
    expect_accurate(f, r, tag);
    // J and B (spin-up and coast-down slopes) are asked of no motor to an
    // accuracy; measured +25 % (J) and +20 % (B) at 1 rad. The factor-1.5
    // bound catches a gross error (a torque constant or a slope off by 2x),
    // not the estimate's known bias.
    EXPECT_GT(r.res.j_kgm2, f.motor.j_kgm2 / 1.5) << tag;
    EXPECT_LT(r.res.j_kgm2, f.motor.j_kgm2 * 1.5) << tag;
    EXPECT_GT(r.res.b_nm_s_rad, f.motor.b_nm_s_rad / 1.5) << tag;
    EXPECT_LT(r.res.b_nm_s_rad, f.motor.b_nm_s_rad * 1.5) << tag;
  }
}

// A phase really opened (the plant's open-phase model, PmsmOpenPhase) on
// the salient motor is still refused by name, each phase, at the angle
// where the old check gave a false refusal.
TEST(CommissionRefuses, OpenPhaseEachPhaseSalient) {
  const MotorFiles f = ipm();
  for (int ph = 0; ph < 3; ++ph) {
    CommissionSetup s = default_commission_setup(f);
    s.encoder_offset_rad = 1.0;
    s.inject = [ph](hal_host::PmsmBoard& b) {
      hal_host::PmsmBoard::Injection inj;
      inj.open_phase = ph;
      b.inject(inj);
    };
    expect_refused(run_commission(f, s), MC_COMM_ERR_OPEN_PHASE,
                   ("ipm open phase " + std::to_string(ph)).c_str());
  }
}

TEST(CommissionRefuses, ImplausibleSensorOffset) {
  const MotorFiles f = d5065();
  CommissionSetup s = default_commission_setup(f);
  s.adc_offset_a = 0.3 * f.board.i_sense_max_a;  // a broken sensor
  expect_refused(run_commission(f, s), MC_COMM_ERR_OFFSET, "offset");
}

TEST(CommissionRefuses, EncoderNotMoving) {
  const MotorFiles f = d5065();
  CommissionSetup s = default_commission_setup(f);
  s.inject = [&s](hal_host::PmsmBoard& b) {
    hal_host::PmsmBoard::Injection inj;
    inj.offset_a[0] = s.adc_offset_a;
    inj.offset_a[1] = -0.7 * s.adc_offset_a;
    inj.offset_a[2] = 0.4 * s.adc_offset_a;
    inj.encoder_frozen = true;
    b.inject(inj);
  };
  expect_refused(run_commission(f, s), MC_COMM_ERR_ENCODER_NO_MOTION, "encoder frozen");
}

// The hub motor (sim/motors/hub-6p5in-15pp.toml) on the ODrive v3.6 with
// its Hall sensors read as 90 counts: 6 counts per electrical turn, below
// MC_COMM_COUNTS_PER_E_TURN_MIN (12): refused by name before the spin (the
// coast's speed from so few counts read the flux 41 % low, error_bits 0,
// before the check). At 180 counts (12 per electrical turn) the same motor
// identifies within the library's bounds (flux measured 1.5 % off).
using testlib::hub_on_odrive;

TEST(CommissionRefuses, EncoderTooCoarseForTheFlux) {
  const MotorFiles f = hub_on_odrive(90);
  const CommissionRun r = run_commission(f, default_commission_setup(f));
  expect_refused(r, MC_COMM_ERR_ENCODER_COARSE, "90 counts, 15 pole pairs");
  EXPECT_EQ(r.err, MC_COMM_ERR_ENCODER_COARSE) << commission_error_names(r.err);
}

TEST(CommissionCoarse, TwelveCountsPerElectricalTurnIdentify) {
  const MotorFiles f = hub_on_odrive(180);
  expect_accurate(f, run_commission(f, default_commission_setup(f)), "hub_180_counts");
}

TEST(CommissionRefuses, BlockedRotor) {
  const MotorFiles f = d5065();
  CommissionSetup s = default_commission_setup(f);
  // The plant's rotor as good as locked (the drive's table keeps the file's
  // inertia: 10^6 kg m^2 is outside the parameter's range).
  s.plant = [](hal_host::PmsmBoardConfig& bc) { bc.motor.J_kgm2 = 1.0e6; };
  expect_refused(run_commission(f, s), MC_COMM_ERR_ROTOR_BLOCKED, "blocked");
}

TEST(CommissionRefuses, RotorTurnsTheWrongWay) {
  const MotorFiles f = d5065();
  CommissionSetup s = default_commission_setup(f);
  // An overhauling load appears when the flux spin-up begins: it turns the
  // rotor against the drive's torque.
  bool loaded = false;
  s.each_period = [&loaded](hal_host::PmsmBoard& b, uint32_t step) {
    if (!loaded && step == MC_COMM_STEP_FLUX) {
      // about 10x the spin-up torque (1.5 * 7 * 2.92e-3 Wb * 10 A)
      b.set_load(load_constant(3.0));
      loaded = true;
    }
  };
  expect_refused(run_commission(f, s), MC_COMM_ERR_WRONG_DIRECTION, "wrong way");
}

// The motor files the library list does not carry: the light-rotor maxon
// class (on the 24 V ODrive, as its speed-law test runs it), with its
// light rotor and the catalogue's, identify within the library's bounds:
// the flux step's checks (mc_comm_check.h) do not refuse them.
TEST(CommissionChecks, TheLightRotorFilesPassTheChecks) {
  const std::string dir = MCSIM_MOTORS_DIR;
  for (const char* j : {"1.35e-6", "1.35e-5"}) {
    const MotorFiles f = load_motor_files(dir + "/maxon-ec45flat-class-24v.toml",
                                          dir + "/odrive-v36-24v.toml", {{"motor.j_kgm2", j}});
    expect_accurate(f, run_commission(f, default_commission_setup(f)),
                    std::string("maxon-ec45flat J ") + j);
  }
}

// The flux step's own J/B check (mc_comm_check.h): the d5065 with Coulomb
// friction, a constant torque the viscous model J a = T - B w cannot hold:
// the coast reads it as viscous and the spin-up's two halves then give two
// inertias. Refused by name (the status frame: RANGE, detail
// MECH_SPIN_COAST), nothing staged.
TEST(CommissionRefuses, CoulombFrictionIsNotViscous) {
  const MotorFiles f = d5065();
  for (const double frac : {0.1, 0.3}) {
    CommissionSetup s = default_commission_setup(f);
    // of the spin-up's torque, 1.5 p psi i_test / 2 (i_test as the board's
    // rule gives it: a quarter of the sense range)
    const double tq = 1.5 * f.motor.pole_pairs * f.motor.flux_wb * 0.125 * f.board.i_sense_max_a;
    s.plant = [tq, frac](hal_host::PmsmBoardConfig& bc) { bc.motor.load.coulomb_nm = frac * tq; };
    const CommissionRun r = run_commission(f, s);
    const mc_comm_mech_chk_t& mc = r.mech_chk;
    std::printf(
        "COMMISSION_REFUSED {\"case\": \"coulomb %.2f\", \"detail\": \"%s\", "
        "\"j_dev\": %.4f, \"j_tol\": %.4f, \"j_lo_frac\": %.4f, \"j_hi_frac\": %.4f}\n",
        frac, commission_detail_name(r.detail).c_str(), mc.j_dev, mc.j_tol,
        mc.j_lo_kgm2 / f.motor.j_kgm2 - 1, mc.j_hi_kgm2 / f.motor.j_kgm2 - 1);
    expect_refused(r, MC_COMM_ERR_RANGE, "coulomb friction");
    EXPECT_EQ(r.detail, MC_COMM_DETAIL_MECH_SPIN_COAST) << commission_detail_name(r.detail);
    EXPECT_GT(mc.j_dev, mc.j_tol) << frac;
  }
}

// A load that appears during the coast (a brake, a coupling that engages):
// a fifth of the spin-up torque 0.15 s after the rotor's speed peaked,
// within the coast's 0.25 s fit. The coast is no longer one line: refused
// by name (RANGE, detail MECH_FIT), nothing staged.
TEST(CommissionRefuses, ALoadDuringTheCoast) {
  const MotorFiles f = d5065();
  CommissionSetup s = default_commission_setup(f);
  const double tq = 1.5 * f.motor.pole_pairs * f.motor.flux_wb * 0.125 * f.board.i_sense_max_a;
  double peak = 0, t_peak = 0;
  bool loaded = false;
  s.each_period = [&](hal_host::PmsmBoard& b, uint32_t step) {
    if (step != MC_COMM_STEP_FLUX || loaded) return;
    const double w = b.state()(2);
    if (w > peak) {
      peak = w;
      t_peak = b.t_s();
    } else if (b.t_s() - t_peak >= 0.15) {
      b.set_load(load_constant(0.2 * tq));
      loaded = true;
    }
  };
  const CommissionRun r = run_commission(f, s);
  const mc_comm_mech_chk_t& mc = r.mech_chk;
  std::printf(
      "COMMISSION_REFUSED {\"case\": \"coast load\", \"detail\": \"%s\", "
      "\"fit_rms\": %.4f, \"fit_tol\": %.4f}\n",
      commission_detail_name(r.detail).c_str(), mc.fit_rms, mc.fit_tol);
  ASSERT_TRUE(loaded);
  expect_refused(r, MC_COMM_ERR_RANGE, "a load during the coast");
  EXPECT_EQ(r.detail, MC_COMM_DETAIL_MECH_FIT) << commission_detail_name(r.detail);
  EXPECT_GT(mc.fit_rms, mc.fit_tol);
}

// ------------------------------------------- running on identified values
TEST(CommissionThenRun, SensoredAndSensorlessOnIdentifiedValues) {
  for (int i : {2, 0, 3}) {
    const MotorFiles f = load(kCases[i]);
    const CommissionSetup s = default_commission_setup(f);
    const CommissionRun r = run_commission(f, s);
    ASSERT_TRUE(r.done) << kCases[i].motor;
    double w = 0;
    const double e1 = verify_speed_step(f, s, r.staged, MC_LAW_SPEED_PI, &w);
    const double e2 = verify_speed_step(f, s, r.staged, MC_LAW_SPEED_SENSORLESS, &w);
    std::printf(
        "COMMISSION_RUN {\"case\": \"%s\", \"speed_rad_s\": %.3f, "
        "\"sensored_err_frac\": %.5f, \"sensorless_err_frac\": %.5f}\n",
        kCases[i].motor, w, e1, e2);
    EXPECT_LT(e1, 0.02) << kCases[i].motor;
    EXPECT_LT(e2, 0.05) << kCases[i].motor;
  }
}

// ------------------------------------ sensorless start from any rotor angle
// The sensorless speed step (I-f start, then the flux observer) from 8
// evenly spaced initial electrical angles, on every library motor, on the
// motor's true values (the start-up is under test, not the identification).
// Pass: no fault (the observer's DIVERGED among them) and the speed within
// 5 % of the target at the end, the criterion of the sensorless tests of
// tests/sil/motors and of CommissionThenRun above.
CommissionRun true_values_run(const MotorFiles& f, const CommissionSetup& s) {
  CommissionRun r;
  r.res.r_ohm = static_cast<float>(f.motor.r_ohm);
  r.res.ld_h = static_cast<float>(f.motor.ld_h);
  r.res.lq_h = static_cast<float>(f.motor.lq_h);
  r.res.flux_wb = static_cast<float>(f.motor.flux_wb);
  r.res.pole_pairs = static_cast<uint32_t>(f.motor.pole_pairs);
  r.res.encoder_offset_rad = static_cast<float>(s.encoder_offset_rad);
  r.res.encoder_direction = s.encoder_direction;
  r.res.j_kgm2 = static_cast<float>(f.motor.j_kgm2);
  r.res.b_nm_s_rad = static_cast<float>(f.motor.b_nm_s_rad);
  r.res.valid = MC_COMM_HAVE_ALL;
  r.done = true;
  r.staged = staged_params(commission_booted_params(f), r.res);
  return r;
}

class SensorlessStartAngle : public ::testing::TestWithParam<int> {};

TEST_P(SensorlessStartAngle, EightInitialAnglesLockAndTrack) {
  const MotorFiles f = load(kCases[GetParam()]);
  CommissionSetup s = default_commission_setup(f);
  s.adc_offset_a = 0.0;  // the drive subtracts none here (true-value run)
  const CommissionRun r = true_values_run(f, s);
  for (int k = 0; k < 8; ++k) {
    s.sensorless_start_theta_e_rad = 2.0 * kPi * k / 8.0;
    double w = 0;
    const double e = verify_speed_step(f, s, r.staged, MC_LAW_SPEED_SENSORLESS, &w);
    std::printf(
        "SENSORLESS_START {\"case\": \"%s\", \"theta_e0_rad\": %.4f, \"speed_rad_s\": %.3f, "
        "\"err_frac\": %.5f}\n",
        kCases[GetParam()].motor, s.sensorless_start_theta_e_rad, w, e);
    EXPECT_FALSE(std::isnan(e)) << kCases[GetParam()].motor
                                << " faulted from theta_e0 = " << s.sensorless_start_theta_e_rad;
    EXPECT_LT(e, 0.05) << kCases[GetParam()].motor
                       << " theta_e0 = " << s.sensorless_start_theta_e_rad;
  }
}
INSTANTIATE_TEST_SUITE_P(Library, SensorlessStartAngle,
                         ::testing::Range(0, static_cast<int>(testlib::library().size())));

}  // namespace
}  // namespace mcsim
