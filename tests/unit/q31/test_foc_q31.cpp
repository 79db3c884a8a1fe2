// FOC dq current controller: q31 twin against the f32 kernel.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "q31_test_util.hpp"

extern "C" {
#include "foc/mc_foc_q31.h"
}

using namespace q31t;

namespace
{
// current base 50 A: above every current AND every current error of the
// tests (errors beyond one base saturate: FocQ31.ErrorsSaturateAtTheRangeEdges)
constexpr double kIb = 50.0, kVb = 400.0, kWb = 1000.0;

mc_foc_q31_cfg_t cfg()
{
    mc_foc_q31_cfg_t c{};
    float kp = 0.0f, ki = 0.0f;
    // paper-002 test motor, current loops at 2 pi 500 rad/s, 20 kHz
    EXPECT_EQ(mc_foc_f32_gains_from_bandwidth(0.675f, 1.14e-3f, 3141.59f, &kp, &ki), 0u);
    c.f.r_ohm = 0.675f;
    c.f.ld_h = 1.14e-3f;
    c.f.lq_h = 1.14e-3f;
    c.f.flux_wb = 0.11f;
    c.f.kp_d_v_per_a = kp;
    c.f.ki_d_v_per_as = ki;
    c.f.kp_q_v_per_a = kp;
    c.f.ki_q_v_per_as = ki;
    c.f.dt_s = 5e-5f;
    c.f.aw = MC_PI_AW_CLAMP;
    c.f.kaw_per_s = 0.0f;
    c.f.limit_mode = MC_SVPWM_LIMIT_CIRCLE;
    c.f.v_limit_ratio = 0.95f;
    c.f.v_abs_max_v = 300.0f;
    c.f.decouple = true;
    c.i_base_a = static_cast<float>(kIb);
    c.v_base_v = static_cast<float>(kVb);
    c.omega_base_rad_s = static_cast<float>(kWb);
    return c;
}
} // namespace

TEST(FocQ31, InitRules)
{
    mc_foc_q31_t q{};
    q.vd = 3;
    mc_foc_q31_cfg_t c = cfg();
    c.f.limit_mode = MC_SVPWM_LIMIT_HEXAGON; // departure: circle only
    EXPECT_EQ(mc_foc_q31_init(&q, &c), MC_FOC_ERR_LIMIT_MODE);
    c = cfg();
    c.v_base_v = 0.0f;
    EXPECT_EQ(mc_foc_q31_init(&q, &c), MC_FOC_ERR_SCALE);
    c = cfg();
    c.f.ld_h = -1.0f;
    EXPECT_EQ(mc_foc_q31_init(&q, &c), MC_FOC_ERR_MOTOR);
    c = cfg();
    c.i_base_a = 1.0e6f; // kp i_base/v_base = 8950 per unit: fits (2^15)
    EXPECT_EQ(mc_foc_q31_init(&q, &c), 0u);
    c.i_base_a = 1.0e8f; // ... 9e5: beyond the PI's gain format
    q.vd = 3;
    EXPECT_EQ(mc_foc_q31_init(&q, &c), MC_FOC_ERR_SCALE);
    EXPECT_EQ(q.vd, 3);
    // reset: NONE, voltages and flags to 0; NULL: MC_FOC_ERR_NULL.
    q.flags = MC_FOC_ERR_VBUS;
    EXPECT_EQ(mc_foc_q31_reset(&q), MC_FOC_ERR_NONE);
    EXPECT_EQ(q.vd, 0);
    EXPECT_EQ(q.flags, MC_FOC_ERR_NONE);
    EXPECT_EQ(mc_foc_q31_reset(nullptr), MC_FOC_ERR_NULL);
}

