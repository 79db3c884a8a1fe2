// The current loop's computation-delay compensation (firmware/kernels/foc,
// README "Computation-delay compensation"): the voltage angle of the f32
// and q31 kernels against the closed form theta + 1.5 T omega, the whole
// steps' inverse Park at that angle (and the Park of the currents at the
// sampled one), switching it off, and the setter's rules.
#include <gtest/gtest.h>

#include <cmath>
#include <algorithm>
#include <cstdint>
#include <limits>
#include <random>

extern "C" {
#include "foc/mc_foc.h"
#include "foc/mc_foc_q31.h"
}

namespace
{

constexpr double kPi = 3.14159265358979323846;
constexpr double kTwo31 = 2147483648.0;
// 24 kHz; speed base 20000 rad/s (omega_e T up to 0.83 rad)
constexpr float kDt = 1.0f / 24000.0f;
constexpr double kWb = 20000.0, kIb = 50.0, kVb = 100.0;

mc_foc_f32_cfg_t Cfg()
{
    mc_foc_f32_cfg_t c{};
    c.r_ohm = 0.13f;
    c.ld_h = 80e-6f;
    c.lq_h = 80e-6f;
    c.flux_wb = 2.63e-3f;
    float kp = 0.0f;
    float ki = 0.0f;
    EXPECT_EQ(mc_foc_f32_gains_from_bandwidth(0.13f, 80e-6f, 3000.0f, &kp, &ki), 0u);
    c.kp_d_v_per_a = kp;
    c.ki_d_v_per_as = ki;
    c.kp_q_v_per_a = kp;
    c.ki_q_v_per_as = ki;
    c.dt_s = kDt;
    c.aw = MC_PI_AW_CLAMP;
    c.limit_mode = MC_SVPWM_LIMIT_CIRCLE;
    c.v_limit_ratio = 0.95f;
    c.v_abs_max_v = 60.0f;
    c.decouple = true;
    return c;
}

mc_foc_q31_cfg_t CfgQ31()
{
    mc_foc_q31_cfg_t c{};
    c.f = Cfg();
    c.i_base_a = static_cast<float>(kIb);
    c.v_base_v = static_cast<float>(kVb);
    c.omega_base_rad_s = static_cast<float>(kWb);
    return c;
}

// wrap to [-pi, pi)
double Wrap(double x)
{
    return x - 2.0 * kPi * std::floor((x + kPi) / (2.0 * kPi));
}

q31_t AngQ(double rad)
{
    return static_cast<q31_t>(std::lround(Wrap(rad) / kPi * kTwo31) & 0xFFFFFFFFll);
}

double AngRad(q31_t a)
{
    return static_cast<double>(a) / kTwo31 * kPi;
}

TEST(FocDelay, VoltageAngleF32AndQ31MatchTheClosedForm)
{
    mc_foc_f32_t f{};
    mc_foc_q31_t q{};
    const mc_foc_q31_cfg_t c = CfgQ31();
    ASSERT_EQ(mc_foc_f32_init(&f, &c.f), 0u);
    ASSERT_EQ(mc_foc_q31_init(&q, &c), 0u);
    EXPECT_EQ(f.delay_comp_periods, MC_FOC_DELAY_COMP_PERIODS); // on from init
    EXPECT_EQ(q.delay_comp_periods, MC_FOC_DELAY_COMP_PERIODS);
    std::mt19937 rng(31);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    double worst_f = 0.0, worst_q = 0.0, worst_fq = 0.0;
    for (int k = 0; k < 20000; ++k) {
        const q31_t th_q = AngQ(kPi * u(rng));
        const q31_t w_q = static_cast<q31_t>(std::lround(0.999 * u(rng) * kTwo31));
        const double th = AngRad(th_q);
        const double w = static_cast<double>(w_q) / kTwo31 * kWb;
        const double want = th + 1.5 * static_cast<double>(kDt) * w; // the closed form
        const double got_f =
            mc_foc_f32_eval_voltage_angle(&f, static_cast<float>(th), static_cast<float>(w));
        const double got_q = AngRad(mc_foc_q31_eval_voltage_angle(&q, th_q, w_q));
        worst_f = std::max(worst_f, std::abs(got_f - want));
        worst_q = std::max(worst_q, std::abs(Wrap(got_q - want)));
        worst_fq = std::max(worst_fq, std::abs(Wrap(got_q - got_f)));
    }
    // f32: theta and omega rounded to float (|theta| <= pi: 1.2e-7 each),
    // adv_s = fl(1.5 dt) and one multiply-add (relative 2^-23 of the
    // advance, <= 1.25 rad): below 1e-6 rad.
    EXPECT_LE(worst_f, 1e-6);
    // q31: the gain 1.5 dt omega_base / pi held from a float (relative
    // 2^-23 of the advance: 1.5e-7 rad), the product rounded to a q31 turn
    // (0.5 LSB = 7.3e-10 rad): below 5e-7 rad.
    EXPECT_LE(worst_q, 5e-7);
    EXPECT_LE(worst_fq, 1.5e-6); // the two bounds together
    RecordProperty("worst_f32_rad", std::to_string(worst_f));
    RecordProperty("worst_q31_rad", std::to_string(worst_q));
}

TEST(FocDelay, Q31AngleWrapsAtHalfATurn)
{
    mc_foc_q31_t q{};
    const mc_foc_q31_cfg_t c = CfgQ31();
    ASSERT_EQ(mc_foc_q31_init(&q, &c), 0u);
    // theta just below +pi, omega +0.5 pu (10000 rad/s: +0.625 rad): the
    // voltage angle comes out near -pi + 0.625 + 0.01, not saturated at pi.
    const double th = kPi - 0.01;
    const q31_t w_q = static_cast<q31_t>(1) << 30;
    const double got = AngRad(mc_foc_q31_eval_voltage_angle(&q, AngQ(th), w_q));
    EXPECT_NEAR(got, Wrap(th + 1.5 * static_cast<double>(kDt) * 10000.0), 1e-6);
    EXPECT_LT(got, 0.0);
}

// The angle of (v_alpha, v_beta) minus the angle of (v_d, v_q): the angle
// the inverse Park ran at.
double InvParkAngle(double va, double vb, double vd, double vq)
{
    return Wrap(std::atan2(vb, va) - std::atan2(vq, vd));
}

TEST(FocDelay, WholeStepsInvertParkAtTheVoltageAngle)
{
    const mc_foc_q31_cfg_t c = CfgQ31();
    const double th = 0.7, w = 12000.0; // omega_e T = 0.5
    for (const float periods : {MC_FOC_DELAY_COMP_PERIODS, 0.0f, 2.5f}) {
        mc_foc_f32_t f{};
        mc_foc_q31_t q{};
        ASSERT_EQ(mc_foc_f32_init(&f, &c.f), 0u);
        ASSERT_EQ(mc_foc_q31_init(&q, &c), 0u);
        ASSERT_EQ(mc_foc_f32_set_delay_comp(&f, periods), 0u);
        ASSERT_EQ(mc_foc_q31_set_delay_comp(&q, periods), 0u);
        // phase currents of i_d = 2 A, i_q = 5 A at the sampled angle
        const double ia = 2.0 * std::cos(th) - 5.0 * std::sin(th);
        const double ib_al = 2.0 * std::sin(th) + 5.0 * std::cos(th);
        const double ib = -0.5 * ia + std::sqrt(3.0) / 2.0 * ib_al;
        mc_foc_f32_in_t fi{};
        fi.ia_a = static_cast<float>(ia);
        fi.ib_a = static_cast<float>(ib);
        fi.theta_e_rad = static_cast<float>(th);
        fi.omega_e_rad_s = static_cast<float>(w);
        fi.vbus_v = 56.0f;
        fi.id_ref_a = 0.0f;
        fi.iq_ref_a = 8.0f;
        mc_foc_f32_out_t fo{};
        ASSERT_EQ(mc_foc_f32_step(&f, &fi, &fo), 0u);
        // the currents at their sampling angle: float transforms, 1e-5 A
        EXPECT_NEAR(fo.id_a, 2.0, 1e-5);
        EXPECT_NEAR(fo.iq_a, 5.0, 1e-5);
        const double want = Wrap(th + periods * static_cast<double>(kDt) * w);
        // float sin/cos (2e-7) and the transforms on |v| ~ 30 V: 1e-5 rad
        EXPECT_NEAR(InvParkAngle(fo.v_alpha_v, fo.v_beta_v, fo.vd_v, fo.vq_v), want, 1e-5)
            << "periods " << periods;

        mc_foc_q31_in_t qi{};
        qi.ia = static_cast<q31_t>(std::lround(ia / kIb * kTwo31));
        qi.ib = static_cast<q31_t>(std::lround(ib / kIb * kTwo31));
        qi.theta_e = AngQ(th);
        qi.omega_e = static_cast<q31_t>(std::lround(w / kWb * kTwo31));
        qi.vbus = static_cast<q31_t>(std::lround(56.0 / kVb * kTwo31));
        qi.id_ref = 0;
        qi.iq_ref = static_cast<q31_t>(std::lround(8.0 / kIb * kTwo31));
        mc_foc_q31_out_t qo{};
        ASSERT_EQ(mc_foc_q31_step(&q, &qi, &qo), 0u);
        // q31 sin/cos (1.4e-9) and transforms (a few LSB on ~2^29): 1e-6 rad
        EXPECT_NEAR(InvParkAngle(qo.v_alpha, qo.v_beta, qo.vd, qo.vq), want, 1e-6)
            << "periods " << periods;
    }
}

TEST(FocDelay, DecouplingPredictionWeight)
{
    // w = min(1, periods dt kp / L): 1.5 dt bw with bw = 3000 rad/s here
    // (0.1875), 0 with the compensation off, 1 at the clamp; the q31 twin's
    // the same as a q31 fraction (float products: 1e-6 relative; q31
    // rounding 0.5 LSB).
    mc_foc_f32_t f{};
    mc_foc_q31_t q{};
    const mc_foc_q31_cfg_t c = CfgQ31();
    ASSERT_EQ(mc_foc_f32_init(&f, &c.f), 0u);
    ASSERT_EQ(mc_foc_q31_init(&q, &c), 0u);
    for (const float periods : {MC_FOC_DELAY_COMP_PERIODS, 0.0f, MC_FOC_DELAY_COMP_MAX}) {
        ASSERT_EQ(mc_foc_f32_set_delay_comp(&f, periods), 0u);
        ASSERT_EQ(mc_foc_q31_set_delay_comp(&q, periods), 0u);
        const double want = std::min(1.0, periods * static_cast<double>(kDt) * 3000.0);
        EXPECT_NEAR(f.pred_d, want, 1e-6 * want + 1e-12);
        EXPECT_NEAR(f.pred_q, want, 1e-6 * want + 1e-12);
        EXPECT_NEAR(q.pred_d / kTwo31, want, 1e-6 * want + 1e-9);
        EXPECT_NEAR(q.pred_q / kTwo31, want, 1e-6 * want + 1e-9);
    }
    // With the compensation off the step is the kernel as it was: the
    // decoupling from the measured currents, the inverse Park at theta
    // (WholeStepsInvertParkAtTheVoltageAngle covers the angle); here the
    // d voltage at a zero error carries exactly -omega L_q i_q.
    ASSERT_EQ(mc_foc_f32_set_delay_comp(&f, 0.0f), 0u);
    float vd = 0.0f, vq = 0.0f;
    ASSERT_EQ(mc_foc_f32_step_dq(&f, 0.0f, 5.0f, 0.0f, 5.0f, 10000.0f, 56.0f, &vd, &vq), 0u);
    EXPECT_FLOAT_EQ(vd, -10000.0f * 80e-6f * 5.0f);
    // On: the q current predicted 0.1875 of the way to its reference (0 A
    // measured, 8 A wanted: 1.5 A), no integral yet on d (zero error).
    mc_foc_f32_t g{};
    ASSERT_EQ(mc_foc_f32_init(&g, &c.f), 0u);
    ASSERT_EQ(mc_foc_f32_step_dq(&g, 0.0f, 8.0f, 0.0f, 0.0f, 10000.0f, 56.0f, &vd, &vq), 0u);
    EXPECT_NEAR(vd, -10000.0 * 80e-6 * (1.5 * static_cast<double>(kDt) * 3000.0 * 8.0), 1e-5);
}

TEST(FocDelay, SetterRulesAndResetKeepsIt)
{
    mc_foc_f32_t f{};
    mc_foc_q31_t q{};
    const mc_foc_q31_cfg_t c = CfgQ31();
    ASSERT_EQ(mc_foc_f32_init(&f, &c.f), 0u);
    ASSERT_EQ(mc_foc_q31_init(&q, &c), 0u);
    ASSERT_EQ(mc_foc_f32_set_delay_comp(&f, 2.0f), 0u);
    ASSERT_EQ(mc_foc_q31_set_delay_comp(&q, 2.0f), 0u);
    for (const float bad : {-0.1f, 4.01f, std::numeric_limits<float>::quiet_NaN(),
                            std::numeric_limits<float>::infinity()}) {
        EXPECT_EQ(mc_foc_f32_set_delay_comp(&f, bad), MC_FOC_ERR_DELAY);
        EXPECT_EQ(mc_foc_q31_set_delay_comp(&q, bad), MC_FOC_ERR_DELAY);
        EXPECT_EQ(f.delay_comp_periods, 2.0f); // nothing changed
        EXPECT_EQ(f.adv_s, 2.0f * kDt);
        EXPECT_EQ(q.delay_comp_periods, 2.0f);
    }
    EXPECT_EQ(mc_foc_f32_set_delay_comp(nullptr, 1.0f), MC_FOC_ERR_NULL);
    EXPECT_EQ(mc_foc_q31_set_delay_comp(nullptr, 1.0f), MC_FOC_ERR_NULL);
    ASSERT_EQ(mc_foc_f32_reset(&f), 0u);
    ASSERT_EQ(mc_foc_q31_reset(&q), 0u);
    EXPECT_EQ(f.delay_comp_periods, 2.0f);
    EXPECT_EQ(q.delay_comp_periods, 2.0f);
    EXPECT_EQ(mc_foc_f32_set_delay_comp(&f, MC_FOC_DELAY_COMP_MAX), 0u); // the edge is valid
}

} // namespace
