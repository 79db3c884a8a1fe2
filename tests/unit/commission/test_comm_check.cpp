// The flux step's consistency checks (firmware/app/commission/mc_comm_check.h)
// on synthetic records with closed forms: consistent data pass, data that
// break the model are refused by name, and the status frame's mapping of
// the wide error bits.
#include <gtest/gtest.h>

#include <cmath>

extern "C" {
#include "commission/mc_comm_check.h"
#include "commission/mc_commission.h"
}

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr float kDt = 1.0f / 20000.0f;  // a 20 kHz PWM period

// ------------------------------------------------------------ blocks
TEST(CommCheckBlocks, ALineOfAnyLengthIsKeptAsItsBlockMeans) {
  for (const uint32_t n : {16u, 17u, 100u, 1000u, 40000u}) {
    mc_comm_blk_t b;
    mc_comm_blk_reset(&b);
    for (uint32_t k = 0; k < n; ++k) mc_comm_blk_step(&b, 50.0f + 300.0f * kDt * k);
    // 8..16 full blocks once they have merged, each len samples
    EXPECT_GE(b.nb, 8u) << n;
    EXPECT_LE(b.nb, 16u) << n;
    EXPECT_LE(b.nb * b.len, n) << n;
    EXPECT_GT(2 * b.nb * b.len + b.len, n) << n;
    // block j's mean is the line at its centre, (j len + (len - 1) / 2) dt;
    // float sums of up to 2048 samples: 1e-5 relative
    for (uint32_t j = 0; j < b.nb; ++j) {
      const double t = (j * b.len + 0.5 * (b.len - 1)) * kDt;
      EXPECT_NEAR(b.mean[j], 50.0 + 300.0 * t, 1e-5 * (50.0 + 300.0 * t)) << n << " block " << j;
    }
    const double m = 50.0 + 300.0 * (0.5 * (b.nb * b.len - 1)) * kDt;
    EXPECT_NEAR(mc_comm_blk_mean(&b, 0u, b.nb), m, 1e-5 * m) << n;
  }
}

// -------------------------------------------------------------- flux
// A coast of T s from w0 (electrical) with v = psi w + v0 sampled every dt,
// split into its halves as the flux step splits it.
// psi_hi, psi_lo: the bands' through-origin fits in double (closed form).
struct FluxBands {
  mc_ident_line_f32_t hi{}, lo{};
  double psi_hi = 0, psi_lo = 0;
  FluxBands(double psi, double v0, double w0, double decay, double t_s) {
    mc_ident_line_f32_reset(&hi);
    mc_ident_line_f32_reset(&lo);
    const int n = static_cast<int>(t_s / kDt);
    double svw[2] = {0, 0}, sww[2] = {0, 0};
    for (int k = 0; k < n; ++k) {
      const double w = w0 * std::exp(-decay * k * kDt);
      const double v = psi * w + v0;
      mc_ident_line_f32_step(k < n / 2 ? &hi : &lo, static_cast<float>(w), static_cast<float>(v));
      svw[k < n / 2 ? 0 : 1] += v * w;
      sww[k < n / 2 ? 0 : 1] += w * w;
    }
    psi_hi = svw[0] / sww[0];
    psi_lo = svw[1] / sww[1];
  }
};

TEST(CommCheckFlux, BandResolutionIsItsThreeTerms) {
  // 4096 counts, a 0.125 s band, tau 2 ms, 100 rad/s, 0.2 V of 10 V
  const double q = 2 * kPi / 4096;
  const double expect = 3 * q / (0.125 * 100) + q / (2 * 0.002 * 100) + 0.2 / 10;
  EXPECT_NEAR(mc_comm_flux_band_res_f32(4096u, 0.125f, 0.002f, 100.0f, 0.2f, 10.0f), expect,
              1e-6 * expect);  // float arithmetic
  // nothing to resolve with: 1 (no agreement possible within it)
  EXPECT_EQ(1.0f, mc_comm_flux_band_res_f32(0u, 0.125f, 0.002f, 100.0f, 0.2f, 10.0f));
  EXPECT_EQ(1.0f, mc_comm_flux_band_res_f32(4096u, 0.125f, 0.002f, 0.0f, 0.2f, 10.0f));
  EXPECT_EQ(1.0f, mc_comm_flux_band_res_f32(4096u, 0.125f, 0.002f, 100.0f, 0.2f, 0.0f));
}