TEST(FocQ31, DqStepMatchesF32OnRandomWalks)
{
    // 40000 steps: references random-walk, the currents follow them with a
    // lag and noise (as in a running loop), speed and vbus wander; every
    // few thousand steps the speed jumps so the voltage limit acts for a
    // while: integrators, decoupling and anti-windup run in both kernels.
    const mc_foc_q31_cfg_t c = cfg();
    mc_foc_f32_t f{};
    mc_foc_q31_t q{};
    ASSERT_EQ(mc_foc_f32_init(&f, &c.f), 0u);
    ASSERT_EQ(mc_foc_q31_init(&q, &c), 0u);
    std::mt19937 rng(40);
    std::normal_distribution<double> n(0.0, 1.0);
    double idr = 0, iqr = 0, id = 0, iq = 0, w = 0, vb = 200;
    double worst_lin = 0.0;
    long limited = 0;
    for (int k = 0; k < 40000; ++k) {
        idr = std::clamp(idr + 0.02 * n(rng), -5.0, 5.0);
        iqr = std::clamp(iqr + 0.05 * n(rng), -15.0, 15.0);
        id += 0.05 * (idr - id) + 0.02 * n(rng);
        iq += 0.05 * (iqr - iq) + 0.02 * n(rng);
        w = std::clamp(w + 2.0 * n(rng), -900.0, 900.0);
        if (k % 5000 == 2500)
            w = (w > 0 ? -1.0 : 1.0) * 1400.0 * 0.6; // speed reversal
        vb = std::clamp(vb + 0.5 * n(rng), 100.0, 390.0);
        const q31_t q_idr = to_q(idr, kIb), q_iqr = to_q(iqr, kIb), q_id = to_q(id, kIb),
                    q_iq = to_q(iq, kIb), q_w = to_q(w, kWb), q_vb = to_q(vb, kVb);
        float vdf = 0, vqf = 0;
        ASSERT_EQ(mc_foc_f32_step_dq(
                      &f, static_cast<float>(from_q(q_idr, kIb)),
                      static_cast<float>(from_q(q_iqr, kIb)), static_cast<float>(from_q(q_id, kIb)),
                      static_cast<float>(from_q(q_iq, kIb)), static_cast<float>(from_q(q_w, kWb)),
                      static_cast<float>(from_q(q_vb, kVb)), &vdf, &vqf),
                  0u);
        q31_t vdq = 0, vqq = 0;
        ASSERT_EQ(mc_foc_q31_step_dq(&q, q_idr, q_iqr, q_id, q_iq, q_w, q_vb, &vdq, &vqq), 0u);
        const double err =
            std::max(std::abs(vdf - from_q(vdq, kVb)), std::abs(vqf - from_q(vqq, kVb)));
        const double vmax = 0.95 * from_q(q_vb, kVb) / std::sqrt(3.0);
        const bool lim = std::hypot(vdf, vqf) > vmax * 0.9999;
        limited += lim ? 1 : 0;
        // (the d-priority corner |v_d| ~ v_max, where the room
        // sqrt(v_max^2 - v_d^2) amplifies any rounding of v_d, is not
        // reached by this walk; FocQ31.ErrorsSaturateAtTheRangeEdges sits
        // in it)
        worst_lin = std::max(worst_lin, err);
    }
    // Bounds. Away from the corner: the f32 PI rounds its integrator and
    // output (ulp 7.6e-6 V at 100 V, a few per step, the integrator walk
    // bounded by the loop) and v_max (7e-8 relative of the ratio/sqrt(3)
    // constant in both): 2e-4 V (1070 LSB of the 400 V base, 1e-6 of the
    // bus).
    const double bound = 2.0e-4;
    report("foc |v_f32 - v_q31| (linear + circle)", worst_lin, bound, "V");
    report("foc same in LSB of the voltage base", worst_lin / kVb * kQ31, bound / kVb * kQ31,
           "LSB");
    std::printf("[ measured ] foc steps at the voltage limit: %ld of 40000\n", limited);
    EXPECT_LE(worst_lin, bound);
    EXPECT_GT(limited, 100); // the limit path was exercised
}

