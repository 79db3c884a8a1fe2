// PI^2D law: q31 twin against the f32 kernel (open loop, same inputs).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "q31_test_util.hpp"

extern "C" {
#include "pi2d/mc_pi2d_q31.h"
}

using namespace q31t;

namespace
{
// Paper 000 Section V gains on the normalised machine, limits that act.
mc_pi2d_q31_cfg_t cfg()
{
    mc_pi2d_q31_cfg_t c{};
    c.f.r_ohm = 1.0f;
    c.f.l_h = 1.0f;
    c.f.pole_pairs = 1;
    c.f.ke_v_s_rad = 0.17f;
    c.f.kt_nm_a = 0.51f;
    c.f.j_kgm2 = 1.0f;
    c.f.k1_per_s = 4.0f;
    c.f.k2_per_s = 75.0f;
    c.f.kp_per_s2 = 5.0f;
    c.f.kd_per_s2 = 10.0f;
    c.f.ki_per_s3 = 0.01f;
    c.f.a_per_s = 50.0f;
    c.f.b = 50.0f;
    c.f.eps_per_s = 0.02f;
    c.f.dt_s = 1e-4f;
    c.f.iq_max_a = 6.0f;
    c.f.v_max_v = 60.0f;
    c.f.nu_max_nm = 3.0f;
    c.base = {8.0f, 100.0f, 1.0f, 4.0f, 20.0f, 20.0f, 20.0f, 10.0f, 4.0f};
    return c;
}
} // namespace

TEST(Pi2dQ31, InitRules)
{
    mc_pi2d_q31_t q{};
    q.nu_q46 = 9;
    mc_pi2d_q31_cfg_t c = cfg();
    c.base.v_base_v = -1.0f;
    EXPECT_EQ(mc_pi2d_q31_init(&q, &c), MC_PI2D_ERR_SCALE);
    c = cfg();
    c.f.ki_per_s3 = 1.0f; // ki >= eps: the f32 rule
    EXPECT_EQ(mc_pi2d_q31_init(&q, &c) & MC_PI2D_ERR_KI_EPS, MC_PI2D_ERR_KI_EPS);
    c = cfg();
    c.base.v_base_v = 1.0e-9f; // L k2 i_b / v_b = 6e11: no gain format holds it
    EXPECT_EQ(mc_pi2d_q31_init(&q, &c), MC_PI2D_ERR_SCALE);
    EXPECT_EQ(q.nu_q46, 9);
    c = cfg();
    EXPECT_EQ(mc_pi2d_q31_init(&q, &c), 0u);
}

TEST(Pi2dQ31, SameShapeAsF32NullPointersWriteNothing)
{
    // Twin of mc_pi2d_f32_step: out is required and is the only place the
    // outputs go; a NULL st, in or out gives MC_PI2D_ERR_NULL and writes
    // nothing (state compared bit for bit, out keeps its sentinel).
    mc_pi2d_q31_t q{};
    const mc_pi2d_q31_cfg_t c = cfg();
    ASSERT_EQ(mc_pi2d_q31_init(&q, &c), 0u);
    mc_pi2d_q31_in_t in{};
    in.theta_m = 1 << 24;
    mc_pi2d_q31_out_t o{};
    ASSERT_EQ(mc_pi2d_q31_step(&q, &in, &o), MC_PI2D_ERR_NONE);
    const mc_pi2d_q31_t before = q;
    mc_pi2d_q31_out_t sentinel{};
    sentinel.vd = 42;
    mc_pi2d_q31_out_t o2 = sentinel;
    EXPECT_EQ(mc_pi2d_q31_step(nullptr, &in, &o2), MC_PI2D_ERR_NULL);
    EXPECT_EQ(mc_pi2d_q31_step(&q, nullptr, &o2), MC_PI2D_ERR_NULL);
    EXPECT_EQ(o2.vd, 42);
    EXPECT_EQ(mc_pi2d_q31_step(&q, &in, nullptr), MC_PI2D_ERR_NULL);
    EXPECT_EQ(std::memcmp(&q, &before, sizeof q), 0);
    EXPECT_EQ(mc_pi2d_q31_reset(nullptr, 0, 0), MC_PI2D_ERR_NULL);
    EXPECT_EQ(mc_pi2d_q31_reset(&q, 0, 0), MC_PI2D_ERR_NONE);
}

