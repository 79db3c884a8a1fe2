// Unit tests of the csmc kernels (paper 001). Every tolerance carries the
// reason for its size; references are computed here in double.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

extern "C" {
#include "csmc/mc_csmc.h"
#include "csmc/mc_csmc_linalg.h"
#include "csmc/mc_csvc.h"
#include "observer/mc_hgo.h"
#include "csmc/mc_stepper_dq.h"
}

namespace {

constexpr double kPi = 3.14159265358979323846;

// ------------------------------------------------------------ dq transform
TEST(CsmcStepperDq, MatchesPaperMatrixAndRoundTrips) {
  std::mt19937 g(1);
  std::uniform_real_distribution<float> u(-5.0f, 5.0f);
  for (int i = 0; i < 1000; ++i) {
    const float xa = u(g), xb = u(g), th = 0.1f * u(g);
    float xd, xq, ra, rb;
    mc_stepper_ab_to_dq_f32(xa, xb, th, 50u, &xd, &xq);
    const double e = 50.0 * static_cast<double>(th);
    const double xd_ref = std::cos(e) * xa + std::sin(e) * xb;
    const double xq_ref = -std::sin(e) * xa + std::cos(e) * xb;
    // sincos error 2e-7 plus rounding of N_r*phi (ulp(25 rad) = 2e-6 rad)
    // times |x| <= 7: 2e-5.
    EXPECT_NEAR(xd, xd_ref, 2e-5);
    EXPECT_NEAR(xq, xq_ref, 2e-5);
    mc_stepper_dq_to_ab_f32(xd, xq, th, 50u, &ra, &rb);
    // rotation and its transpose with the same sin/cos: a few ulp of 7.
    EXPECT_NEAR(ra, xa, 4e-6);
    EXPECT_NEAR(rb, xb, 4e-6);
  }
}

TEST(CsmcStepperDq, QuarterToothPitchMovesAToQ) {
  // N_r phi = pi/2: the a axis is the -q axis, the b axis is the d axis.
  float xd, xq;
  mc_stepper_ab_to_dq_f32(1.0f, 0.0f, static_cast<float>(kPi / 2.0 / 50.0), 50u, &xd, &xq);
  EXPECT_NEAR(xd, 0.0f, 1e-6);  // cos(pi/2) in float: 1e-7 class
  EXPECT_NEAR(xq, -1.0f, 1e-6);
}

// -------------------------------------------------------------- linalg
// exp(A) in double by Taylor with scaling and squaring (reference).
std::vector<double> expm_ref(const std::vector<double>& a, int n) {
  double norm = 0.0;
  for (int i = 0; i < n; ++i) {
    double r = 0.0;
    for (int j = 0; j < n; ++j) r += std::abs(a[static_cast<size_t>(i * n + j)]);
    norm = std::max(norm, r);
  }
  int s = 0;
  while (norm > 1e-3) {
    norm *= 0.5;
    ++s;
  }
  const double sc = std::ldexp(1.0, -s);
  std::vector<double> m(a.size()), term(a.size(), 0.0), sum(a.size(), 0.0), tmp(a.size());
  for (size_t i = 0; i < a.size(); ++i) m[i] = a[i] * sc;
  for (int i = 0; i < n; ++i)
    term[static_cast<size_t>(i * n + i)] = sum[static_cast<size_t>(i * n + i)] = 1.0;
  for (int k = 1; k < 12; ++k) {
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        double acc = 0.0;
        for (int l = 0; l < n; ++l)
          acc += term[static_cast<size_t>(i * n + l)] * m[static_cast<size_t>(l * n + j)];
        tmp[static_cast<size_t>(i * n + j)] = acc / k;
      }
    term = tmp;
    for (size_t i = 0; i < sum.size(); ++i) sum[i] += term[i];
  }
  for (int q = 0; q < s; ++q) {
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        double acc = 0.0;
        for (int l = 0; l < n; ++l)
          acc += sum[static_cast<size_t>(i * n + l)] * sum[static_cast<size_t>(l * n + j)];
        tmp[static_cast<size_t>(i * n + j)] = acc;
      }
    sum = tmp;
  }
  return sum;
}

TEST(CsmcLinalg, ExpmOfRotationIsCosSin) {
  const float w = 2.5f;
  const float a[4] = {0.0f, w, -w, 0.0f};
  float e[4];
  ASSERT_TRUE(mc_linalg_expm_f32(a, 2u, e));
  // norm 2.5 -> 3 squarings; float rounding ~1e-7 doubled 3 times: 1e-6.
  EXPECT_NEAR(e[0], std::cos(2.5), 1e-6);
  EXPECT_NEAR(e[1], std::sin(2.5), 1e-6);
  EXPECT_NEAR(e[2], -std::sin(2.5), 1e-6);
  EXPECT_NEAR(e[3], std::cos(2.5), 1e-6);
}

TEST(CsmcLinalg, ExpmOfObserverMatrixAtDtEqualEps) {
  // The HGO generator at dt = eps (h = 1): norm 100, 8 squarings.
  const std::vector<double> a = {-17, 1, 0, -80, 0, 1, -100, 0, 0};
  float af[9], e[9];
  for (int i = 0; i < 9; ++i) af[i] = static_cast<float>(a[static_cast<size_t>(i)]);
  ASSERT_TRUE(mc_linalg_expm_f32(af, 3u, e));
  const auto r = expm_ref(a, 3);
  // Entries are O(1e-3..1); 8 squarings of float rounding: the header
  // states ~2^8 * 1e-7 relative to the largest entry (~0.5): 2e-5.
  for (int i = 0; i < 9; ++i) EXPECT_NEAR(e[i], r[static_cast<size_t>(i)], 2e-5) << i;
}

TEST(CsmcLinalg, ExpmRejectsBadInput) {
  const float nan_m[1] = {std::nanf("")};
  const float huge[1] = {1e30f};
  float e[1] = {7.0f};
  EXPECT_FALSE(mc_linalg_expm_f32(nan_m, 1u, e));
  EXPECT_FALSE(mc_linalg_expm_f32(huge, 1u, e));
  EXPECT_FALSE(mc_linalg_expm_f32(huge, 7u, e));
  EXPECT_EQ(e[0], 7.0f);  // not written
}

TEST(CsmcLinalg, HurwitzRouth) {
  const float p3[3] = {100.0f, 80.0f, 17.0f};  // (l+2)(l+5)(l+10)
  EXPECT_TRUE(mc_linalg_hurwitz_f32(p3, 3u));
  const float p3b[3] = {2000.0f, 80.0f, 17.0f};  // a1 a2 < a3: unstable
  EXPECT_FALSE(mc_linalg_hurwitz_f32(p3b, 3u));
  const float osc[2] = {4.0f, 0.0f};  // l^2 + 4: on the axis
  EXPECT_FALSE(mc_linalg_hurwitz_f32(osc, 2u));
  const float p5[5] = {50.0f, 120.0f, 109.0f, 49.0f, 11.0f};
  EXPECT_TRUE(mc_linalg_hurwitz_f32(p5, 5u));
  const float neg[1] = {-1.0f};
  EXPECT_FALSE(mc_linalg_hurwitz_f32(neg, 1u));
}

TEST(CsmcLinalg, PolyFromPaperPoles) {
  const float re[5] = {-1, -2, -2, -3, -3};
  const float im[5] = {0, 1, -1, 1, -1};
  float p[5];
  ASSERT_TRUE(mc_linalg_poly_from_roots_f32(re, im, 5u, p));
  // (l+1)(l^2+4l+5)(l^2+6l+10) = l^5+11l^4+49l^3+109l^2+120l+50, exact in float.
  const float want[5] = {50, 120, 109, 49, 11};
  for (int i = 0; i < 5; ++i) EXPECT_EQ(p[i], want[i]) << i;
  const float im_bad[5] = {0, 1, 1, 1, -1};  // not a conjugate pair
  EXPECT_FALSE(mc_linalg_poly_from_roots_f32(re, im_bad, 5u, p));
}

