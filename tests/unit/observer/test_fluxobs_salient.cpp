// Flux gradient observer on a salient (interior-magnet) machine, the
// active-flux form (mc_fluxobs.h): x = Lq i + psi_a c(theta), psi_a = flux +
// (Ld - Lq) i_d, with i_d taken at the previous estimate. Checked on a
// synthetic machine whose flux is exact (the voltage is the period average
// of dx/dt + R i for the kernel's trapezoid), so what is left is the
// observer's own error:
//   - configuration rules and the active flux (with its floor);
//   - Ld == Lq gives the surface-magnet observer bit for bit;
//   - the steady angle error at an MTPA operating point against the error
//     the one-step-late i_d predicts, at two speeds (it does not depend on
//     the speed);
//   - convergence from wrong starting angles;
//   - the q31 twin against the f32 kernel on the same machine.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>

extern "C" {
#include "observer/mc_fluxobs.h"
#include "observer/mc_fluxobs_q31.h"
}

namespace {

constexpr double kPi = 3.14159265358979323846;

// sim/motors/ipm-representative-48v.toml: Lq/Ld = 2, 20 kHz.
constexpr double kR = 0.05, kLd = 0.2e-3, kLq = 0.4e-3, kFlux = 0.02, kDt = 5e-5;
constexpr uint32_t kPoles = 4;

// gamma as the sensorless law sets it for this motor (its scenario's
// obs_gamma_per_wb2_s): critical speed 4.35 rad/s at the largest active
// flux, psi_a(id_mtpa(80 A)).
constexpr double kGamma = 92827.8;

mc_fluxobs_f32_cfg_t cfg_salient() {
  mc_fluxobs_f32_cfg_t c{};
  c.r_ohm = static_cast<float>(kR);
  c.l_h = static_cast<float>(kLq);
  c.flux_wb = static_cast<float>(kFlux);
  c.gamma = static_cast<float>(kGamma);
  c.dt_s = static_cast<float>(kDt);
  c.resid_tol = 0.3f;
  c.resid_time_s = 0.05f;
  c.ld_minus_lq_h = static_cast<float>(kLd - kLq);
  return c;
}

// The salient machine at constant electrical speed we, rotor-frame
// currents (id, iq) constant: its stator flux and the exact voltage.
struct Ipm {
  double we, th, id, iq;
  void current(double theta, double* ia, double* ib) const {
    const double c = std::cos(theta), s = std::sin(theta);
    *ia = c * id - s * iq;
    *ib = s * id + c * iq;
  }
  void flux(double theta, double* xa, double* xb) const {
    double ia, ib;
    current(theta, &ia, &ib);
    const double psi_a = kFlux + (kLd - kLq) * id;
    *xa = kLq * ia + psi_a * std::cos(theta);
    *xb = kLq * ib + psi_a * std::sin(theta);
  }
  void advance(double dt, double* va, double* vb, double* ia, double* ib) {
    double x0a, x0b, x1a, x1b, i0a, i0b;
    flux(th, &x0a, &x0b);
    current(th, &i0a, &i0b);
    th += we * dt;
    flux(th, &x1a, &x1b);
    current(th, ia, ib);
    *va = (x1a - x0a) / dt + kR * 0.5 * (i0a + *ia);
    *vb = (x1b - x0b) / dt + kR * 0.5 * (i0b + *ib);
  }
};

// MTPA's d current for |i| (the closed form mc_fw.h documents, in double).
double mtpa_id(double i) {
  const double dl = kLq - kLd;
  return (kFlux - std::sqrt(kFlux * kFlux + 8.0 * dl * dl * i * i)) / (4.0 * dl);
}

// Runs the kernel on the machine from a start angle offset; returns the
// largest |angle error| over the last `tail_s` of `run_s`.
double run_err(mc_fluxobs_f32_t* st, Ipm* m, double start_off, double run_s, double tail_s) {
  double ia, ib;
  m->current(m->th, &ia, &ib);
  EXPECT_EQ(mc_fluxobs_f32_reset(st, static_cast<float>(m->th + start_off), static_cast<float>(ia),
                                 static_cast<float>(ib)),
            0u);
  const long n = std::lround(run_s / kDt), n_tail = std::lround(tail_s / kDt);
  double worst = 0.0;
  for (long k = 0; k < n; ++k) {
    double va, vb;
    m->advance(kDt, &va, &vb, &ia, &ib);
    mc_fluxobs_f32_step(st, static_cast<float>(va), static_cast<float>(vb), static_cast<float>(ia),
                        static_cast<float>(ib));
    if (k >= n - n_tail) {
      worst = std::max(worst, std::abs(std::remainder(st->theta_e_rad - m->th, 2 * kPi)));
    }
  }
  return worst;
}

TEST(FluxObsSalient, ConfigRulesAndActiveFlux) {
  mc_fluxobs_f32_t st{};
  mc_fluxobs_f32_cfg_t c = cfg_salient();
  c.ld_minus_lq_h = NAN;
  EXPECT_EQ(mc_fluxobs_f32_init(&st, &c), MC_FLUXOBS_ERR_MOTOR);
  c.ld_minus_lq_h = -c.l_h;  // Ld = 0
  EXPECT_EQ(mc_fluxobs_f32_init(&st, &c), MC_FLUXOBS_ERR_MOTOR);
  c = cfg_salient();
  ASSERT_EQ(mc_fluxobs_f32_init(&st, &c), 0u);
  // psi_a = flux + (Ld - Lq) i_d in float arithmetic, exactly
  EXPECT_EQ(mc_fluxobs_f32_eval_active_flux(&c, -5.0f), c.flux_wb + (c.ld_minus_lq_h * -5.0f));
  // floored at 0.1 flux: +95 A would give 0.02 - 0.019 = 0.001 Wb
  EXPECT_EQ(mc_fluxobs_f32_eval_active_flux(&c, 95.0f), MC_FLUXOBS_PSI_A_MIN_FRAC * c.flux_wb);
  EXPECT_EQ(mc_fluxobs_f32_eval_active_flux(&c, NAN), MC_FLUXOBS_PSI_A_MIN_FRAC * c.flux_wb);
  // non-salient: the flux itself
  c.ld_minus_lq_h = 0.0f;
  EXPECT_EQ(mc_fluxobs_f32_eval_active_flux(&c, 37.0f), c.flux_wb);
}

// Ld == Lq (ld_minus_lq_h = 0): the same state, bit for bit, as a kernel
// whose config never had the field set (the surface-magnet observer), on a
// run from a wrong start with the salient machine's signals (any signals
// do: this compares two kernels, not a kernel with a machine).
TEST(FluxObsSalient, ZeroSaliencyIsTheSurfaceObserverBitForBit) {
  mc_fluxobs_f32_cfg_t a = cfg_salient();
  a.ld_minus_lq_h = 0.0f;
  mc_fluxobs_f32_cfg_t b{};
  b.r_ohm = a.r_ohm;
  b.l_h = a.l_h;
  b.flux_wb = a.flux_wb;
  b.gamma = a.gamma;
  b.dt_s = a.dt_s;
  b.resid_tol = a.resid_tol;
  b.resid_time_s = a.resid_time_s;
  mc_fluxobs_f32_t sa{}, sb{};
  ASSERT_EQ(mc_fluxobs_f32_init(&sa, &a), 0u);
  ASSERT_EQ(mc_fluxobs_f32_init(&sb, &b), 0u);
  EXPECT_EQ(sa.psi_a_wb, a.flux_wb);
  Ipm m{400.0, 0.3, -5.0, 20.0};
  double ia, ib;
  m.current(m.th, &ia, &ib);
  mc_fluxobs_f32_reset(&sa, 1.3f, static_cast<float>(ia), static_cast<float>(ib));
  mc_fluxobs_f32_reset(&sb, 1.3f, static_cast<float>(ia), static_cast<float>(ib));
  for (int k = 0; k < 4000; ++k) {
    double va, vb;
    m.advance(kDt, &va, &vb, &ia, &ib);
    mc_fluxobs_f32_step(&sa, static_cast<float>(va), static_cast<float>(vb), static_cast<float>(ia),
                        static_cast<float>(ib));
    mc_fluxobs_f32_step(&sb, static_cast<float>(va), static_cast<float>(vb), static_cast<float>(ia),
                        static_cast<float>(ib));
    ASSERT_EQ(sa.x_alpha_wb, sb.x_alpha_wb) << k;
    ASSERT_EQ(sa.x_beta_wb, sb.x_beta_wb) << k;
    ASSERT_EQ(sa.theta_e_rad, sb.theta_e_rad) << k;
    ASSERT_EQ(sa.resid, sb.resid) << k;
  }
  EXPECT_EQ(sa.psi_a_wb, a.flux_wb);
}

// The steady angle error at an MTPA operating point (|i| 23.4 A: the
// scenario's end point, id -5 A) comes from the one-step-late i_d: the
// step takes i_d at the previous estimate, an angle omega_e dt (+ phi)
// behind, so psi_a is off by dpsi = |Ld - Lq| |iq| (omega_e dt + phi). On
// the constraint circle a radius error dpsi at speed omega_e leaves the
// steady angle phi with omega_e phi = gamma psi_a dpsi (the error system's
// rotor-frame equilibrium, to first order), so
//     phi = g dt / (1 - g / omega_e),  g = gamma psi_a |Ld - Lq| |iq|,
// independent of the speed to first order (4.5e-4 rad here). Bound: within
// 10 % of that either way (first order: the neglected terms are of the
// order g / omega_e = 2 to 5 % here; measured within 0.4 %, printed), at
// two speeds a factor 2.5 apart (the scenario's 109 and 43 rad/s
// mechanical).
TEST(FluxObsSalient, SteadyAngleErrorIsTheOneStepLateIdAtAnySpeed) {
  const double i = 23.4, id = mtpa_id(i), iq = std::sqrt(i * i - id * id);
  const double psi_a = kFlux + (kLd - kLq) * id;
  for (double wm : {108.65, 43.46}) {
    const double we = kPoles * wm;
    const double g = kGamma * psi_a * std::abs(kLd - kLq) * iq;
    const double phi = g * kDt / (1.0 - g / we);
    mc_fluxobs_f32_t st{};
    const mc_fluxobs_f32_cfg_t c = cfg_salient();
    ASSERT_EQ(mc_fluxobs_f32_init(&st, &c), 0u);
    Ipm m{we, 0.7, id, iq};
    // 30 time scales 2 / (gamma psi_a^2) = 0.047 s, the last 0.1 s judged
    const double err = run_err(&st, &m, 0.3, 1.5, 0.1);
    std::printf("omega_m %.2f rad/s: steady |angle error| %.3e rad, predicted %.3e rad\n", wm, err,
                phi);
    EXPECT_LE(err, 1.1 * phi) << wm;
    EXPECT_GE(err, 0.9 * phi) << wm;  // the effect predicted, not a smaller one by luck
    EXPECT_NEAR(st.psi_a_wb, psi_a, std::abs(kLd - kLq) * iq * 2.0 * (we * kDt + phi))
        << "psi_a off by more than twice the late i_d's error";
    EXPECT_EQ(st.flags, 0u);
  }
}

// From wrong starting angles up to 2 rad either way at the scenario's
// speed (omega_e 435 rad/s, 25 times the critical speed at the smallest
// psi_a of this run) the estimate converges: within 1e-3 rad after 0.5 s
// (about 10 time scales). The psi_a the kernel uses moves with the
// estimate's error while it converges (i_d at a wrong angle): the paper's
// proof, for a constant radius, does not cover that; this is measured.
TEST(FluxObsSalient, ConvergesFromWrongStartAngles) {
  const double i = 23.4, id = mtpa_id(i), iq = std::sqrt(i * i - id * id);
  for (double off : {-2.0, -1.0, -0.5, 0.5, 1.0, 2.0}) {
    mc_fluxobs_f32_t st{};
    mc_fluxobs_f32_cfg_t c = cfg_salient();
    c.resid_time_s = 1.0f;  // starts off the constraint: the monitor is not under test
    ASSERT_EQ(mc_fluxobs_f32_init(&st, &c), 0u);
    Ipm m{kPoles * 108.65, 0.2, id, iq};
    const double err = run_err(&st, &m, off, 0.5, 0.01);
    EXPECT_LT(err, 1e-3) << "start " << off << " rad";
  }
}

// The q31 twin on the same machine and start: both angles within 2e-5 rad
// of each other (the non-salient twin test's bound and reason,
// tests/unit/q31/test_fluxobs_q31.cpp: the f32 flux integration's rounding
// drift; the twin's psi_a rounds to one q31 LSB of the flux base, 1.4e-11
// Wb, far below that), and the active flux alike.
TEST(FluxObsSalient, Q31TwinMatchesF32) {
  const double ib = 125.0, vb = 60.0, fb = 0.0625;  // flux base > 1.5 (flux + Lq i_max)
  mc_fluxobs_q31_cfg_t qc{};
  qc.f = cfg_salient();
  qc.i_base_a = static_cast<float>(ib);
  qc.v_base_v = static_cast<float>(vb);
  qc.flux_base_wb = static_cast<float>(fb);
  mc_fluxobs_f32_t f{};
  mc_fluxobs_q31_t q{};
  ASSERT_EQ(mc_fluxobs_f32_init(&f, &qc.f), 0u);
  ASSERT_EQ(mc_fluxobs_q31_init(&q, &qc), 0u);
  const double i = 23.4, id = mtpa_id(i), iq = std::sqrt(i * i - id * id);
  Ipm m{kPoles * 108.65, 0.4, id, iq};
  auto toq = [](double v, double base) {
    return static_cast<q31_t>(std::nearbyint(v / base * 2147483648.0));
  };
  double ia, ibb;
  m.current(m.th, &ia, &ibb);
  const double start = m.th + 0.5;
  ASSERT_EQ(mc_fluxobs_f32_reset(&f, static_cast<float>(start), static_cast<float>(ia),
                                 static_cast<float>(ibb)),
            0u);
  ASSERT_EQ(
      mc_fluxobs_q31_reset(&q, toq(std::remainder(start, 2 * kPi), kPi), toq(ia, ib), toq(ibb, ib)),
      0u);
  double worst = 0.0, worst_psi = 0.0;
  for (int k = 0; k < 20000; ++k) {
    double va, vbv;
    m.advance(kDt, &va, &vbv, &ia, &ibb);
    const q31_t vaq = toq(va, vb), vbq = toq(vbv, vb), iaq = toq(ia, ib), ibq = toq(ibb, ib);
    mc_fluxobs_f32_step(&f, static_cast<float>(vaq / 2147483648.0 * vb),
                        static_cast<float>(vbq / 2147483648.0 * vb),
                        static_cast<float>(iaq / 2147483648.0 * ib),
                        static_cast<float>(ibq / 2147483648.0 * ib));
    mc_fluxobs_q31_step(&q, vaq, vbq, iaq, ibq);
    const double tq = q.theta / 2147483648.0 * kPi;
    worst = std::max(worst, std::abs(std::remainder(f.theta_e_rad - tq, 2 * kPi)));
    worst_psi = std::max(worst_psi, std::abs(f.psi_a_wb - q.psi_a_pu / 2147483648.0 * fb));
  }
  std::printf("q31 vs f32 (salient): angle %.2e rad, psi_a %.2e Wb\n", worst, worst_psi);
  EXPECT_LE(worst, 2e-5);
  // psi_a from i_d at angles 2e-5 rad apart: |Ld - Lq| |i| 2e-5 = 1e-7 Wb
  EXPECT_LE(worst_psi, std::abs(kLd - kLq) * i * 2e-5 + 1e-9);
  EXPECT_EQ(q.flags, 0u);
}

}  // namespace