TEST(Pi2dQ31, MatchesF32OnRandomTrajectories)
{
    // 100000 steps (10 s normalised) of smooth random measurements and
    // references (the closed-loop test in tests/sil/q31 does the real loop):
    // positions random-walk by 1e-4 per step, currents by 1e-3, the speed
    // reference ramps; the iq clamp and the voltage circle act at times.
    const mc_pi2d_q31_cfg_t c = cfg();
    mc_pi2d_f32_t f{};
    mc_pi2d_q31_t q{};
    ASSERT_EQ(mc_pi2d_f32_init(&f, &c.f), 0u);
    ASSERT_EQ(mc_pi2d_q31_init(&q, &c), 0u);
    const mc_pi2d_q31_bases_t &b = c.base;
    std::mt19937 rng(50);
    std::normal_distribution<double> n(0.0, 1.0);
    double id = 0, iq = 0, e = 0, w = 0;
    double worst_v = 0, worst_nu = 0, worst_iq = 0, worst_th = 0;
    long iq_lim = 0, v_lim = 0;
    for (int k = 0; k < 100000; ++k) {
        id = std::clamp(id + 1e-3 * n(rng), -2.0, 2.0);
        iq = std::clamp(iq + 3e-3 * n(rng), -6.0, 6.0);
        e = std::clamp(e + 1e-4 * n(rng), -0.5, 0.5);
        w = 10.0 * std::sin(1e-4 * k);
        mc_pi2d_q31_in_t qi{};
        qi.id = to_q(id, b.i_base_a);
        qi.iq = to_q(iq, b.i_base_a);
        qi.theta_m = to_q(0.3 + e, b.theta_base_rad);
        qi.theta_ref = to_q(0.3, b.theta_base_rad);
        qi.omega_ref = to_q(w, b.omega_base_rad_s);
        qi.alpha_ref = to_q(10.0 * std::cos(1e-4 * k), b.alpha_base_rad_s2);
        qi.jerk_ref = to_q(-10.0 * std::sin(1e-4 * k), b.jerk_base_rad_s3);
        qi.id_ref = 0;
        qi.did_ref = 0;
        mc_pi2d_f32_in_t fi{};
        fi.id_a = static_cast<float>(from_q(qi.id, b.i_base_a));
        fi.iq_a = static_cast<float>(from_q(qi.iq, b.i_base_a));
        fi.theta_m_rad = static_cast<float>(from_q(qi.theta_m, b.theta_base_rad));
        fi.theta_ref_rad = static_cast<float>(from_q(qi.theta_ref, b.theta_base_rad));
        fi.omega_ref_rad_s = static_cast<float>(from_q(qi.omega_ref, b.omega_base_rad_s));
        fi.alpha_ref_rad_s2 = static_cast<float>(from_q(qi.alpha_ref, b.alpha_base_rad_s2));
        fi.jerk_ref_rad_s3 = static_cast<float>(from_q(qi.jerk_ref, b.jerk_base_rad_s3));
        mc_pi2d_f32_out_t fo{};
        mc_pi2d_q31_out_t qo{};
        ASSERT_EQ(mc_pi2d_f32_step(&f, &fi, &fo), 0u);
        ASSERT_EQ(mc_pi2d_q31_step(&q, &qi, &qo), 0u);
        ASSERT_EQ(fo.iq_limited, qo.iq_limited) << "step " << k;
        ASSERT_EQ(fo.v_limited, qo.v_limited) << "step " << k;
        iq_lim += qo.iq_limited ? 1 : 0;
        v_lim += qo.v_limited ? 1 : 0;
        worst_v = std::max({worst_v, std::abs(fo.vd_v - from_q(qo.vd, b.v_base_v)),
                            std::abs(fo.vq_v - from_q(qo.vq, b.v_base_v))});
        worst_nu = std::max(worst_nu, std::abs(fo.nu_nm - from_q(qo.nu, b.nu_base_nm)));
        worst_iq = std::max(worst_iq, std::abs(fo.iq_ref_a - from_q(qo.iq_ref, b.i_base_a)));
        worst_th =
            std::max(worst_th, std::abs(fo.theta_f_rad - from_q(qo.theta_f, b.thetaf_base_rad)));
    }
    // Bounds: the f32 kernel sums a dozen terms of up to ~500 V that
    // largely cancel (L k2 x2* against (L k2 - R) x2: ulp 3e-5 V each) and
    // scales by v_max/|u|: 1e-3 V (2e4 LSB of the 100 V base, 1.7e-5 of
    // v_max); theta_f: f32 ulp 2.4e-7 rad at 4 rad through the slow pole;
    // nu is the f32 kernel's compensated sum (~1 ulp of 3 N m = 2.4e-7);
    // x2*: terms up to 6 A (ulp 4.8e-7 A), kp e4 with e4 rounded in f32.
    const double bv = 1.0e-3, bnu = 2.0e-6, biq = 4.0e-5, bth = 4.0e-6;
    report("pi2d |v_f32 - v_q31|", worst_v, bv, "V");
    report("pi2d same in LSB of the voltage base", worst_v / b.v_base_v * kQ31,
           bv / b.v_base_v * kQ31, "LSB");
    report("pi2d |nu_f32 - nu_q31|", worst_nu, bnu, "N m");
    report("pi2d |iq_ref_f32 - iq_ref_q31|", worst_iq, biq, "A");
    report("pi2d |theta_f_f32 - theta_f_q31|", worst_th, bth, "rad");
    std::printf("[ measured ] pi2d steps with iq clamp %ld, voltage limit %ld\n", iq_lim, v_lim);
    EXPECT_LE(worst_v, bv);
    EXPECT_LE(worst_nu, bnu);
    EXPECT_LE(worst_iq, biq);
    EXPECT_LE(worst_th, bth);
}

