// Commissioning without an encoder (issue 31, "Commissioning without an
// encoder"; firmware/app/commission/README.md "Without an encoder"): the
// library's motors on their boards with encoder_cpr 0, the drive
// application's commissioning over CAN (generic_commission.hpp, as
// test_commission_sil). R and L are measured on the aligned rotor as with
// an encoder, the flux from the I-f spin's two holds, the pole pairs the
// table's (the user's). Bounds: those of the encoder runs
// (test_commission_sil: R 2 %, Ld and Lq 5 %, flux 3 %, the sensor offsets
// 0.2 % of the sense range, under 10 s), the same reasons. Each accuracy
// run prints "COMMISSION_SLS {json}" with the two holds' fluxes and their
// check (dev against tol), each refusal "COMMISSION_REFUSED {json}".
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "motor_file.hpp"
#include "motor_library.hpp"
#include "scenarios/generic_commission.hpp"

namespace mcsim {
namespace {

MotorFiles no_encoder(const testlib::Case& c) {
  MotorFiles f = testlib::files(c);
  f.board.encoder_cpr = 0;
  return f;
}

void expect_accurate_sls(const MotorFiles& f, const CommissionRun& r, const std::string& tag) {
  ASSERT_TRUE(r.done) << tag << ": " << commission_error_names(r.err) << " "
                      << commission_detail_name(r.detail);
  const MotorSpec& m = f.motor;
  const double er = r.res.r_ohm / m.r_ohm - 1, ed = r.res.ld_h / m.ld_h - 1,
               eq = r.res.lq_h / m.lq_h - 1, ef = r.res.flux_wb / m.flux_wb - 1;
  const mc_comm_flux_chk_t& fc = r.flux_chk;
  std::printf(
      "COMMISSION_SLS {\"case\": \"%s\", \"r_frac\": %.5f, \"ld_frac\": %.5f, \"lq_frac\": %.5f, "
      "\"flux_frac\": %.5f, \"psi_hi_frac\": %.5f, \"psi_lo_frac\": %.5f, \"flux_dev\": %.5f, "
      "\"flux_tol\": %.5f, \"duration_s\": %.3f}\n",
      tag.c_str(), er, ed, eq, ef, fc.psi_hi_wb / m.flux_wb - 1, fc.psi_lo_wb / m.flux_wb - 1,
      fc.dev, fc.tol, r.duration_s);
  // the result says what it is: no encoder values, no mechanics
  EXPECT_NE(r.res.valid & MC_COMM_SENSORLESS, 0u) << tag;
  EXPECT_EQ(r.res.valid & (MC_COMM_HAVE_ENCODER | MC_COMM_HAVE_MECH), 0u) << tag;
  EXPECT_LT(std::abs(er), 0.02) << tag;
  EXPECT_LT(std::abs(ed), 0.05) << tag;
  EXPECT_LT(std::abs(eq), 0.05) << tag;
  EXPECT_LT(std::abs(ef), 0.03) << tag;
  EXPECT_LE(fc.dev, fc.tol) << tag;
  EXPECT_EQ(r.res.pole_pairs, static_cast<uint32_t>(m.pole_pairs)) << tag;
  EXPECT_LT(r.duration_s, 10.0) << tag;
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(r.res.adc_offset_a[k], r.true_adc_offset_a[k], 0.002 * f.board.i_sense_max_a)
        << tag << " phase " << k;
  }
  // the staged table keeps the booted encoder values (none measured)
  EXPECT_EQ(r.staged.encoder_cpr, 0u) << tag;
}

class NoEncoderLibrary : public ::testing::TestWithParam<int> {};

TEST_P(NoEncoderLibrary, IdentifiesWithinTheEncoderBounds) {
  const testlib::Case& c = testlib::library()[static_cast<size_t>(GetParam())];
  const MotorFiles f = no_encoder(c);
  CommissionSetup s = default_commission_setup(f);
  s.encoder_offset_rad = 0.7 + 0.9 * GetParam();  // the rotor's power-up angle
  expect_accurate_sls(f, run_commission(f, s), std::string(c.motor) + " no encoder");
}

INSTANTIATE_TEST_SUITE_P(Library, NoEncoderLibrary,
                         ::testing::Range(0, static_cast<int>(testlib::library().size())));

// The salient IPM (Lq = 2 Ld): the rotor's d axis in the spin's frame is
// found where the back-EMF has no d part, Ld and Lq on their own axes.
// From two power-up angles (the alignment finds the rotor from either).
TEST(NoEncoderSalient, IpmIdentifiesWithinTheEncoderBounds) {
  const std::string dir = MCSIM_MOTORS_DIR;
  MotorFiles f = load_motor_files(dir + "/ipm-representative-48v.toml", "");
  f.board.encoder_cpr = 0;
  ASSERT_NEAR(f.motor.lq_h / f.motor.ld_h, 2.0, 1e-9);  // the file is salient
  for (double th : {1.0, 2.6}) {
    CommissionSetup s = default_commission_setup(f);
    s.encoder_offset_rad = th;
    expect_accurate_sls(f, run_commission(f, s), "ipm no encoder theta_e " + std::to_string(th));
  }
}

MotorFiles d5065_no_encoder() {
  return no_encoder(testlib::library()[2]);
}

void expect_if_sync(const CommissionRun& r, const char* what) {
  std::printf("COMMISSION_REFUSED {\"case\": \"%s\", \"error\": \"%s\", \"detail\": \"%s\"}\n",
              what, commission_error_names(r.err).c_str(),
              commission_detail_name(r.detail).c_str());
  EXPECT_FALSE(r.done) << what;
  // a wide bit: the frame's error field carries RANGE, its detail the name
  EXPECT_EQ(r.err, MC_COMM_ERR_RANGE) << what << ": " << commission_error_names(r.err);
  EXPECT_EQ(r.detail, MC_COMM_DETAIL_IF_SYNC) << what << ": " << commission_detail_name(r.detail);
  EXPECT_TRUE(r.bridge_off) << what;
  EXPECT_EQ(r.res.valid, 0u) << what << ": nothing to store";
}

// A friction the spin's torque cannot overcome (1.2 times the most i_test
// makes, 1.5 p psi i_test): the rotor stays, the back-EMF the holds see is
// the inductance's error alone, far below the IF_PSI_MIN share of Ld i_test.
TEST(NoEncoderRefuses, AFrictionThatStallsTheSpin) {
  const MotorFiles f = d5065_no_encoder();
  CommissionSetup s = default_commission_setup(f);
  const double tq = 1.5 * f.motor.pole_pairs * f.motor.flux_wb * 0.25 * f.board.i_sense_max_a;
  s.plant = [tq](hal_host::PmsmBoardConfig& bc) { bc.motor.load.coulomb_nm = 1.2 * tq; };
  expect_if_sync(run_commission(f, s), "stalled by friction");
}

// A rotor that cannot be turned at all (J 10^6 kg m^2).
TEST(NoEncoderRefuses, BlockedRotor) {
  const MotorFiles f = d5065_no_encoder();
  CommissionSetup s = default_commission_setup(f);
  s.plant = [](hal_host::PmsmBoardConfig& bc) { bc.motor.J_kgm2 = 1.0e6; };
  expect_if_sync(run_commission(f, s), "blocked");
}

// The rotor follows the ramp, then a load above the pull-out torque (twice
// the most i_test makes) arrives as the higher hold begins: it falls out of
// step, its back-EMF turns in the spin's frame and the hold refuses it.
TEST(NoEncoderRefuses, OutOfStepUnderALoad) {
  const MotorFiles f = d5065_no_encoder();
  CommissionSetup s = default_commission_setup(f);
  const double tq = 1.5 * f.motor.pole_pairs * f.motor.flux_wb * 0.25 * f.board.i_sense_max_a;
  double peak = 0;
  bool loaded = false;
  s.each_period = [&](hal_host::PmsmBoard& b, uint32_t step) {
    if (step != MC_COMM_STEP_FLUX || loaded) return;
    const double w = b.state()(2);
    peak = std::max(peak, w);
    // the ramp over (the speed no longer rising, well above the start's)
    if (peak > 100.0 && w < peak) {
      b.set_load(load_constant(2.0 * tq));
      loaded = true;
    }
  };
  const CommissionRun r = run_commission(f, s);
  ASSERT_TRUE(loaded);
  expect_if_sync(r, "out of step");
}

}  // namespace
}  // namespace mcsim
