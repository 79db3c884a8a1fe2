// PI^2D kernel (paper 000): with perfect knowledge of the plant the closed
// loop's error dynamics are (20)-(25) (with the corrected sign of gamma in
// Delta) to float rounding, in the paper's normalised units and in physical
// units; config validation; limits; the gain certificate for the paper's
// gains.
#include <cfloat>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

extern "C" {
#include "pi2d/mc_pi2d.h"
}

namespace {

// The paper's Section V: R = L = p = J = 1, gamma = ke = 0.17, sigma = kt =
// 0.51, closed-loop k1 = 4, k2 = 75, kp = 5, kd = 10, ki = 0.01, a = b = 50,
// eps = 0.02, at the scenario's 10 kHz.
mc_pi2d_f32_cfg_t paper_cfg() {
  mc_pi2d_f32_cfg_t c{};
  c.r_ohm = 1.0f;
  c.l_h = 1.0f;
  c.pole_pairs = 1;
  c.ke_v_s_rad = 0.17f;
  c.kt_nm_a = 0.51f;
  c.j_kgm2 = 1.0f;
  c.k1_per_s = 4.0f;
  c.k2_per_s = 75.0f;
  c.kp_per_s2 = 5.0f;
  c.kd_per_s2 = 10.0f;
  c.ki_per_s3 = 0.01f;
  c.a_per_s = 50.0f;
  c.b = 50.0f;
  c.eps_per_s = 0.02f;
  c.dt_s = 1.0e-4f;
  c.iq_max_a = 1e6f;
  c.v_max_v = 1e9f;
  c.nu_max_nm = 1e6f;
  return c;
}

// Paper-002 test motor (p = 4, flux 0.11 Wb, L = 1.14 mH, R = 0.675 ohm),
// J = 1e-3 kg m^2, gains of the pi2d-motor scenario's order of magnitude.
mc_pi2d_f32_cfg_t motor_cfg() {
  mc_pi2d_f32_cfg_t c{};
  c.r_ohm = 0.675f;
  c.l_h = 1.14e-3f;
  c.pole_pairs = 4;
  c.ke_v_s_rad = 0.44f;
  c.kt_nm_a = 0.66f;
  c.j_kgm2 = 1.0e-3f;
  c.k1_per_s = 3000.0f;
  c.k2_per_s = 3000.0f;
  c.kp_per_s2 = 4000.0f;
  c.kd_per_s2 = 2.4e5f;
  c.ki_per_s3 = 4.0e4f;
  c.a_per_s = 2000.0f;
  c.b = 1.0f;
  c.eps_per_s = 20.0f;
  c.dt_s = 5.0e-5f;
  c.iq_max_a = 1e6f;
  c.v_max_v = 1e9f;
  c.nu_max_nm = 1e6f;
  return c;
}

const mc_pi2d_f32_cfg_t kPaper = paper_cfg();

struct Case {
  double x1, x2, x3, x4, qc, nu, tau, th_ref, w_ref, a_ref, j_ref, id_ref, did_ref;
};

// Independent evaluation (double) of the closed-loop error derivatives from
// the plant equations and the controller's definitions, with the voltages
// the kernel produced; returns the residuals of (20), (21), (22) and the
// scale of the terms (for the rounding tolerance).
struct Residuals {
  double r20, r21, r21_printed, r22, scale20, scale21, scale22;
};

Residuals check_case(const mc_pi2d_f32_cfg_t& c, const Case& s) {
  mc_pi2d_f32_t st{};
  EXPECT_EQ(mc_pi2d_f32_init(&st, &c), MC_PI2D_ERR_NONE);
  EXPECT_EQ(mc_pi2d_f32_reset(&st, static_cast<float>(s.qc), static_cast<float>(s.nu)), 0u);
  mc_pi2d_f32_in_t in{};
  in.id_a = static_cast<float>(s.x1);
  in.iq_a = static_cast<float>(s.x2);
  in.theta_m_rad = static_cast<float>(s.x4);
  in.theta_ref_rad = static_cast<float>(s.th_ref);
  in.omega_ref_rad_s = static_cast<float>(s.w_ref);
  in.alpha_ref_rad_s2 = static_cast<float>(s.a_ref);
  in.jerk_ref_rad_s3 = static_cast<float>(s.j_ref);
  in.id_ref_a = static_cast<float>(s.id_ref);
  in.did_ref_a_s = static_cast<float>(s.did_ref);
  mc_pi2d_f32_out_t o{};
  EXPECT_EQ(mc_pi2d_f32_step(&st, &in, &o), 0u);
  // Inputs as the kernel saw them (rounded to float).
  const double x1 = in.id_a, x2 = in.iq_a, x3 = s.x3, x4 = in.theta_m_rad;
  const double R = c.r_ohm, L = c.l_h, p = c.pole_pairs, ke = c.ke_v_s_rad, kt = c.kt_nm_a,
               J = c.j_kgm2, a = c.a_per_s, b = c.b, kp = c.kp_per_s2, kd = c.kd_per_s2,
               ki = c.ki_per_s3, eps = c.eps_per_s, k1 = c.k1_per_s, k2 = c.k2_per_s;
  const double sigma = kt / J;
  const double u1 = o.vd_v, u2 = o.vq_v;
  // Plant (1)-(4) in physical units.
  const double dx1 = (-R * x1 + p * L * x2 * x3 + u1) / L;
  const double dx2 = (-R * x2 - p * L * x1 * x3 - ke * x3 + u2) / L;
  const double dx3 = (kt * x2 - s.tau) / J;
  // Controller definitions (8)-(12).
  const double e4 = x4 - static_cast<double>(in.theta_ref_rad);
  const double e3 = x3 - static_cast<double>(in.omega_ref_rad_s);
  const double th = static_cast<double>(static_cast<float>(s.qc)) + b * e4;
  const double dth = -a * th + b * e3;
  const double nu = static_cast<float>(s.nu);
  const double v3 = -kp * e4 - kd * th, dv3 = -kp * e3 - kd * dth;
  const double dnu = -J * ki * (e4 - th);
  const double x2s = (nu + J * (in.alpha_ref_rad_s2 + v3)) / kt;
  const double dx2s = (dnu + J * (in.jerk_ref_rad_s3 + dv3)) / kt;
  const double e1 = x1 - in.id_ref_a, e2 = x2 - x2s;
  const double de1 = dx1 - in.did_ref_a_s, de2 = dx2 - dx2s, de3 = dx3 - in.alpha_ref_rad_s2;
  // (20)-(22), re-derived (Delta with -gamma), and the printed Delta (+gamma).
  const double delta = (kp + b * kd) / sigma - ke / L - p * x1;
  const double delta_printed = (kp + b * kd) / sigma + ke / L - p * x1;
  const double v2 = -eps * sigma * (e4 - th);
  const double kpp = kp - ki / eps;
  const double z = (nu - s.tau) / J - ki / eps * e4;
  Residuals r{};
  r.r20 = de1 - (-k1 * e1 + p * x2 * e3);
  r.r21 = de2 - (-k2 * e2 + delta * e3 + v2);
  r.r21_printed = de2 - (-k2 * e2 + delta_printed * e3 + v2);
  r.r22 = de3 - (sigma * e2 - kpp * e4 - kd * th + z);
  // Size of the terms whose float rounding the residual sees: the voltage
  // terms over L (u1, u2 are sums of these), and the reference current.
  r.scale20 =
      (std::abs(R * in.id_ref_a) + std::abs(L * in.did_ref_a_s) +
       std::abs(p * L * x2 * in.omega_ref_rad_s) + std::abs((L * k1 - R) * e1) + std::abs(u1)) /
      L;
  r.scale21 = (std::abs(ke * in.omega_ref_rad_s) + std::abs(p * L * x1 * in.omega_ref_rad_s) +
               std::abs(R * x2s) + std::abs(L * o.rho_a_s) + std::abs(L * v2) +
               std::abs((L * k2 - R) * e2) + std::abs(L * k2 * x2s) + std::abs(u2)) /
              L;
  r.scale22 = sigma * (std::abs(x2s) + std::abs(nu / kt) + std::abs(J * v3 / kt) +
                       std::abs(J * in.alpha_ref_rad_s2 / kt));
  return r;
}

void run_algebra(const mc_pi2d_f32_cfg_t& c, double i_scale, double w_scale, double th_scale,
                 double tau_scale) {
  std::mt19937 rng(1234);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int printed_wrong = 0;
  for (int k = 0; k < 500; ++k) {
    Case s{};
    s.x1 = i_scale * u(rng);
    s.x2 = i_scale * u(rng);
    s.x3 = w_scale * u(rng);
    s.x4 = th_scale * u(rng);
    s.qc = th_scale * u(rng);
    s.nu = tau_scale * u(rng);
    s.tau = tau_scale * u(rng);
    s.th_ref = s.x4 + 0.1 * th_scale * u(rng);
    s.w_ref = w_scale * u(rng);
    s.a_ref = 10.0 * w_scale * u(rng);
    s.j_ref = 100.0 * w_scale * u(rng);
    s.id_ref = 0.1 * i_scale * u(rng);
    s.did_ref = i_scale * u(rng);
    const Residuals r = check_case(c, s);
    // Float rounding: each voltage is a sum of ~6 products computed in
    // float, each term rounded to 2^-24 relative, plus the rounding of x2*
    // (which enters e2 multiplied by L k2): a few ulp of the largest term.
    // 2e-6 (~ 32 ulp) of the sum of |terms| bounds it with a margin; a wrong
    // coefficient anywhere gives residuals of order 1 relative.
    EXPECT_LT(std::abs(r.r20), 2e-6 * r.scale20) << k;
    EXPECT_LT(std::abs(r.r21), 2e-6 * r.scale21) << k;
    EXPECT_LT(std::abs(r.r22), 2e-6 * r.scale22) << k;
    // The printed Delta is off by 2 (ke/L) e3: the residual is that term.
    const double slip = 2.0 * c.ke_v_s_rad / c.l_h * (s.x3 - static_cast<float>(s.w_ref));
    EXPECT_NEAR(r.r21_printed, -slip, 2e-6 * r.scale21 + 1e-9) << k;
    if (std::abs(r.r21_printed) > 2e-6 * r.scale21) ++printed_wrong;
  }
  // The same check with the printed Delta fails in almost every case (the
  // rest have e3 near 0).
  EXPECT_GT(printed_wrong, 450);
}

TEST(Pi2dAlgebra, ErrorDynamicsAre20To25InPaperUnits) {
  run_algebra(paper_cfg(), 3.0, 15.0, 5.0, 2.0);
}

TEST(Pi2dAlgebra, ErrorDynamicsAre20To25InPhysicalUnits) {
  run_algebra(motor_cfg(), 5.0, 120.0, 0.5, 3.0);
}

TEST(Pi2dConfig, RejectsWhatThePaperForbidsAndLeavesStateAlone) {
  mc_pi2d_f32_t st{};
  ASSERT_EQ(mc_pi2d_f32_init(&st, &kPaper), 0u);
  st.nu_nm = 0.5f;
  auto expect = [&](void (*edit)(mc_pi2d_f32_cfg_t*), uint32_t bits) {
    mc_pi2d_f32_cfg_t c = paper_cfg();
    edit(&c);
    EXPECT_EQ(mc_pi2d_f32_init(&st, &c), bits);
    EXPECT_EQ(st.nu_nm, 0.5f);
  };
  expect([](mc_pi2d_f32_cfg_t* c) { c->r_ohm = 0.0f; }, MC_PI2D_ERR_PLANT);
  expect([](mc_pi2d_f32_cfg_t* c) { c->pole_pairs = 0; }, MC_PI2D_ERR_PLANT);
  expect([](mc_pi2d_f32_cfg_t* c) { c->ke_v_s_rad = -0.1f; }, MC_PI2D_ERR_PLANT);
  expect([](mc_pi2d_f32_cfg_t* c) { c->j_kgm2 = NAN; }, MC_PI2D_ERR_PLANT);
  expect([](mc_pi2d_f32_cfg_t* c) { c->k1_per_s = 0.0f; }, MC_PI2D_ERR_K12);
  expect([](mc_pi2d_f32_cfg_t* c) { c->k2_per_s = -75.0f; }, MC_PI2D_ERR_K12);
  expect([](mc_pi2d_f32_cfg_t* c) { c->kp_per_s2 = 0.0f; }, MC_PI2D_ERR_KPKD);
  expect([](mc_pi2d_f32_cfg_t* c) { c->kd_per_s2 = -1.0f; }, MC_PI2D_ERR_KPKD);
  expect([](mc_pi2d_f32_cfg_t* c) { c->a_per_s = 0.0f; }, MC_PI2D_ERR_FILTER);
  expect([](mc_pi2d_f32_cfg_t* c) { c->b = -50.0f; }, MC_PI2D_ERR_FILTER);
  // 0 < ki < eps violated (R = L = 1: the paper's own rule).
  expect([](mc_pi2d_f32_cfg_t* c) { c->ki_per_s3 = 0.0f; }, MC_PI2D_ERR_KI_EPS);
  expect([](mc_pi2d_f32_cfg_t* c) { c->ki_per_s3 = 0.02f; }, MC_PI2D_ERR_KI_EPS);
  expect([](mc_pi2d_f32_cfg_t* c) { c->eps_per_s = 0.0f; }, MC_PI2D_ERR_KI_EPS);
  // kp' = kp - ki/eps <= 0.
  expect([](mc_pi2d_f32_cfg_t* c) { c->kp_per_s2 = 0.4f; }, MC_PI2D_ERR_KP_PRIME);
  expect([](mc_pi2d_f32_cfg_t* c) { c->dt_s = 0.0f; }, MC_PI2D_ERR_DT);
  expect([](mc_pi2d_f32_cfg_t* c) { c->v_max_v = 0.0f; }, MC_PI2D_ERR_LIMITS);
  expect([](mc_pi2d_f32_cfg_t* c) { c->nu_max_nm = INFINITY; }, MC_PI2D_ERR_LIMITS);
  // Several at once are all reported.
  expect(
      [](mc_pi2d_f32_cfg_t* c) {
        c->k1_per_s = 0.0f;
        c->a_per_s = 0.0f;
        c->dt_s = -1.0f;
      },
      MC_PI2D_ERR_K12 | MC_PI2D_ERR_FILTER | MC_PI2D_ERR_DT);
  EXPECT_EQ(mc_pi2d_f32_init(nullptr, &kPaper), MC_PI2D_ERR_NULL);
}

TEST(Pi2dConfig, KiEpsRuleScalesWithTheElectricalTimeConstant) {
  // Physical units: 0 < ki (L/R)^2 < eps. L/R = 1.69e-3 s: ki = 4e4 gives
  // 0.114, so eps = 0.2 passes and eps = 0.1 does not (kp raised so that
  // kp' = kp - ki/eps stays positive).
  mc_pi2d_f32_t st{};
  mc_pi2d_f32_cfg_t c = motor_cfg();
  c.kp_per_s2 = 4.0e5f;
  c.eps_per_s = 0.2f;
  EXPECT_EQ(mc_pi2d_f32_init(&st, &c), 0u);
  c.eps_per_s = 0.1f;
  EXPECT_EQ(mc_pi2d_f32_init(&st, &c), MC_PI2D_ERR_KI_EPS);
}

TEST(Pi2dLimits, CurrentClampFreezesNuAndZeroesRho) {
  mc_pi2d_f32_cfg_t c = paper_cfg();
  c.iq_max_a = 1.0f;
  mc_pi2d_f32_t st{};
  ASSERT_EQ(mc_pi2d_f32_init(&st, &c), 0u);
  mc_pi2d_f32_in_t in{};
  in.theta_m_rad = -1.0f;  // large lag: x2* = (J (kp + kd b)) / kt >> 1
  mc_pi2d_f32_out_t o{};
  ASSERT_EQ(mc_pi2d_f32_step(&st, &in, &o), 0u);
  EXPECT_TRUE(o.iq_limited);
  EXPECT_EQ(o.iq_ref_a, 1.0f);
  EXPECT_EQ(o.rho_a_s, 0.0f);
  EXPECT_EQ(o.dnu_nm_s, 0.0f);
  EXPECT_EQ(st.nu_nm, 0.0f);
}

// A clamp set at run time (a current limit lowered while the law runs)
// applies from the next step; an invalid one is refused, nothing changes.
TEST(Pi2dLimits, CurrentClampSetAtRunTime) {
  mc_pi2d_f32_cfg_t c = paper_cfg();
  c.iq_max_a = 5.0f;
  mc_pi2d_f32_t st{};
  ASSERT_EQ(mc_pi2d_f32_init(&st, &c), 0u);
  EXPECT_EQ(mc_pi2d_f32_set_iq_max(&st, 0.0f), MC_PI2D_ERR_LIMITS);
  EXPECT_EQ(mc_pi2d_f32_set_iq_max(&st, std::nanf("")), MC_PI2D_ERR_LIMITS);
  EXPECT_EQ(mc_pi2d_f32_set_iq_max(nullptr, 1.0f), MC_PI2D_ERR_NULL);
  EXPECT_EQ(st.cfg.iq_max_a, 5.0f);
  ASSERT_EQ(mc_pi2d_f32_set_iq_max(&st, 0.5f), 0u);
  mc_pi2d_f32_in_t in{};
  in.theta_m_rad = -1.0f;  // large lag: x2* far above 0.5
  mc_pi2d_f32_out_t o{};
  ASSERT_EQ(mc_pi2d_f32_step(&st, &in, &o), 0u);
  EXPECT_TRUE(o.iq_limited);
  EXPECT_EQ(o.iq_ref_a, 0.5f);
}

TEST(Pi2dLimits, VoltageCircleAndNuClamp) {
  mc_pi2d_f32_cfg_t c = paper_cfg();
  c.v_max_v = 2.0f;
  c.nu_max_nm = 1e-3f;
  mc_pi2d_f32_t st{};
  ASSERT_EQ(mc_pi2d_f32_init(&st, &c), 0u);
  mc_pi2d_f32_in_t in{};
  in.id_a = 3.0f;
  in.iq_a = -4.0f;
  mc_pi2d_f32_out_t o{};
  ASSERT_EQ(mc_pi2d_f32_step(&st, &in, &o), 0u);
  EXPECT_TRUE(o.v_limited);
  // Scaled onto the circle: |u| = v_max to float rounding (2 ulp).
  EXPECT_NEAR(std::hypot(o.vd_v, o.vq_v), 2.0, 5e-7);
  EXPECT_EQ(st.nu_nm, 0.0f);  // frozen while limited
  // Unlimited steps with a small lag integrate nu up to its clamp.
  c.v_max_v = 1e9f;
  ASSERT_EQ(mc_pi2d_f32_init(&st, &c), 0u);
  in = {};
  in.theta_m_rad = -0.1f;  // nu rate J ki e4 = 1e-3 N m/s: the clamp in ~1 s of 4
  for (int k = 0; k < 40000; ++k) mc_pi2d_f32_step(&st, &in, &o);
  EXPECT_EQ(st.nu_nm, 1e-3f);
  ASSERT_EQ(mc_pi2d_f32_reset(&st, 0.0f, 5.0f), 0u);
  EXPECT_EQ(st.nu_nm, 1e-3f);
}

TEST(Pi2dStep, NonFiniteInputGivesZeroVoltageAndStickyFlag) {
  mc_pi2d_f32_t st{};
  ASSERT_EQ(mc_pi2d_f32_init(&st, &kPaper), 0u);
  mc_pi2d_f32_in_t in{};
  in.theta_m_rad = 0.1f;
  mc_pi2d_f32_out_t o{};
  ASSERT_EQ(mc_pi2d_f32_step(&st, &in, &o), 0u);
  const float nu = st.nu_nm, q = mc_ddiff_f32_get_q(&st.dd);
  in.iq_a = NAN;
  EXPECT_EQ(mc_pi2d_f32_step(&st, &in, &o), MC_PI2D_ERR_NAN_INPUT);
  EXPECT_EQ(o.vd_v, 0.0f);
  EXPECT_EQ(o.vq_v, 0.0f);
  EXPECT_EQ(st.nu_nm, nu);
  EXPECT_EQ(mc_ddiff_f32_get_q(&st.dd), q);
  in.iq_a = 0.0f;
  EXPECT_EQ(mc_pi2d_f32_step(&st, &in, &o), 0u);
  EXPECT_NE(st.flags & MC_PI2D_ERR_NAN_INPUT, 0u);
  EXPECT_EQ(mc_pi2d_f32_reset(&st, 0.0f, 0.0f), 0u);
  EXPECT_EQ(st.flags, 0u);
}

TEST(Pi2dCertificate, PaperGainsMeet34ButNot38) {
  const mc_pi2d_envelope_t env{-0.5f, 0.5f, 5.0f};
  mc_pi2d_cert_t r{};
  ASSERT_EQ(mc_pi2d_f32_certify(&kPaper, &env, &r), 0u);
  // Hand values: kp' = 5 - 0.01/0.02 = 4.5, b' = 49.
  EXPECT_NEAR(r.kp_prime_per_s2, 4.5f, 1e-6f);
  // (34): kd a/b = 10 >= 0.02 (20 + 2500/49 + 5.5^2/4.5) = 1.55485 (printed
  // with a^2/b: 1.53444). Float evaluation: 1e-5 relative.
  EXPECT_NEAR(r.c34_lhs, 10.0f, 1e-4f);
  EXPECT_NEAR(r.c34_rhs, 1.554853f, 2e-5f);
  EXPECT_NEAR(r.c34_printed_rhs, 1.534444f, 2e-5f);
  EXPECT_GT(r.c34_margin, 8.0f);
  // (38): |Delta + sigma| = 505/0.51 - 0.17 + 0.5 + 0.51 = 991.036 at
  // x1 = -0.5; 2 eps b' = 1.96 < (x2 = 5)^2 / k1 = 6.25: no k2 can satisfy
  // it over this envelope, and k2 = 75 is far from it.
  EXPECT_NEAR(r.delta_sigma_max, 991.0358f, 1e-2f);
  EXPECT_NEAR(r.c38_lhs, 1.96f, 1e-5f);
  EXPECT_LT(r.c38_margin, -13000.0f);
  EXPECT_EQ(r.c38_k2_min_per_s, FLT_MAX);
  // Printed (38) with the printed Delta (+gamma): k2 >= 991.376^2/0.98 +
  // 25/4 = 1.0029e6.
  EXPECT_NEAR(r.c38_printed_rhs, 1.00290e6f, 2e2f);
  EXPECT_FALSE(r.holds);
  // With x2 = 0 the re-derived condition needs k2 >= 991.036^2/1.96.
  const mc_pi2d_envelope_t env0{-0.5f, 0.5f, 0.0f};
  ASSERT_EQ(mc_pi2d_f32_certify(&kPaper, &env0, &r), 0u);
  EXPECT_NEAR(r.c38_k2_min_per_s, 991.0358f * 991.0358f / 1.96f, 50.0f);
}

TEST(Pi2dCertificate, GainsThatMeetBothAreCertified) {
  // Gains chosen to meet both: kp' = kd = 1 (kills the (kp'-kd)^2 term),
  // a = 1, b = 2: (34) 0.5 >= eps (2 + 1 + 0) = 0.15 with eps = 0.05;
  // ki = 0.01 < eps, kp = 1 + ki/eps = 1.2. (38): |Delta + sigma| <=
  // 3.2/0.51 - 0.17 + 0.5 + 0.51 = 7.12, 2 eps b' = 0.1; |x2| <= 0.1 with
  // k1 = 1 uses 0.01, and k2 = 1000 uses 0.0507.
  mc_pi2d_f32_cfg_t c = paper_cfg();
  c.kp_per_s2 = 1.2f;
  c.kd_per_s2 = 1.0f;
  c.a_per_s = 1.0f;
  c.b = 2.0f;
  c.eps_per_s = 0.05f;
  c.ki_per_s3 = 0.01f;
  c.k1_per_s = 1.0f;
  c.k2_per_s = 1000.0f;
  const mc_pi2d_envelope_t env{-0.5f, 0.5f, 0.1f};
  mc_pi2d_cert_t r{};
  ASSERT_EQ(mc_pi2d_f32_certify(&c, &env, &r), 0u);
  EXPECT_GE(r.c34_margin, 0.0f) << r.c34_lhs << " " << r.c34_rhs;
  EXPECT_GE(r.c38_margin, 0.0f) << r.c38_lhs << " " << r.c38_rhs;
  EXPECT_NEAR(r.c34_rhs, 0.15f, 1e-5f);
  EXPECT_NEAR(r.c38_margin, 0.1f - 0.01f - 7.1175f * 7.1175f / 1000.0f, 1e-4f);
  EXPECT_TRUE(r.holds);
  // Bad envelope.
  const mc_pi2d_envelope_t bad{1.0f, -1.0f, 1.0f};
  EXPECT_EQ(mc_pi2d_f32_certify(&c, &bad, &r), MC_PI2D_ERR_ENVELOPE);
}

}  // namespace