// -------------------------------------------- servocompensator / integrator
TEST(CsmcCsvc, IntegratorIsExactInsideBoundaryLayer) {
  mc_csvc_f32_cfg_t c{};
  ASSERT_EQ(mc_csvc_f32_integrator(100.0f, &c.model), MC_CSVC_ERR_NONE);
  c.mu = 50.0f;
  c.dt_s = 1e-4f;
  mc_csvc_f32_t st;
  ASSERT_EQ(mc_csvc_f32_init(&st, &c), MC_CSVC_ERR_NONE);
  // Inside the layer: sigma[k+1] = sigma[k] + dt * e (pure integral of e).
  double sig = 0.0;
  for (int k = 0; k < 100; ++k) {
    const float e = 0.3f;
    const float s = mc_csvc_f32_term(&st) + e;  // k0 sigma + e
    ASSERT_LE(std::abs(s), 50.0f);
    mc_csvc_f32_update(&st, s);
    sig += 1e-4 * 0.3;
  }
  float sigma[MC_CSVC_MAX_ORDER];
  mc_csvc_f32_sigma(&st, sigma);
  // float accumulation of 100 steps of 3e-5: relative 1e-6.
  EXPECT_NEAR(sigma[0], sig, 1e-6 * sig + 1e-9);
}

TEST(CsmcCsvc, OutsideBoundaryLayerSigmaStaysOrderMu) {
  mc_csvc_f32_cfg_t c{};
  ASSERT_EQ(mc_csvc_f32_integrator(20.0f, &c.model), MC_CSVC_ERR_NONE);
  c.mu = 0.1f;
  c.dt_s = 1e-4f;
  mc_csvc_f32_t st;
  ASSERT_EQ(mc_csvc_f32_init(&st, &c), MC_CSVC_ERR_NONE);
  for (int k = 0; k < 20000; ++k) mc_csvc_f32_update(&st, 1e3f);  // far outside
  float sigma[MC_CSVC_MAX_ORDER];
  mc_csvc_f32_sigma(&st, sigma);
  // sigma' = -k0 sigma + mu -> mu/k0 = 5e-3 (2 s = 40 time constants).
  EXPECT_NEAR(sigma[0], 0.1 / 20.0, 1e-6);
}

TEST(CsmcCsvc, PlacementOfPaperServocompensators) {
  for (double w0 : {2.0, 5.0}) {
    const float w02 = static_cast<float>(w0 * w0);
    const float c2[3] = {0.0f, -w02, 0.0f};
    const float re2[3] = {-1, -2, -2}, im2[3] = {0, 1, -1};
    mc_csvc_f32_cfg_t c{};
    ASSERT_EQ(mc_csvc_f32_place(3u, c2, re2, im2, &c.model), MC_CSVC_ERR_NONE);
    // (l+1)(l^2+4l+5) = l^3+5l^2+9l+5 -> K0 = c + p = (5, 9 - w0^2, 5).
    EXPECT_FLOAT_EQ(c.model.k0[0], 5.0f);
    EXPECT_FLOAT_EQ(c.model.k0[1], 9.0f - w02);
    EXPECT_FLOAT_EQ(c.model.k0[2], 5.0f);
    c.mu = 50.0f;
    c.dt_s = 1e-4f;
    mc_csvc_f32_t st;
    ASSERT_EQ(mc_csvc_f32_init(&st, &c), MC_CSVC_ERR_NONE);
    // exp(S2 dt) has eigenvalues 1, e^(+-j w0 dt): trace 1 + 2 cos(w0 dt).
    // The internal model must be exact: float entries near 1, rounding 1e-7.
    const double tr = st.phi[0] + st.phi[4] + st.phi[8];
    EXPECT_NEAR(tr, 1.0 + 2.0 * std::cos(w0 * 1e-4), 3e-7);
    // S1: l (l^2 + w0^2)(l^2 + 4 w0^2) (the matrix of the paper, c3 = -5 w0^2).
    const float c1[5] = {0.0f, -4.0f * w02 * w02, 0.0f, -5.0f * w02, 0.0f};
    const float re1[5] = {-1, -2, -2, -3, -3}, im1[5] = {0, 1, -1, 1, -1};
    mc_csvc_f32_cfg_t c5{};
    ASSERT_EQ(mc_csvc_f32_place(5u, c1, re1, im1, &c5.model), MC_CSVC_ERR_NONE);
    c5.mu = 0.1f;
    c5.dt_s = 1e-4f;
    mc_csvc_f32_t st5;
    ASSERT_EQ(mc_csvc_f32_init(&st5, &c5), MC_CSVC_ERR_NONE);
    double tr5 = 0.0;
    for (int i = 0; i < 5; ++i) tr5 += st5.phi[i * 5 + i];
    EXPECT_NEAR(tr5, 1.0 + 2.0 * std::cos(w0 * 1e-4) + 2.0 * std::cos(2.0 * w0 * 1e-4), 1e-6);
  }
}

// The paper's internal models (and the conditional integrator) run in the
// modal realisation; the others in the dense one. Both realise the same
// exp(S dt), Gam: over a run crossing the boundary layer both ways their
// K0 sigma and sigma must agree to rounding.
struct CsvcModel {
  uint32_t n;
  float c[5];
  float re[5];
  float im[5];
  uint32_t real;
};

// exp(A) in double (Taylor to degree 20; the arguments here have norm < 0.1,
// so the truncation is far below double rounding).
std::vector<double> expm_d(const std::vector<double>& a, size_t n) {
  std::vector<double> r(n * n, 0.0), term(n * n, 0.0), nxt(n * n);
  for (size_t i = 0; i < n; ++i) r[i * n + i] = term[i * n + i] = 1.0;
  for (int k = 1; k <= 20; ++k) {
    for (size_t i = 0; i < n; ++i)
      for (size_t j = 0; j < n; ++j) {
        double acc = 0.0;
        for (size_t l = 0; l < n; ++l) acc += term[i * n + l] * a[l * n + j];
        nxt[i * n + j] = acc / k;
      }
    term = nxt;
    for (size_t i = 0; i < n * n; ++i) r[i] += term[i];
  }
  return r;
}