TEST(Pi2dQ31, FullScaleInputsSaturateNeverWrap)
{
    // Position error beyond the base, opposite full-scale currents and
    // speeds: every output stays in range with the sign of the law (a wrap
    // flips it), the clamps act, nu stays within +-nu_max.
    const mc_pi2d_q31_cfg_t c = cfg();
    mc_pi2d_q31_t q{};
    ASSERT_EQ(mc_pi2d_q31_init(&q, &c), 0u);
    mc_pi2d_q31_in_t in{};
    in.theta_m = MC_Q31_MAX;
    in.theta_ref = MC_Q31_MIN; // e4 = +2 bases: saturates at +1
    in.id = MC_Q31_MIN;
    in.iq = MC_Q31_MIN;
    in.omega_ref = MC_Q31_MAX;
    in.alpha_ref = MC_Q31_MIN;
    in.jerk_ref = MC_Q31_MIN;
    mc_pi2d_q31_out_t o{};
    for (int k = 0; k < 2000; ++k) {
        ASSERT_EQ(mc_pi2d_q31_step(&q, &in, &o), 0u);
        ASSERT_EQ(o.e4, MC_Q31_MAX);
        ASSERT_LT(o.iq_ref, 0); // -kp e4 - kd theta_f: negative
        ASSERT_TRUE(o.iq_limited);
        ASSERT_TRUE(o.v_limited);
        const double vm = std::hypot(from_q(o.vd, 100.0), from_q(o.vq, 100.0));
        ASSERT_LE(vm, 60.0 * (1.0 + 1e-7)); // limit_vec: < 2^-28 relative, + rounding
    }
    EXPECT_NEAR(from_q(o.iq_ref, 8.0), -6.0, 1e-8);
    EXPECT_EQ(o.nu, 0); // frozen by the conditional integration
    // reset with nu beyond its clamp
    ASSERT_EQ(mc_pi2d_q31_reset(&q, 0, MC_Q31_MAX), MC_PI2D_ERR_NONE);
    EXPECT_NEAR(q.nu_q46 / 70368744177664.0 * 4.0, 3.0, 1e-8);
}