TEST(FocQ31, FullStepDutiesMatchF32)
{
    // One fast step from random states: Clarke, Park at a random angle, dq
    // step, inverse Park, SVPWM. Duties in LSB of q31 (2^-31).
    const mc_foc_q31_cfg_t c = cfg();
    std::mt19937 rng(41);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    double worst = 0.0;
    for (int k = 0; k < 5000; ++k) {
        mc_foc_f32_t f{};
        mc_foc_q31_t q{};
        ASSERT_EQ(mc_foc_f32_init(&f, &c.f), 0u);
        ASSERT_EQ(mc_foc_q31_init(&q, &c), 0u);
        mc_foc_q31_in_t qi{};
        qi.ia = to_q(15.0 * u(rng), kIb);
        qi.ib = to_q(15.0 * u(rng), kIb);
        qi.three_phase = false;
        qi.theta_e = ang_q(kPi * u(rng));
        qi.omega_e = to_q(800.0 * u(rng), kWb);
        qi.vbus = to_q(250.0 + 100.0 * u(rng), kVb);
        qi.id_ref = to_q(2.0 * u(rng), kIb);
        qi.iq_ref = to_q(10.0 * u(rng), kIb);
        mc_foc_f32_in_t fi{};
        fi.ia_a = static_cast<float>(from_q(qi.ia, kIb));
        fi.ib_a = static_cast<float>(from_q(qi.ib, kIb));
        fi.three_phase = false;
        fi.theta_e_rad = static_cast<float>(ang_rad(qi.theta_e));
        fi.omega_e_rad_s = static_cast<float>(from_q(qi.omega_e, kWb));
        fi.vbus_v = static_cast<float>(from_q(qi.vbus, kVb));
        fi.id_ref_a = static_cast<float>(from_q(qi.id_ref, kIb));
        fi.iq_ref_a = static_cast<float>(from_q(qi.iq_ref, kIb));
        mc_foc_f32_out_t fo{};
        mc_foc_q31_out_t qo{};
        ASSERT_EQ(mc_foc_f32_step(&f, &fi, &fo), 0u);
        ASSERT_EQ(mc_foc_q31_step(&q, &qi, &qo), 0u);
        const double d[3] = {fo.duty_a - from_q(qo.duty_a, 1.0), fo.duty_b - from_q(qo.duty_b, 1.0),
                             fo.duty_c - from_q(qo.duty_c, 1.0)};
        for (double v : d)
            worst = std::max(worst, std::abs(v));
    }
    // Bound: the f32 chain (sincos 1e-7, transforms and SVPWM a few ulp of
    // 1) gives duties within ~1e-6; q31 within 4 LSB (mc_svpwm.h). 5e-6.
    const double bound = 5.0e-6;
    report("foc full step |duty_f32 - duty_q31|", worst, bound, "1");
    EXPECT_LE(worst, bound);
}

TEST(FocQ31, ErrorsSaturateAtTheRangeEdges)
{
    // References at +full scale, currents at -full scale: the current error
    // saturates at +1 base (a wrap would make it negative), the PIs drive
    // the voltage to the limit with the right sign, and keep it there.
    const mc_foc_q31_cfg_t c = cfg();
    mc_foc_q31_t q{};
    ASSERT_EQ(mc_foc_q31_init(&q, &c), 0u);
    const q31_t vbus = to_q(200.0, kVb);
    const double vmax = 0.95 * 200.0 / std::sqrt(3.0);
    q31_t vd = 0, vq = 0;
    for (int k = 0; k < 100; ++k) {
        ASSERT_EQ(mc_foc_q31_step_dq(&q, MC_Q31_MAX, MC_Q31_MAX, MC_Q31_MIN, MC_Q31_MIN, MC_Q31_MAX,
                                     vbus, &vd, &vq),
                  0u);
        ASSERT_GT(vd, 0);
        ASSERT_GE(vq, 0);
    }
    // d priority: all of it; 2e-5 V: the float constant ratio/sqrt(3) (2 ulp)
    EXPECT_NEAR(from_q(vd, kVb), vmax, 2.0e-5);
    EXPECT_NEAR(from_q(vq, kVb), 0.0, 1e-3);
    // opposite corner, speed at -full scale
    for (int k = 0; k < 100; ++k) {
        ASSERT_EQ(mc_foc_q31_step_dq(&q, MC_Q31_MIN, MC_Q31_MIN, MC_Q31_MAX, MC_Q31_MAX, MC_Q31_MIN,
                                     vbus, &vd, &vq),
                  0u);
    }
    EXPECT_NEAR(from_q(vd, kVb), -vmax, 2.0e-5);
    // vbus <= 0: refused, zero voltage, sticky flag
    EXPECT_EQ(mc_foc_q31_step_dq(&q, 0, 0, 0, 0, 0, 0, &vd, &vq), MC_FOC_ERR_VBUS);
    EXPECT_EQ(vd, 0);
    EXPECT_NE(q.flags & MC_FOC_ERR_VBUS, 0u);
}