TEST(CommCheckFlux, TheBackEmfAloneAgreesAnOffsetBeyondTheResolutionIsRefused) {
  // a coast from 700 rad/s el. losing a third over 0.25 s, psi 10 mWb
  const double psi = 0.01, w0 = 700, decay = 1.6;
  const float tol = 0.01f;
  mc_comm_flux_chk_t out;
  const FluxBands ok(psi, 0.0, w0, decay, 0.25);
  EXPECT_EQ(0u, mc_comm_flux_check_f32(&ok.hi, &ok.lo, tol, &out));
  // float sums over 2500 samples a band
  EXPECT_LT(out.dev, 1e-4f);
  EXPECT_NEAR(out.psi_hi_wb, psi, 1e-4 * psi);
  // a constant 1.5 V besides (a voltage the fit takes for back-EMF): the
  // through-origin fits read psi + v0 mean(w) / mean(w^2) in each band,
  // about 4 % apart at the bands' 630 and 520 rad/s, beyond the 1 %
  const FluxBands bad(psi, 1.5, w0, decay, 0.25);
  const double dev = std::abs(bad.psi_hi - bad.psi_lo) / (0.5 * (bad.psi_hi + bad.psi_lo));
  EXPECT_GT(dev, 0.03);
  EXPECT_EQ(MC_COMM_ERR_FLUX_SPEEDS, mc_comm_flux_check_f32(&bad.hi, &bad.lo, tol, &out));
  // the float sums against the closed form: 1e-3 of the deviation
  EXPECT_NEAR(out.dev, dev, 1e-3 * dev);
  EXPECT_NEAR(out.psi_lo_wb, bad.psi_lo, 1e-4 * bad.psi_lo);
  EXPECT_EQ(tol, out.tol);
  // just inside the tolerance passes: a tolerance above the deviation
  EXPECT_EQ(0u, mc_comm_flux_check_f32(&bad.hi, &bad.lo, static_cast<float>(1.01 * dev), &out));
  // an empty band
  mc_ident_line_f32_t empty;
  mc_ident_line_f32_reset(&empty);
  EXPECT_EQ(MC_COMM_ERR_FLUX_SPEEDS, mc_comm_flux_check_f32(&ok.hi, &empty, tol, &out));
}

// --------------------------------------------------------- mechanics
// A rotor J w' = T - Tc - B w - load(t), spun up from rest with T for
// t_spin, then coasting (T = 0) for 0.25 s; the records as the flux step
// keeps them (the spin-up from 0.02 s), the speed exact (RK4 would be
// overkill at 50 us: forward Euler steps of dt/10).
struct Rotor {
  mc_comm_blk_t spin{}, coast{};
  Rotor(double j, double b, double t, double tc, double t_spin, double coast_step_nm = 0.0) {
    mc_comm_blk_reset(&spin);
    mc_comm_blk_reset(&coast);
    double w = 0;
    auto advance = [&](double tq) {
      for (int s = 0; s < 10; ++s) {
        const double fr = (w > 0 ? tc : 0.0);
        w += (tq - fr - b * w) / j * (kDt / 10);
      }
    };
    const int ns = static_cast<int>(t_spin / kDt);
    for (int k = 0; k < ns; ++k) {
      advance(t);
      if (k * kDt >= 0.02) mc_comm_blk_step(&spin, static_cast<float>(w));
    }
    const int nc = static_cast<int>(0.25 / kDt);
    for (int k = 0; k < nc; ++k) {
      advance(k < nc / 2 ? 0.0 : -coast_step_nm);
      mc_comm_blk_step(&coast, static_cast<float>(w));
    }
  }
};

constexpr uint32_t kCpr = 16384u;

TEST(CommCheckMech, AViscousRotorIsConsistent) {
  // the d5065's figures roughly: J 1e-4, B/J 0.2 .. 2 /s, 0.3 N m
  for (const double bj : {0.2, 2.0}) {
    const double j = 1e-4, b = bj * j, t = 0.3;
    const Rotor r(j, b, t, 0.0, 0.3);
    mc_comm_mech_chk_t out;
    EXPECT_EQ(0u, mc_comm_mech_check_f32(&r.spin, &r.coast, kDt, kCpr, t, &out)) << bj;
    // the halves' chords of an exponential: under 1 % apart; the coast's
    // middle third off its chord: beta T / 12 of the fall (mc_comm_check.c),
    // 0.004 and 0.04 here (T the coast's blocks, within 0.25 s)
    EXPECT_LT(out.j_dev, 0.01f) << bj;
    EXPECT_LT(out.fit_rms, bj * 0.25f / 12.0f * 1.1f) << bj;
    EXPECT_GT(out.fit_rms, bj * 0.2f / 12.0f * 0.9f) << bj;
    // each half's J with the coast's B/J: the viscous model's own J within
    // 2 % (a line's slope over a curving record)
    EXPECT_NEAR(out.j_lo_kgm2, j, 0.02 * j) << bj;
    EXPECT_NEAR(out.j_hi_kgm2, j, 0.02 * j) << bj;
    // the tolerances: the stated ones plus a small resolution part
    EXPECT_GE(out.j_tol, MC_COMM_MECH_J_TOL);
    EXPECT_LT(out.j_tol, MC_COMM_MECH_J_TOL + 0.02f);
    EXPECT_GE(out.fit_tol, MC_COMM_MECH_FIT_TOL);
  }
}