// Runs the modal and the dense realisation and a double-precision exact
// discretisation side by side (each closes its own loop s = K0 sigma + s*),
// returns the largest error of each against the double one, relative to the
// largest |sigma_i| and |K0 sigma|.
void run_modal_vs_dense(const CsvcModel& m, float mu, float dt, int steps, double err_term[2],
                        double err_sigma[2]) {
  mc_csvc_f32_cfg_t c{};
  ASSERT_EQ(mc_csvc_f32_place(m.n, m.c, m.re, m.im, &c.model), MC_CSVC_ERR_NONE);
  c.mu = mu;
  c.dt_s = dt;
  mc_csvc_f32_t fast;
  ASSERT_EQ(mc_csvc_f32_init(&fast, &c), MC_CSVC_ERR_NONE);
  ASSERT_EQ(fast.real, m.real);
  mc_csvc_f32_t dense = fast;
  mc_csvc_f32_force_dense(&dense);
  const size_t n = m.n, na = n + 1;
  std::vector<double> aug(na * na, 0.0);
  for (size_t i = 0; i + 1 < n; ++i) aug[i * na + i + 1] = dt;
  for (size_t j = 0; j < n; ++j) aug[(n - 1) * na + j] = static_cast<double>(c.model.c[j]) * dt;
  aug[(n - 1) * na + n] = dt;
  const std::vector<double> e = expm_d(aug, na);
  std::vector<double> sref(n, 0.0), nx(n);
  std::mt19937 g(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  double tmax = 0.0, smax = 0.0;
  for (int q = 0; q < 2; ++q) err_term[q] = err_sigma[q] = 0.0;
  for (int k = 0; k < steps; ++k) {
    // s* = a sinusoid at the model's lowest frequency plus a constant and
    // noise, with bursts far outside the boundary layer.
    const double t = k * static_cast<double>(dt);
    float sstar =
        static_cast<float>(0.3 * mu * std::sin(2.0 * kPi * t) + 0.2 * mu) + 0.1f * mu * u(g);
    if ((k / 2000) % 5 == 4) sstar *= 30.0f;
    double tr = 0.0;
    for (size_t i = 0; i < n; ++i) tr += static_cast<double>(c.model.k0[i]) * sref[i];
    const float tf = mc_csvc_f32_term(&fast);
    const float td = mc_csvc_f32_term(&dense);
    err_term[0] = std::max(err_term[0], std::abs(tf - tr));
    err_term[1] = std::max(err_term[1], std::abs(td - tr));
    tmax = std::max(tmax, std::abs(tr));
    mc_csvc_f32_update(&fast, tf + sstar);
    mc_csvc_f32_update(&dense, td + sstar);
    const double sr = tr + sstar;
    const double v = std::min(std::max(sr, -static_cast<double>(mu)), static_cast<double>(mu)) - tr;
    for (size_t i = 0; i < n; ++i) {
      double acc = e[i * na + n] * v;
      for (size_t j = 0; j < n; ++j) acc += e[i * na + j] * sref[j];
      nx[i] = acc;
    }
    sref = nx;
    float sf[MC_CSVC_MAX_ORDER], sd[MC_CSVC_MAX_ORDER];
    mc_csvc_f32_sigma(&fast, sf);
    mc_csvc_f32_sigma(&dense, sd);
    for (size_t i = 0; i < n; ++i) {
      err_sigma[0] = std::max(err_sigma[0], std::abs(sf[i] - sref[i]));
      err_sigma[1] = std::max(err_sigma[1], std::abs(sd[i] - sref[i]));
      smax = std::max(smax, std::abs(sref[i]));
    }
  }
  for (int q = 0; q < 2; ++q) {
    err_term[q] /= tmax;
    err_sigma[q] /= smax;
  }
}

TEST(CsmcCsvc, ModalRealisationAgreesWithDense) {
  const float w02 = static_cast<float>(4.0 * kPi * kPi);
  const CsvcModel s1{5u,
                     {0.0f, -4.0f * w02 * w02, 0.0f, -5.0f * w02, 0.0f},
                     {-1, -2, -2, -3, -3},
                     {0, 1, -1, 1, -1},
                     MC_CSVC_REAL_MODAL2};
  const CsvcModel s2{3u, {0.0f, -w02, 0.0f}, {-1, -2, -2}, {0, 1, -1}, MC_CSVC_REAL_MODAL1};
  const CsvcModel integ{1u, {0.0f}, {-20.0f}, {0.0f}, MC_CSVC_REAL_MODAL0};
  for (const CsvcModel* m : {&s1, &s2, &integ}) {
    double et[2], es[2];
    run_modal_vs_dense(*m, 0.1f, 1.0e-5f, 200000, et, es);
    // Inside the boundary layer sigma integrates s* open loop (eigenvalues
    // of S on the imaginary axis), so float rounding accumulates over the
    // 2e5 steps instead of decaying. Measured against the double-precision
    // exact discretisation: modal 1e-5..2e-5 (n = 5, 3) and 1.4e-4 (n = 1,
    // a plain float sum of 2e5 terms); dense 1e-4..2e-4 (its float Phi
    // entries near 1 carry the rounding of the matrix exponential).
    // Bounds: 2.5x the measured modal error; and modal no worse than dense.
    const double bound = (m->n == 1u) ? 3.5e-4 : 5e-5;
    EXPECT_LT(et[0], bound) << m->n;
    EXPECT_LT(es[0], bound) << m->n;
    EXPECT_LE(et[0], et[1]) << m->n;
    EXPECT_LE(es[0], es[1]) << m->n;
  }
}

TEST(CsmcCsvc, OtherModelsUseTheDenseRealisation) {
  mc_csvc_f32_cfg_t c{};
  c.mu = 1.0f;
  c.dt_s = 1e-4f;
  mc_csvc_f32_t st;
  // double integrator (Jordan block at 0), a real eigenvalue, an even order
  const CsvcModel others[] = {
      {2u, {0.0f, 0.0f}, {-1, -2}, {0, 0}, MC_CSVC_REAL_DENSE},
      {1u, {-3.0f}, {-5}, {0}, MC_CSVC_REAL_DENSE},
      {2u, {-4.0f, 0.0f}, {-1, -1}, {1, -1}, MC_CSVC_REAL_DENSE},
      {3u, {0.0f, 4.0f, 0.0f}, {-1, -2, -3}, {0, 0, 0}, MC_CSVC_REAL_DENSE},
  };
  for (const CsvcModel& m : others) {
    ASSERT_EQ(mc_csvc_f32_place(m.n, m.c, m.re, m.im, &c.model), MC_CSVC_ERR_NONE);
    ASSERT_EQ(mc_csvc_f32_init(&st, &c), MC_CSVC_ERR_NONE);
    EXPECT_EQ(st.real, MC_CSVC_REAL_DENSE) << m.n;
    // and it still integrates: a constant s* inside the layer drives K0 sigma
    for (int k = 0; k < 10; ++k) mc_csvc_f32_update(&st, mc_csvc_f32_term(&st) + 0.5f);
    EXPECT_NE(mc_csvc_f32_term(&st), 0.0f);
  }
}

TEST(CsmcCsvc, RejectsBadConfigWithoutTouchingState) {
  mc_csvc_f32_t st;
  std::memset(&st, 0xA5, sizeof st);
  mc_csvc_f32_t before = st;
  mc_csvc_f32_cfg_t c{};
  c.model.order = 3u;
  c.model.c[1] = -4.0f;
  c.model.k0[0] = 5.0f;    // K0 = (5, 0, 5): l^3 + 5 l^2 + 4 l + 5 -> 5*4 < 5? 20 > 5 ok
  c.model.k0[1] = -10.0f;  // makes l coefficient -6: not Hurwitz
  c.model.k0[2] = 5.0f;
  c.mu = 1.0f;
  c.dt_s = 1e-4f;
  EXPECT_EQ(mc_csvc_f32_init(&st, &c), MC_CSVC_ERR_NOT_HURWITZ);
  c.model.k0[1] = 5.0f;
  c.mu = 0.0f;
  EXPECT_EQ(mc_csvc_f32_init(&st, &c), MC_CSVC_ERR_MU);
  c.mu = 1.0f;
  c.dt_s = 1.0f;  // dt * ||S - J K0|| = 1 * 15 > 0.1
  EXPECT_EQ(mc_csvc_f32_init(&st, &c), MC_CSVC_ERR_DT);
  c.model.order = 6u;
  EXPECT_EQ(mc_csvc_f32_init(&st, &c), MC_CSVC_ERR_ORDER);
  EXPECT_EQ(std::memcmp(&st, &before, sizeof st), 0);
  mc_csvc_f32_model_t m{};
  EXPECT_EQ(mc_csvc_f32_integrator(-1.0f, &m), MC_CSVC_ERR_MODEL);
  const float cc[2] = {0, 0}, re[2] = {-1, 1}, im[2] = {0, 0};
  EXPECT_EQ(mc_csvc_f32_place(2u, cc, re, im, &m), MC_CSVC_ERR_POLES);
}

// ------------------------------------------------------ high-gain observer
mc_hgo_f32_cfg_t hgo_cfg(double eps, double dt, uint32_t order) {
  return mc_hgo_f32_cfg_t{17.0f, 80.0f, 100.0f, static_cast<float>(eps), static_cast<float>(dt),
                          order};
}

// Continuous observer (6) in scaled form, integrated by RK4 with step h
// from t0 to t1 with input y(t).
template <class Y>
void hgo_ref_advance(double eps, double* eta, double t0, double t1, int n, Y y) {
  const double h = (t1 - t0) / n;
  auto f = [&](double t, const double* e, double* d) {
    const double inn = y(t) - e[0];
    d[0] = (e[1] + 17.0 * inn) / eps;
    d[1] = (e[2] + 80.0 * inn) / eps;
    d[2] = (100.0 * inn) / eps;
  };
  for (int k = 0; k < n; ++k) {
    const double t = t0 + k * h;
    double k1[3], k2[3], k3[3], k4[3], tmp[3];
    f(t, eta, k1);
    for (int i = 0; i < 3; ++i) tmp[i] = eta[i] + 0.5 * h * k1[i];
    f(t + 0.5 * h, tmp, k2);
    for (int i = 0; i < 3; ++i) tmp[i] = eta[i] + 0.5 * h * k2[i];
    f(t + 0.5 * h, tmp, k3);
    for (int i = 0; i < 3; ++i) tmp[i] = eta[i] + h * k3[i];
    f(t + h, tmp, k4);
    for (int i = 0; i < 3; ++i) eta[i] += h / 6.0 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
  }
}

TEST(CsmcHgo, ForwardEulerDivergesAtTenKhzKernelDoesNot) {
  // eps = 1e-4, dt = 1e-4 (10 kHz): the Euler map I + dt A has eigenvalues
  // 1 - (2, 5, 10) = -1, -4, -9.
  const double eps = 1e-4, dt = 1e-4;
  double z[3] = {0, 0, 0};
  mc_hgo_f32_t st;
  ASSERT_EQ(mc_hgo_f32_init(&st, nullptr), MC_HGO_ERR_NULL);
  const mc_hgo_f32_cfg_t c = hgo_cfg(eps, dt, 2u);
  ASSERT_EQ(mc_hgo_f32_init(&st, &c), MC_HGO_ERR_NONE);
  mc_hgo_f32_est_t est{};
  for (int k = 0; k < 200; ++k) {
    const double y = 0.01;  // a constant measured error
    const double inn = y - z[0];
    const double d0 = z[1] + 17.0 * inn / eps, d1 = z[2] + 80.0 * inn / (eps * eps),
                 d2 = 100.0 * inn / (eps * eps * eps);
    z[0] += dt * d0;
    z[1] += dt * d1;
    z[2] += dt * d2;
    mc_hgo_f32_step(&st, static_cast<float>(y), &est);
  }
  EXPECT_GT(std::abs(z[0]), 1e10);  // Euler: |9|^200 growth
  mc_hgo_f32_step(&st, 0.01f, &est);
  // Kernel: converged to the constant (z1 = y, derivatives 0). Rounding of
  // y (ulp 1e-9) seen through 1/eps and 1/eps^2: z2 ~1e-4, z3 ~ 1.
  EXPECT_NEAR(est.z1, 0.01f, 1e-8);
  EXPECT_NEAR(est.z2, 0.0f, 1e-3);
  EXPECT_NEAR(est.z3, 0.0f, 5.0);
}

TEST(CsmcHgo, ZeroOrderHoldVariantIsTheExactDiscretisationOfTheHeldInput) {
  // input_order 0: the kernel equals the continuous observer driven by the
  // sampled-and-held y (fine RK4 reference, 200 sub-steps per period).
  const double eps = 1e-4, dt = 1e-4;
  const mc_hgo_f32_cfg_t c = hgo_cfg(eps, dt, 0u);
  mc_hgo_f32_t st;
  ASSERT_EQ(mc_hgo_f32_init(&st, &c), MC_HGO_ERR_NONE);
  double eta[3] = {0, 0, 0};
  auto ysig = [](double t) { return 0.05 * std::sin(7.0 * t) + 0.02 * t; };
  mc_hgo_f32_est_t est{};
  double max_e2 = 0.0, max_e3 = 0.0;
  for (int k = 0; k < 300; ++k) {
    const double tk = k * dt;
    const float yk = static_cast<float>(ysig(tk));
    mc_hgo_f32_step(&st, yk, &est);
    if (k > 50) {
      max_e2 = std::max(max_e2, std::abs(est.z2 - eta[1] / eps));
      max_e3 = std::max(max_e3, std::abs(est.z3 - eta[2] / (eps * eps)));
    }
    const double yh = yk;
    hgo_ref_advance(eps, eta, tk, tk + dt, 200, [yh](double) { return yh; });
  }
  // float rounding of eta (~1e-9 absolute) divided by eps and eps^2:
  // 1e-4 rad/s and ~2 rad/s^2 (z3 itself reaches ~1e3 here).
  EXPECT_LT(max_e2, 2e-3);
  EXPECT_LT(max_e3, 5.0);
}

TEST(CsmcHgo, ParabolicInputModelRecoversTheContinuousObserver) {
  // y(t) smooth, dt = eps / 10 (100 kHz, eps = 1e-4). Compare with the
  // continuous observer driven by the true y (fine RK4), and with the true
  // derivatives. ZOH is shown biased by ~ y' dt / eps^2 in z3.
  const double eps = 1e-4, dt = 1e-5;
  auto ysig = [](double t) { return 0.3 * std::sin(3.0 * t); };
  mc_hgo_f32_t q, z;
  const mc_hgo_f32_cfg_t cq = hgo_cfg(eps, dt, 2u), cz = hgo_cfg(eps, dt, 0u);
  ASSERT_EQ(mc_hgo_f32_init(&q, &cq), MC_HGO_ERR_NONE);
  ASSERT_EQ(mc_hgo_f32_init(&z, &cz), MC_HGO_ERR_NONE);
  double eta[3] = {0, 0, 0};
  mc_hgo_f32_est_t eq{}, ez{};
  double q_e2 = 0, q_e3 = 0, z_e3_min = 1e30;
  for (int k = 0; k < 20000; ++k) {
    const double tk = k * dt;
    mc_hgo_f32_step(&q, static_cast<float>(ysig(tk)), &eq);
    mc_hgo_f32_step(&z, static_cast<float>(ysig(tk)), &ez);
    if (k > 1000) {
      q_e2 = std::max(q_e2, std::abs(eq.z2 - eta[1] / eps));
      q_e3 = std::max(q_e3, std::abs(eq.z3 - eta[2] / (eps * eps)));
      const double dy = 0.9 * std::cos(3.0 * tk);
      if (std::abs(dy) > 0.5) z_e3_min = std::min(z_e3_min, std::abs(ez.z3 - eta[2] / (eps * eps)));
    }
    hgo_ref_advance(eps, eta, tk, tk + dt, 10, ysig);
  }
  // Float rounding of y (|y| <= 0.3: 1.5e-8) amplified by ~alpha/eps and
  // ~alpha3/eps^2 through the second difference: 2e-2 rad/s, ~40 rad/s^2
  // (measured 8e-3 and 17); the true z3 swings by 2.7 rad/s^2, so these
  // bound rounding noise, not a bias.
  EXPECT_LT(q_e2, 2e-2);
  EXPECT_LT(q_e3, 40.0);
  // ZOH: bias ~ y' dt / eps^2 ~ 0.5 * 1e-5 / 1e-8 = 500 rad/s^2 where |y'| > 0.5.
  EXPECT_GT(z_e3_min, 200.0);
}

TEST(CsmcHgo, RejectsBadConfigAndNanInput) {
  mc_hgo_f32_t st;
  std::memset(&st, 0x5A, sizeof st);
  const mc_hgo_f32_t before = st;
  mc_hgo_f32_cfg_t c = hgo_cfg(1e-4, 1e-4, 2u);
  c.alpha3 = 2000.0f;  // alpha1 alpha2 = 1360 < alpha3: not Hurwitz
  EXPECT_EQ(mc_hgo_f32_init(&st, &c), MC_HGO_ERR_ALPHA);
  c = hgo_cfg(0.0, 1e-4, 2u);
  EXPECT_EQ(mc_hgo_f32_init(&st, &c), MC_HGO_ERR_EPS);
  c = hgo_cfg(1e-4, -1.0, 3u);
  EXPECT_EQ(mc_hgo_f32_init(&st, &c), MC_HGO_ERR_DT | MC_HGO_ERR_ORDER);
  EXPECT_EQ(std::memcmp(&st, &before, sizeof st), 0);
  c = hgo_cfg(1e-4, 1e-4, 2u);
  ASSERT_EQ(mc_hgo_f32_init(&st, &c), MC_HGO_ERR_NONE);
  mc_hgo_f32_est_t e{};
  EXPECT_EQ(mc_hgo_f32_step(&st, 0.1f, &e), MC_HGO_ERR_NONE);
  const float eta0 = st.z[0];
  // Refused: the bit returned and made sticky, the current estimate written.
  EXPECT_EQ(mc_hgo_f32_step(&st, std::nanf(""), &e), MC_HGO_ERR_NAN_INPUT);
  EXPECT_EQ(st.flags, MC_HGO_ERR_NAN_INPUT);
  EXPECT_EQ(st.z[0], eta0);
  EXPECT_EQ(e.z1, eta0);
  // NULL state or estimate: MC_HGO_ERR_NULL, nothing written.
  const mc_hgo_f32_t kept = st;
  mc_hgo_f32_est_t e_null{42.0f, 42.0f, 42.0f};
  EXPECT_EQ(mc_hgo_f32_step(nullptr, 0.1f, &e_null), MC_HGO_ERR_NULL);
  EXPECT_EQ(e_null.z1, 42.0f);
  EXPECT_EQ(mc_hgo_f32_step(&st, 0.1f, nullptr), MC_HGO_ERR_NULL);
  EXPECT_EQ(std::memcmp(&st, &kept, sizeof st), 0);
  EXPECT_EQ(mc_hgo_f32_reset(&st, 0.0f, std::nanf(""), 0.0f), MC_HGO_ERR_NAN_INPUT);
  EXPECT_EQ(mc_hgo_f32_reset(&st, 0.0f, 0.0f, 0.0f), MC_HGO_ERR_NONE);
  EXPECT_EQ(st.flags, MC_HGO_ERR_NONE);
}

// ---------------------------------------------------------- the CSMC law
mc_csmc_f32_cfg_t paper_cfg(mc_csmc_law_t law, mc_csmc_sw_t sw, bool integ) {
  mc_csmc_f32_cfg_t c{};
  c.law = law;
  c.sw = sw;
  c.k1_per_s2 = 7.5e4f;
  c.k2_per_s = 550.0f;
  c.mu1_a = 0.1f;
  c.mu2_rad_s2 = 50.0f;
  if (integ) {
    EXPECT_EQ(mc_csvc_f32_integrator(20.0f, &c.sigma1), MC_CSVC_ERR_NONE);
    EXPECT_EQ(mc_csvc_f32_integrator(100.0f, &c.sigma2), MC_CSVC_ERR_NONE);
  }
  c.m1_v = 50.0f;
  c.m2_v = 50.0f;
  c.model = mc_csmc_f32_model_t{0.1349f,
                                4.1295e-4f,
                                0.0013f,
                                50u,
                                0.2f,
                                20.0f,
                                19.0f,
                                21.0f,
                                0.035f,
                                0.030f,
                                0.040f,
                                2.1f * 20.0f * 0.1f * 0.040f,
                                2.1f * 100.0f * 50.0f * 0.040f};
  c.v_limit_v = 1e4f;
  c.dt_s = 1e-4f;
  return c;
}

TEST(CsmcLaw, ConstLawIsMinusMSat) {
  mc_csmc_f32_t st;
  const mc_csmc_f32_cfg_t c = paper_cfg(MC_CSMC_LAW_CONST, MC_CSMC_SW_SAT, false);
  ASSERT_EQ(mc_csmc_f32_init(&st, &c), MC_CSMC_ERR_NONE);
  mc_csmc_f32_in_t in{};
  in.e1_a = 0.05f;    // s1 = 0.05 -> sat = 0.5 -> u1 = -25
  in.e2_rad = 1e-4f;  // s2 = 7.5 + 550*0.01 + 2 = 15 -> u2 = -15
  in.de2_rad_s = 0.01f;
  in.dde2_rad_s2 = 2.0f;
  mc_csmc_f32_out_t o{};
  mc_csmc_f32_step(&st, &in, &o);
  // float products of values with 7 digits: relative 1e-6.
  EXPECT_NEAR(o.v_d_v, -25.0f, 1e-4);
  EXPECT_NEAR(o.s2_rad_s2, 15.0f, 1e-4);
  EXPECT_NEAR(o.v_q_v, -15.0f, 1e-4);
  in.e2_rad = -1.0f;  // far outside: u2 = +M
  mc_csmc_f32_step(&st, &in, &o);
  EXPECT_EQ(o.v_q_v, 50.0f);
}

TEST(CsmcLaw, IdealSmcSwitchesAtTheSurface) {
  mc_csmc_f32_t st;
  const mc_csmc_f32_cfg_t c = paper_cfg(MC_CSMC_LAW_CONST, MC_CSMC_SW_SGN, false);
  ASSERT_EQ(mc_csmc_f32_init(&st, &c), MC_CSMC_ERR_NONE);
  mc_csmc_f32_in_t in{};
  mc_csmc_f32_out_t o{};
  in.dde2_rad_s2 = 1e-3f;  // s2 tiny positive: full -M (sat would give -2e-5*50)
  in.e1_a = -1e-6f;
  mc_csmc_f32_step(&st, &in, &o);
  EXPECT_EQ(o.v_q_v, -50.0f);
  EXPECT_EQ(o.v_d_v, 50.0f);
  in.dde2_rad_s2 = 0.0f;
  in.e1_a = 0.0f;
  mc_csmc_f32_step(&st, &in, &o);
  EXPECT_EQ(o.v_q_v, 0.0f);  // sgn(0) = 0
}

TEST(CsmcLaw, ModelLawMatchesFormulaAndIsRobustOverTheParameterBox) {
  // The law (5) with the re-derived beta functions: for random states with
  // the sliding variables outside the boundary layer, the true s_i' (with R,
  // L anywhere in the box, the conditional-integrator term at its bound
  // 2 k0 mu) has the sign opposite to s_i: s s' < 0, the reaching condition
  // the beta functions must guarantee.
  mc_csmc_f32_t st;
  const mc_csmc_f32_cfg_t c = paper_cfg(MC_CSMC_LAW_MODEL, MC_CSMC_SW_SAT, false);
  ASSERT_EQ(mc_csmc_f32_init(&st, &c), MC_CSMC_ERR_NONE);
  const double Km = 0.1349, J = 4.1295e-4, B = 0.0013, Nr = 50, tl = 0.2;
  const double k3 = Km / J, k4 = B / J, d0 = tl / J, k1 = 7.5e4, k2 = 550.0;
  std::mt19937 g(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int checked = 0;
  for (int it = 0; it < 4000; ++it) {
    const double x1 = 2 * u(g), x2 = 3 * u(g), x3 = 20 * u(g), e2 = 0.05 * u(g);
    const double de2 = x3;  // phi_d constant
    const double dde2 = k3 * x2 - k4 * x3 - d0;
    mc_csmc_f32_in_t in{};
    in.e1_a = static_cast<float>(x1);
    in.e2_rad = static_cast<float>(e2);
    in.de2_rad_s = static_cast<float>(de2);
    in.dde2_rad_s2 = static_cast<float>(dde2);
    in.i_d_a = static_cast<float>(x1);
    in.i_q_a = static_cast<float>(x2);
    in.omega_m_rad_s = static_cast<float>(x3);
    mc_csmc_f32_out_t o{};
    mc_csmc_f32_reset(&st);
    mc_csmc_f32_step(&st, &in, &o);
    const double s1 = x1, s2 = k1 * e2 + k2 * de2 + dde2;
    // Reference u from the formula in double.
    const double G = k1 * de2 + k2 * dde2 - k4 * (k3 * x2 - k4 * x3 - d0) - k3 * Nr * x1 * x3;
    const double sat1 = std::max(-1.0, std::min(1.0, s1 / 0.1));
    const double sat2 = std::max(-1.0, std::min(1.0, s2 / 50.0));
    const double u1 = 20.0 * x1 - 0.035 * Nr * x2 * x3 -
                      (1.0 * std::abs(x1) + 0.005 * std::abs(Nr * x2 * x3) + 0.168) * sat1;
    const double u2 = 20.0 * x2 + Km * x3 - 0.035 / k3 * G -
                      (1.0 * std::abs(x2) + (0.005 * std::abs(G) + 420.0) / k3) * sat2;
    // float evaluation of terms up to ~1e3 V: relative 1e-6 of the largest term.
    const double tol1 = 1e-5 * (std::abs(u1) + 20.0 * std::abs(x1) + 100.0);
    const double tol2 = 1e-5 * (std::abs(u2) + 0.035 / k3 * std::abs(G) + 100.0);
    ASSERT_NEAR(o.v_d_v, u1, tol1);
    ASSERT_NEAR(o.v_q_v, u2, tol2);
    if (std::abs(s1) <= 0.1 || std::abs(s2) <= 50.0) continue;
    ++checked;
    for (double R : {19.0, 21.0}) {
      for (double L : {0.030, 0.040}) {
        // s1' = k0 (..) + F1 + u1/L, F1 = -R/L x1 + Nr x2 x3; worst k0 term 2 k0 mu.
        const double f1 = -R / L * x1 + Nr * x2 * x3 + o.v_d_v / L;
        const double ds1 = f1 + (s1 > 0 ? 2.0 : -2.0) * 20.0 * 0.1;
        EXPECT_LT(s1 * ds1, 0.0) << "R " << R << " L " << L;
        const double f2 = G - k3 * R / L * x2 - k3 * Km / L * x3 + k3 / L * o.v_q_v;
        const double ds2 = f2 + (s2 > 0 ? 2.0 : -2.0) * 100.0 * 50.0;
        EXPECT_LT(s2 * ds2, 0.0) << "R " << R << " L " << L;
      }
    }
  }
  EXPECT_GT(checked, 1000);
}

TEST(CsmcLaw, ConditionalIntegratorEntersTheSurface) {
  mc_csmc_f32_t st;
  const mc_csmc_f32_cfg_t c = paper_cfg(MC_CSMC_LAW_CONST, MC_CSMC_SW_SAT, true);
  ASSERT_EQ(mc_csmc_f32_init(&st, &c), MC_CSMC_ERR_NONE);
  mc_csmc_f32_in_t in{};
  in.dde2_rad_s2 = 10.0f;  // inside the layer: sigma2 integrates s* = 10
  mc_csmc_f32_out_t o{};
  for (int k = 0; k < 11; ++k) mc_csmc_f32_step(&st, &in, &o);
  // 10 updates of dt * 10 = 1e-3 each -> sigma2 = 1e-2; s2 = 100*1e-2 + 10 = 11.
  EXPECT_NEAR(o.s2_rad_s2, 11.0f, 1e-4);
}

TEST(CsmcLaw, RejectsBadConfigAndNanInput) {
  mc_csmc_f32_t st;
  std::memset(&st, 0x3C, sizeof st);
  std::vector<unsigned char> before(sizeof st);
  std::memcpy(before.data(), &st, sizeof st);
  mc_csmc_f32_cfg_t c = paper_cfg(MC_CSMC_LAW_MODEL, MC_CSMC_SW_SAT, true);
  c.model.r_nom_ohm = 22.0f;  // outside [19, 21]
  EXPECT_EQ(mc_csmc_f32_init(&st, &c), MC_CSMC_ERR_BOUNDS);
  c = paper_cfg(MC_CSMC_LAW_MODEL, MC_CSMC_SW_SAT, true);
  c.model.j_kgm2 = 0.0f;
  EXPECT_EQ(mc_csmc_f32_init(&st, &c), MC_CSMC_ERR_MODEL);
  c = paper_cfg(MC_CSMC_LAW_CONST, MC_CSMC_SW_SAT, true);
  c.m2_v = -1.0f;
  c.k2_per_s = 0.0f;
  EXPECT_EQ(mc_csmc_f32_init(&st, &c), MC_CSMC_ERR_GAIN_M | MC_CSMC_ERR_SURFACE);
  c = paper_cfg(MC_CSMC_LAW_CONST, MC_CSMC_SW_SAT, true);
  c.sigma2.k0[0] = -1.0f;  // -k0 > 0: not Hurwitz
  EXPECT_EQ(mc_csmc_f32_init(&st, &c), MC_CSMC_ERR_SIGMA_2);
  c = paper_cfg(MC_CSMC_LAW_CONST, MC_CSMC_SW_SAT, true);
  c.mu1_a = std::nanf("");
  EXPECT_EQ(mc_csmc_f32_init(&st, &c), MC_CSMC_ERR_MU);
  c = paper_cfg(MC_CSMC_LAW_CONST, MC_CSMC_SW_SAT, true);
  c.law = static_cast<mc_csmc_law_t>(7);
  EXPECT_EQ(mc_csmc_f32_init(&st, &c), MC_CSMC_ERR_LAW);
  EXPECT_EQ(std::memcmp(&st, before.data(), sizeof st), 0);

  c = paper_cfg(MC_CSMC_LAW_CONST, MC_CSMC_SW_SAT, true);
  ASSERT_EQ(mc_csmc_f32_init(&st, &c), MC_CSMC_ERR_NONE);
  mc_csmc_f32_in_t in{};
  in.e1_a = 0.02f;
  mc_csmc_f32_out_t o{};
  EXPECT_EQ(mc_csmc_f32_step(&st, &in, &o), MC_CSMC_ERR_NONE);
  float sg[MC_CSVC_MAX_ORDER];
  mc_csvc_f32_sigma(&st.sigma1, sg);
  const float sig = sg[0];
  const mc_csmc_f32_out_t last = o;
  in.e2_rad = std::nanf("");
  EXPECT_EQ(mc_csmc_f32_step(&st, &in, &o), MC_CSMC_ERR_NAN_INPUT);
  EXPECT_EQ(st.flags, MC_CSMC_ERR_NAN_INPUT);
  EXPECT_EQ(o.v_d_v, last.v_d_v);
  mc_csvc_f32_sigma(&st.sigma1, sg);
  EXPECT_EQ(sg[0], sig);
  // NULL pointers: MC_CSMC_ERR_NULL, nothing written.
  in.e2_rad = 0.0f;
  mc_csmc_f32_out_t o_null{42.0f, 42.0f, 42.0f, 42.0f};
  EXPECT_EQ(mc_csmc_f32_step(nullptr, &in, &o_null), MC_CSMC_ERR_NULL);
  EXPECT_EQ(mc_csmc_f32_step(&st, nullptr, &o_null), MC_CSMC_ERR_NULL);
  EXPECT_EQ(o_null.v_d_v, 42.0f);
  EXPECT_EQ(mc_csmc_f32_step(&st, &in, nullptr), MC_CSMC_ERR_NULL);
  mc_csvc_f32_sigma(&st.sigma1, sg);
  EXPECT_EQ(sg[0], sig);
  EXPECT_EQ(mc_csmc_f32_reset(&st), MC_CSMC_ERR_NONE);
  EXPECT_EQ(st.flags, MC_CSMC_ERR_NONE);
  EXPECT_EQ(mc_csmc_f32_reset(nullptr), MC_CSMC_ERR_NULL);
  EXPECT_EQ(mc_csvc_f32_reset(&st.sigma1), MC_CSVC_ERR_NONE);
  EXPECT_EQ(mc_csvc_f32_reset(nullptr), MC_CSVC_ERR_NULL);
}

TEST(CsmcLaw, ErrorsFromState) {
  const mc_csmc_f32_cfg_t c = paper_cfg(MC_CSMC_LAW_MODEL, MC_CSMC_SW_SAT, false);
  mc_csmc_f32_in_t in{};
  ASSERT_EQ(mc_csmc_f32_err_from_state(&c.model, 0.1f, 1.5f, 2.0f, 0.04f, 0.0f, 0.03142f, 0.5f,
                                       1.0f, &in),
            MC_CSMC_ERR_NONE);
  const double k3 = 0.1349 / 4.1295e-4, k4 = 0.0013 / 4.1295e-4, d0 = 0.2 / 4.1295e-4;
  EXPECT_NEAR(in.e2_rad, 0.04 - 0.03142, 1e-8);
  EXPECT_NEAR(in.de2_rad_s, 1.5, 1e-7);
  // e2'' = k3 iq - k4 w - d0 - phi_d'': terms ~500, float relative 1e-7.
  EXPECT_NEAR(in.dde2_rad_s2, k3 * 1.5 - k4 * 2.0 - d0 - 1.0, 1e-3);
  mc_csmc_f32_model_t bad = c.model;
  bad.km_nm_a = 0.0f;
  EXPECT_EQ(mc_csmc_f32_err_from_state(&bad, 0, 0, 0, 0, 0, 0, 0, 0, &in), MC_CSMC_ERR_MODEL);
}

// ------------------------------------------- law and observer in one step
// The combined step must give the bits of the separate kernels: HGO step
// (estimate, then advance) followed by the law on those estimates.
struct Combo {
  const char* name;
  mc_csmc_f32_cfg_t law;
};

std::vector<Combo> combined_configs() {
  std::vector<Combo> v;
  const float w02 = static_cast<float>(4.0 * kPi * kPi);
  const float c1[5] = {0.0f, -4.0f * w02 * w02, 0.0f, -5.0f * w02, 0.0f};
  const float re1[5] = {-1, -2, -2, -3, -3}, im1[5] = {0, 1, -1, 1, -1};
  const float c2[3] = {0.0f, -w02, 0.0f};
  const float re2[3] = {-1, -2, -2}, im2[3] = {0, 1, -1};
  mc_csmc_f32_cfg_t servo = paper_cfg(MC_CSMC_LAW_CONST, MC_CSMC_SW_SAT, false);
  EXPECT_EQ(mc_csvc_f32_place(5u, c1, re1, im1, &servo.sigma1), MC_CSVC_ERR_NONE);
  EXPECT_EQ(mc_csvc_f32_place(3u, c2, re2, im2, &servo.sigma2), MC_CSVC_ERR_NONE);
  v.push_back({"S1 order 5 / S2 order 3 (modal)", servo});
  mc_csmc_f32_cfg_t swapped = servo;
  std::swap(swapped.sigma1, swapped.sigma2);
  swapped.mu1_a = 50.0f;  // the layers follow the axes' scales
  swapped.mu2_rad_s2 = 0.1f;
  v.push_back({"S2 / S1 swapped", swapped});
  v.push_back({"conditional integrators", paper_cfg(MC_CSMC_LAW_CONST, MC_CSMC_SW_SAT, true)});
  v.push_back({"no sigma", paper_cfg(MC_CSMC_LAW_CONST, MC_CSMC_SW_SAT, false)});
  mc_csmc_f32_cfg_t dense = paper_cfg(MC_CSMC_LAW_CONST, MC_CSMC_SW_SAT, false);
  const float cd[2] = {0.0f, 0.0f}, red[2] = {-1, -2}, imd[2] = {0, 0};
  EXPECT_EQ(mc_csvc_f32_place(2u, cd, red, imd, &dense.sigma1), MC_CSVC_ERR_NONE);
  EXPECT_EQ(mc_csvc_f32_integrator(100.0f, &dense.sigma2), MC_CSVC_ERR_NONE);
  v.push_back({"dense d axis", dense});
  mc_csmc_f32_cfg_t clamp = servo;
  clamp.v_limit_v = 20.0f;  // M = 50 V > v_limit: the clamp can act (general path)
  v.push_back({"clamp", clamp});
  v.push_back({"ideal SMC", paper_cfg(MC_CSMC_LAW_CONST, MC_CSMC_SW_SGN, true)});
  v.push_back({"model law", paper_cfg(MC_CSMC_LAW_MODEL, MC_CSMC_SW_SAT, true)});
  return v;
}

bool same_bits(float a, float b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

TEST(CsmcHgoStep, EqualsTheSeparateKernelsBitForBit) {
  for (const Combo& cb : combined_configs()) {
    const mc_hgo_f32_cfg_t hc = hgo_cfg(1e-3, 1e-4, 2u);
    mc_csmc_hgo_f32_t comb{};
    ASSERT_EQ(mc_csmc_hgo_f32_init(&comb, &cb.law, &hc), MC_CSMC_ERR_NONE) << cb.name;
    mc_csmc_f32_t law{};
    mc_hgo_f32_t hgo{};
    ASSERT_EQ(mc_csmc_f32_init(&law, &cb.law), MC_CSMC_ERR_NONE);
    ASSERT_EQ(mc_hgo_f32_init(&hgo, &hc), MC_HGO_ERR_NONE);
    std::mt19937 g(7);
    // errors inside and outside both boundary layers (mu1 0.1 A, mu2 50
    // rad/s^2 is k1 e2 ~ 7e-4 rad): the saturated branches run too
    std::uniform_real_distribution<float> ue1(-0.3f, 0.3f), ue2(-2e-3f, 2e-3f), ux(-2.0f, 2.0f);
    float e2 = 0.0f;
    for (int k = 0; k < 3000; ++k) {
      if (k == 1500) {  // a reset in the middle restarts both from scratch
        mc_csmc_hgo_f32_reset(&comb);
        mc_csmc_f32_reset(&law);
        ASSERT_EQ(mc_hgo_f32_reset(&hgo, 0.0f, 0.0f, 0.0f), MC_HGO_ERR_NONE);
      }
      e2 = 0.9f * e2 + 0.1f * ue2(g);  // a smooth-ish position error
      mc_csmc_f32_in_t in{};
      in.e1_a = ue1(g);
      in.e2_rad = e2;
      in.i_d_a = ux(g);
      in.i_q_a = ux(g);
      in.omega_m_rad_s = 10.0f * ux(g);
      in.di_dd_a_s = ux(g);
      in.dddphi_d_rad_s3 = ux(g);
      mc_hgo_f32_est_t est;
      mc_hgo_f32_step(&hgo, e2, &est);
      in.de2_rad_s = est.z2;
      in.dde2_rad_s2 = est.z3;
      mc_csmc_f32_out_t ref;
      mc_csmc_f32_step(&law, &in, &ref);
      mc_csmc_f32_out_t o;
      ASSERT_EQ(mc_csmc_hgo_f32_step(&comb, in.e1_a, e2, &in, &o), MC_CSMC_ERR_NONE) << cb.name;
      ASSERT_TRUE(same_bits(o.v_d_v, ref.v_d_v) && same_bits(o.v_q_v, ref.v_q_v) &&
                  same_bits(o.s1_a, ref.s1_a) && same_bits(o.s2_rad_s2, ref.s2_rad_s2))
          << cb.name << " step " << k << ": " << o.v_d_v << " " << ref.v_d_v << " " << o.s2_rad_s2
          << " " << ref.s2_rad_s2;
      ASSERT_EQ(std::memcmp(comb.hgo.z, hgo.z, sizeof hgo.z), 0) << cb.name << " step " << k;
    }
    // the sigma states (an axis without sigma has none to compare)
    for (int ax = 0; ax < 2; ++ax) {
      const mc_csvc_f32_t& a = (ax == 0) ? comb.law.sigma1 : comb.law.sigma2;
      const mc_csvc_f32_t& b = (ax == 0) ? law.sigma1 : law.sigma2;
      if (((ax == 0) ? law.have_sigma1 : law.have_sigma2) == 0u) continue;
      EXPECT_EQ(std::memcmp(a.sigma, b.sigma, sizeof a.sigma), 0) << cb.name << " axis " << ax;
      EXPECT_EQ(std::memcmp(a.xi, b.xi, sizeof a.xi), 0) << cb.name << " axis " << ax;
    }
    EXPECT_EQ(comb.law.flags, 0u);
  }
}

TEST(CsmcHgoStep, NonFiniteInputChangesNothing) {
  for (const Combo& cb : combined_configs()) {
    mc_csmc_hgo_f32_t st{};
    const mc_hgo_f32_cfg_t hc = hgo_cfg(1e-3, 1e-4, 2u);
    ASSERT_EQ(mc_csmc_hgo_f32_init(&st, &cb.law, &hc), MC_CSMC_ERR_NONE);
    mc_csmc_f32_in_t model{};
    mc_csmc_f32_out_t o{};
    for (int k = 0; k < 5; ++k) {  // past the observer's start-up steps
      ASSERT_EQ(mc_csmc_hgo_f32_step(&st, 0.01f * k, 1e-4f * k, &model, &o), MC_CSMC_ERR_NONE);
    }
    const mc_csmc_hgo_f32_t before = st;
    const float bad[] = {NAN, INFINITY, -INFINITY};
    for (float b : bad) {
      for (int which = 0; which < 2; ++which) {
        o = mc_csmc_f32_out_t{1.0f, 1.0f, 1.0f, 1.0f};
        const float e1 = (which == 0) ? b : 0.01f, e2 = (which == 1) ? b : 1e-4f;
        EXPECT_EQ(mc_csmc_hgo_f32_step(&st, e1, e2, &model, &o), MC_CSMC_ERR_NAN_INPUT)
            << cb.name << " " << b << " " << which;
        EXPECT_EQ(o.v_d_v, 0.0f);
        EXPECT_EQ(o.v_q_v, 0.0f);
        EXPECT_EQ(std::memcmp(st.law.sigma1.xi, before.law.sigma1.xi, sizeof st.law.sigma1.xi), 0);
        EXPECT_EQ(std::memcmp(st.law.sigma2.xi, before.law.sigma2.xi, sizeof st.law.sigma2.xi), 0);
        EXPECT_EQ(
            std::memcmp(st.law.sigma1.sigma, before.law.sigma1.sigma, sizeof st.law.sigma1.sigma),
            0);
        EXPECT_EQ(
            std::memcmp(st.law.sigma2.sigma, before.law.sigma2.sigma, sizeof st.law.sigma2.sigma),
            0);
        EXPECT_EQ(std::memcmp(&st.hgo, &before.hgo, sizeof st.hgo), 0) << cb.name;
        EXPECT_NE(st.law.flags & MC_CSMC_ERR_NAN_INPUT, 0u);
      }
    }
    // a model-law input that is not finite is refused the same way
    if (cb.law.law == MC_CSMC_LAW_MODEL) {
      model.omega_m_rad_s = NAN;
      EXPECT_EQ(mc_csmc_hgo_f32_step(&st, 0.01f, 1e-4f, &model, &o), MC_CSMC_ERR_NAN_INPUT);
      EXPECT_EQ(std::memcmp(&st.hgo, &before.hgo, sizeof st.hgo), 0);
      EXPECT_EQ(mc_csmc_hgo_f32_step(&st, 0.01f, 1e-4f, nullptr, &o), MC_CSMC_ERR_NULL);
      model.omega_m_rad_s = 0.0f;
    }
    EXPECT_EQ(mc_csmc_hgo_f32_reset(&st), MC_CSMC_ERR_NONE);
    EXPECT_EQ(st.law.flags, 0u);
    EXPECT_EQ(mc_csmc_hgo_f32_reset(nullptr), MC_CSMC_ERR_NULL);
    EXPECT_EQ(mc_csmc_hgo_f32_step(&st, 0.01f, 1e-4f, &model, &o), MC_CSMC_ERR_NONE);
  }
}

TEST(CsmcHgoStep, InitRejectsBadConfigsAndNulls) {
  const mc_csmc_f32_cfg_t law = paper_cfg(MC_CSMC_LAW_CONST, MC_CSMC_SW_SAT, true);
  mc_csmc_hgo_f32_t st{};
  st.fast = 42u;
  mc_hgo_f32_cfg_t hc = hgo_cfg(1e-3, 2e-4, 2u);  // dt differs from the law's 1e-4
  EXPECT_EQ(mc_csmc_hgo_f32_init(&st, &law, &hc), MC_CSMC_ERR_HGO);
  hc = hgo_cfg(-1e-3, 1e-4, 2u);
  EXPECT_EQ(mc_csmc_hgo_f32_init(&st, &law, &hc), MC_CSMC_ERR_HGO);
  mc_csmc_f32_cfg_t bad = law;
  bad.mu1_a = 0.0f;
  EXPECT_EQ(mc_csmc_hgo_f32_init(&st, &bad, &hc), MC_CSMC_ERR_MU | MC_CSMC_ERR_HGO);
  EXPECT_EQ(mc_csmc_hgo_f32_init(nullptr, &law, &hc), MC_CSMC_ERR_NULL);
  EXPECT_EQ(mc_csmc_hgo_f32_init(&st, nullptr, &hc), MC_CSMC_ERR_NULL);
  EXPECT_EQ(mc_csmc_hgo_f32_init(&st, &law, nullptr), MC_CSMC_ERR_NULL);
  EXPECT_EQ(st.fast, 42u);  // not written on error
  mc_csmc_f32_out_t o{};
  EXPECT_EQ(mc_csmc_hgo_f32_step(nullptr, 0.0f, 0.0f, nullptr, &o), MC_CSMC_ERR_NULL);
  hc = hgo_cfg(1e-3, 1e-4, 2u);
  ASSERT_EQ(mc_csmc_hgo_f32_init(&st, &law, &hc), MC_CSMC_ERR_NONE);
  EXPECT_EQ(mc_csmc_hgo_f32_step(&st, 0.0f, 0.0f, nullptr, nullptr), MC_CSMC_ERR_NULL);
}

}  // namespace