TEST(CommCheckMech, CoulombFrictionIsRefusedByName) {
  // a tenth of the spin-up torque as Coulomb friction, B/J 0.2: the coast
  // reads the constant torque as viscous and the two halves disagree
  const double j = 1e-4, b = 0.2 * j, t = 0.3;
  const Rotor r(j, b, t, 0.1 * t, 0.3);
  mc_comm_mech_chk_t out;
  EXPECT_EQ(MC_COMM_ERR_MECH_SPIN_COAST,
            mc_comm_mech_check_f32(&r.spin, &r.coast, kDt, kCpr, t, &out));
  EXPECT_GT(out.j_dev, out.j_tol);
  EXPECT_LT(out.fit_rms, out.fit_tol) << "the coast itself is a line";
}

TEST(CommCheckMech, ALoadThatStepsDuringTheCoastIsRefusedByName) {
  // a load of a fifth of the spin-up torque from the coast's middle on
  const double j = 1e-4, b = 0.2 * j, t = 0.3;
  const Rotor r(j, b, t, 0.0, 0.3, 0.2 * t);
  mc_comm_mech_chk_t out;
  EXPECT_EQ(MC_COMM_ERR_MECH_FIT, mc_comm_mech_check_f32(&r.spin, &r.coast, kDt, kCpr, t, &out));
  EXPECT_GT(out.fit_rms, out.fit_tol);
}

TEST(CommCheckMech, CoarseCountsWidenTheTolerance) {
  // the same Coulomb rotor read with 64 counts a turn: the resolution
  // allows the disagreement, so the check cannot tell and does not refuse
  const double j = 1e-4, b = 0.2 * j, t = 0.3;
  const Rotor r(j, b, t, 0.1 * t, 0.3);
  mc_comm_mech_chk_t fine;
  mc_comm_mech_chk_t coarse;
  (void)mc_comm_mech_check_f32(&r.spin, &r.coast, kDt, kCpr, t, &fine);
  EXPECT_EQ(0u, mc_comm_mech_check_f32(&r.spin, &r.coast, kDt, 64u, t, &coarse));
  EXPECT_GT(coarse.j_tol, fine.j_tol);
  EXPECT_GT(coarse.j_tol, coarse.j_dev);
}

TEST(CommCheckMech, TooShortARecordIsRefused) {
  mc_comm_blk_t spin;
  mc_comm_blk_t coast;
  mc_comm_blk_reset(&spin);
  mc_comm_blk_reset(&coast);
  for (int k = 0; k < 4; ++k) mc_comm_blk_step(&spin, 1.0f * k);
  for (int k = 0; k < 100; ++k) mc_comm_blk_step(&coast, 10.0f - 0.01f * k);
  mc_comm_mech_chk_t out;
  EXPECT_EQ(MC_COMM_ERR_MECH_FIT, mc_comm_mech_check_f32(&spin, &coast, kDt, kCpr, 0.3f, &out));
}

// ------------------------------------------------- the status frame
TEST(CommCheckFrame, WideBitsTravelAsRangeWithTheirDetail) {
  uint32_t d = 99u;
  EXPECT_EQ(MC_COMM_ERR_OFFSET, mc_comm_err_frame(MC_COMM_ERR_OFFSET, &d));
  EXPECT_EQ(MC_COMM_DETAIL_NONE, d);
  EXPECT_EQ(MC_COMM_ERR_RANGE, mc_comm_err_frame(MC_COMM_ERR_FLUX_SPEEDS, &d));
  EXPECT_EQ(MC_COMM_DETAIL_FLUX_SPEEDS, d);
  EXPECT_EQ(MC_COMM_ERR_RANGE, mc_comm_err_frame(MC_COMM_ERR_MECH_FIT, &d));
  EXPECT_EQ(MC_COMM_DETAIL_MECH_FIT, d);
  EXPECT_EQ(MC_COMM_ERR_RANGE | MC_COMM_ERR_HALL_ORDER,
            mc_comm_err_frame(MC_COMM_ERR_MECH_SPIN_COAST | MC_COMM_ERR_HALL_ORDER, &d));
  EXPECT_EQ(MC_COMM_DETAIL_MECH_SPIN_COAST, d);
  EXPECT_EQ(MC_COMM_ERR_RANGE, mc_comm_err_frame(MC_COMM_ERR_IF_SYNC, &d));
  EXPECT_EQ(MC_COMM_DETAIL_IF_SYNC, d);
}

}  // namespace
