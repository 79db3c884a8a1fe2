// Unit tests of the dq current controller and the whole FOC fast step
// (firmware/kernels/foc). Every tolerance carries the reason for its size.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "foc/mc_foc.h"

namespace
{

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr double kPi = 3.14159265358979323846;

// Motor and loop of the tests: 0.1 ohm, 100 uH, 20 kHz, bandwidth 1000 rad/s
// (bw*dt = 0.05: the loop is well sampled).
constexpr float kR = 0.1f;
constexpr float kL = 100e-6f;
constexpr float kDt = 50e-6f;
constexpr float kBw = 1000.0f;

mc_foc_f32_cfg_t BaseCfg()
{
    mc_foc_f32_cfg_t c{};
    c.r_ohm = kR;
    c.ld_h = kL;
    c.lq_h = kL;
    c.flux_wb = 0.01f;
    float kp = 0.0f;
    float ki = 0.0f;
    EXPECT_EQ(mc_foc_f32_gains_from_bandwidth(kR, kL, kBw, &kp, &ki), MC_FOC_ERR_NONE);
    c.kp_d_v_per_a = kp;
    c.ki_d_v_per_as = ki;
    c.kp_q_v_per_a = kp;
    c.ki_q_v_per_as = ki;
    c.dt_s = kDt;
    c.aw = MC_PI_AW_CLAMP;
    c.kaw_per_s = 1000.0f;
    c.limit_mode = MC_SVPWM_LIMIT_CIRCLE;
    c.v_limit_ratio = 1.0f;
    c.v_abs_max_v = 50.0f;
    c.decouple = true;
    return c;
}

// Exact discretisation of one R-L axis driven by a voltage held over the
// period (zero-order hold): i[k+1] = a i[k] + b v[k], a = exp(-R dt / L),
// b = (1 - a) / R. Computed in double, independent of the kernels' math.
struct RlAxis {
    double a, b;
    RlAxis(double r, double l, double dt) : a(std::exp(-r * dt / l)), b((1.0 - a) / r)
    {
    }
    double Next(double i, double v) const
    {
        return a * i + b * v;
    }
};

TEST(FocF32, GainsFromBandwidth)
{
    float kp = 0.0f;
    float ki = 0.0f;
    ASSERT_EQ(mc_foc_f32_gains_from_bandwidth(0.2f, 1e-3f, 500.0f, &kp, &ki), MC_FOC_ERR_NONE);
    // One float multiply each: relative error below 2^-24 (tolerance 1e-7 relative).
    EXPECT_NEAR(kp, 0.5, 0.5e-7);
    EXPECT_NEAR(ki, 100.0, 100e-7);
    float kp2 = 7.0f;
    float ki2 = 7.0f;
    EXPECT_EQ(mc_foc_f32_gains_from_bandwidth(-1.0f, 1e-3f, 500.0f, &kp2, &ki2), MC_FOC_ERR_MOTOR);
    EXPECT_EQ(mc_foc_f32_gains_from_bandwidth(0.2f, 0.0f, 500.0f, &kp2, &ki2), MC_FOC_ERR_MOTOR);
    EXPECT_EQ(mc_foc_f32_gains_from_bandwidth(0.2f, 1e-3f, kNaN, &kp2, &ki2), MC_FOC_ERR_BW);
    EXPECT_EQ(mc_foc_f32_gains_from_bandwidth(0.2f, 1e-3f, -5.0f, &kp2, &ki2), MC_FOC_ERR_BW);
    EXPECT_EQ(mc_foc_f32_gains_from_bandwidth(0.2f, 1e-3f, 5.0f, nullptr, &ki2), MC_FOC_ERR_NULL);
    EXPECT_EQ(kp2, 7.0f); // nothing written on error
    EXPECT_EQ(ki2, 7.0f);
}

TEST(FocF32, ClosedLoopStepMatchesDesignedBandwidth)
{
    // Both axes on the exact R-L model, omega = 0, steps of 10 A (q) and
    // -4 A (d). With kp = L bw, ki = R bw the continuous loop is
    // bw / (s + bw): i(t) = i_ref (1 - exp(-bw t)).
    // Tolerances (bw*dt = 0.05):
    // - time constant: the response crosses 63.2 % at sample 20 = 1/(bw dt);
    //   allowed +-1 sample (5 %), the resolution of a sampled crossing.
    // - shape: |i[k] - i(t_k)| <= 2.5 % of the step. The sampled loop (held
    //   voltage, backward-Euler integral, zero of the PI at 1/(1 + R dt/L)
    //   instead of exactly on the plant pole exp(-R dt/L)) differs from the
    //   continuous one by about 0.3 bw dt = 1.5 % at its worst, early on.
    // - after 20 time constants: within 0.5 % of the reference (the slow
    //   residual mode of the imperfect cancellation decays with R/L).
    mc_foc_f32_cfg_t c = BaseCfg();
    mc_foc_f32_t st;
    ASSERT_EQ(mc_foc_f32_init(&st, &c), MC_FOC_ERR_NONE);
    const RlAxis axis(kR, kL, kDt);
    const double iq_ref = 10.0;
    const double id_ref = -4.0;
    double id = 0.0;
    double iq = 0.0;
    int k63_q = -1;
    int k63_d = -1;
    double worst_q = 0.0;
    double worst_d = 0.0;
    for (int k = 1; k <= 400; ++k) {
        float vd = 0.0f;
        float vq = 0.0f;
        ASSERT_EQ(mc_foc_f32_step_dq(&st, static_cast<float>(id_ref), static_cast<float>(iq_ref),
                                     static_cast<float>(id), static_cast<float>(iq), 0.0f, 24.0f,
                                     &vd, &vq),
                  MC_FOC_ERR_NONE);
        id = axis.Next(id, vd);
        iq = axis.Next(iq, vq);
        const double shape = 1.0 - std::exp(-static_cast<double>(kBw) * k * kDt);
        worst_q = std::max(worst_q, std::fabs(iq - iq_ref * shape) / iq_ref);
        worst_d = std::max(worst_d, std::fabs(id - id_ref * shape) / -id_ref);
        if (k63_q < 0 && iq >= iq_ref * (1.0 - std::exp(-1.0))) {
            k63_q = k;
        }
        if (k63_d < 0 && id <= id_ref * (1.0 - std::exp(-1.0))) {
            k63_d = k;
        }
    }
    EXPECT_NEAR(k63_q, 20, 1);
    EXPECT_NEAR(k63_d, 20, 1);
    EXPECT_LT(worst_q, 0.025);
    EXPECT_LT(worst_d, 0.025);
    EXPECT_NEAR(iq, iq_ref, 0.005 * iq_ref);
    EXPECT_NEAR(id, id_ref, 0.005 * -id_ref);
}

TEST(FocF32, DecouplingTermsAreExact)
{
    // Zero current error and fresh integrators: the PI outputs are exactly
    // 0, so vd, vq are the feed-forward terms alone:
    //   vd = -omega Lq iq,   vq = omega Ld id + omega psi.
    // Tolerance 2e-6 relative: a few float roundings (2^-24 each).
    mc_foc_f32_cfg_t c = BaseCfg();
    c.ld_h = 80e-6f;
    c.lq_h = 120e-6f;
    c.flux_wb = 0.012f;
    for (float omega : {1500.0f, -800.0f, 0.0f}) {
        mc_foc_f32_t st;
        ASSERT_EQ(mc_foc_f32_init(&st, &c), MC_FOC_ERR_NONE);
        const double id = -3.0;
        const double iq = 5.0;
        float vd = 0.0f;
        float vq = 0.0f;
        ASSERT_EQ(mc_foc_f32_step_dq(&st, -3.0f, 5.0f, -3.0f, 5.0f, omega, 48.0f, &vd, &vq),
                  MC_FOC_ERR_NONE);
        const double vd_expect = -static_cast<double>(omega) * 120e-6 * iq;
        const double vq_expect = static_cast<double>(omega) * (80e-6 * id + 0.012);
        EXPECT_NEAR(vd, vd_expect, 2e-6 * std::fabs(vd_expect) + 1e-12);
        EXPECT_NEAR(vq, vq_expect, 2e-6 * std::fabs(vq_expect) + 1e-12);
    }
    // Decoupling off: nothing added (exactly 0).
    c.decouple = false;
    mc_foc_f32_t st;
    ASSERT_EQ(mc_foc_f32_init(&st, &c), MC_FOC_ERR_NONE);
    float vd = 1.0f;
    float vq = 1.0f;
    ASSERT_EQ(mc_foc_f32_step_dq(&st, -3.0f, 5.0f, -3.0f, 5.0f, 1500.0f, 48.0f, &vd, &vq),
              MC_FOC_ERR_NONE);
    EXPECT_EQ(vd, 0.0f);
    EXPECT_EQ(vq, 0.0f);
}

// Closed loop on the PMSM dq model with the speed terms held over each
// period (taken from the currents at the start of the period):
//   id+ = a id + b (vd + w Lq iq),   iq+ = a iq + b (vq - w Ld id - w psi).
// Returns the worst deviation of iq from the omega = 0 response.
double CoupledRunWorstDeviation(bool decouple, double omega)
{
    mc_foc_f32_cfg_t c = BaseCfg();
    c.decouple = decouple;
    mc_foc_f32_t st0;
    mc_foc_f32_t st;
    EXPECT_EQ(mc_foc_f32_init(&st0, &c), MC_FOC_ERR_NONE);
    EXPECT_EQ(mc_foc_f32_init(&st, &c), MC_FOC_ERR_NONE);
    // this plant applies the voltage at once (no computation delay): the
    // delay compensation is off (tests/unit/foc/test_foc_delay.cpp)
    EXPECT_EQ(mc_foc_f32_set_delay_comp(&st0, 0.0f), MC_FOC_ERR_NONE);
    EXPECT_EQ(mc_foc_f32_set_delay_comp(&st, 0.0f), MC_FOC_ERR_NONE);
    const RlAxis axis(kR, kL, kDt);
    double id0 = 0.0, iq0 = 0.0, id = 0.0, iq = 0.0, worst = 0.0;
    for (int k = 0; k < 400; ++k) {
        float vd0, vq0, vd, vq;
        EXPECT_EQ(mc_foc_f32_step_dq(&st0, -2.0f, 10.0f, static_cast<float>(id0),
                                     static_cast<float>(iq0), 0.0f, 48.0f, &vd0, &vq0),
                  MC_FOC_ERR_NONE);
        EXPECT_EQ(mc_foc_f32_step_dq(&st, -2.0f, 10.0f, static_cast<float>(id),
                                     static_cast<float>(iq), static_cast<float>(omega), 48.0f, &vd,
                                     &vq),
                  MC_FOC_ERR_NONE);
        id0 = axis.Next(id0, vd0);
        iq0 = axis.Next(iq0, vq0);
        const double id_next = axis.Next(id, vd + omega * kL * iq);
        const double iq_next =
            axis.Next(iq, vq - omega * kL * id - omega * static_cast<double>(0.01f));
        id = id_next;
        iq = iq_next;
        worst = std::max(worst, std::fabs(iq - iq0) + std::fabs(id - id0));
    }
    return worst;
}

TEST(FocF32, DecouplingCancelsTheSpeedTermsInClosedLoop)
{
    // With decoupling the coupled plant behaves as at standstill: the only
    // differences are float roundings of the feed-forward (volts ~ 20 V,
    // 2^-24 relative, times b ~ 0.5 A/V, accumulated over the run):
    // tolerance 1e-3 A on a 10 A step. Without decoupling the back-EMF
    // (omega psi = 20 V) and cross terms move the currents by amperes.
    const double omega = 2000.0;
    EXPECT_LT(CoupledRunWorstDeviation(true, omega), 1e-3);
    EXPECT_GT(CoupledRunWorstDeviation(false, omega), 0.5);
}

TEST(FocF32, DAxisPriorityVoltageLimit)
{
    // vbus = 12 V, circle: v_max = 12/sqrt(3) = 6.93 V. kp = 1 V/A, ki
    // small. A d error of 5 A asks vd = 5 V (+ one integral increment); a
    // q error of 100 A asks far more than is left.
    mc_foc_f32_cfg_t c = BaseCfg();
    c.kp_d_v_per_a = 1.0f;
    c.kp_q_v_per_a = 1.0f;
    c.ki_d_v_per_as = 100.0f;
    c.ki_q_v_per_as = 100.0f;
    c.decouple = false;
    mc_foc_f32_t st;
    ASSERT_EQ(mc_foc_f32_init(&st, &c), MC_FOC_ERR_NONE);
    const double v_max = 12.0 / std::sqrt(3.0);
    float vd = 0.0f;
    float vq = 0.0f;
    ASSERT_EQ(mc_foc_f32_step_dq(&st, 5.0f, 100.0f, 0.0f, 0.0f, 0.0f, 12.0f, &vd, &vq),
              MC_FOC_ERR_NONE);
    // vd is what the d PI alone gives (not reduced): 5 + 100*50e-6*5.
    // Tolerance 1e-6: two float roundings near 5 (ulp(8)/2 = 4.8e-7).
    EXPECT_NEAR(vd, 5.025, 1e-6);
    // vq takes what is left of the circle; |v| never exceeds v_max.
    // Tolerance 1e-5 V: float v_max and sqrt, relative 2^-23 on ~7 V.
    EXPECT_NEAR(vq, std::sqrt(v_max * v_max - 5.025 * 5.025), 1e-5);
    EXPECT_LE(std::hypot(vd, vq), v_max * (1.0 + 1e-6));

    // A d demand beyond the circle: vd = v_max, nothing left for q.
    // Tolerance 1e-5 V as above.
    ASSERT_EQ(mc_foc_f32_step_dq(&st, 100.0f, 100.0f, 0.0f, 0.0f, 0.0f, 12.0f, &vd, &vq),
              MC_FOC_ERR_NONE);
    EXPECT_NEAR(vd, v_max, 1e-5);
    EXPECT_NEAR(vq, 0.0, 1e-5);

    // Negative demands mirror it.
    ASSERT_EQ(mc_foc_f32_init(&st, &c), MC_FOC_ERR_NONE);
    ASSERT_EQ(mc_foc_f32_step_dq(&st, -5.0f, -100.0f, 0.0f, 0.0f, 0.0f, 12.0f, &vd, &vq),
              MC_FOC_ERR_NONE);
    EXPECT_NEAR(vd, -5.025, 1e-6);
    EXPECT_NEAR(vq, -std::sqrt(v_max * v_max - 5.025 * 5.025), 1e-5);
}

TEST(FocF32, AntiWindupSeesTheAppliedLimit)
{
    // A long q saturation against the circle, then the q error reverses:
    // because the q PI's limit was the circle remainder, its integrator did
    // not wind up and vq leaves the limit at the first reversed step.
    // With MC_PI_AW_NONE it stays pinned for many steps (the integrator
    // holds up to v_abs_max = 50 V against a limit of 6.9 V).
    for (mc_pi_aw_t aw : {MC_PI_AW_CLAMP, MC_PI_AW_BACK_CALC, MC_PI_AW_NONE}) {
        mc_foc_f32_cfg_t c = BaseCfg();
        c.aw = aw;
        c.decouple = false;
        mc_foc_f32_t st;
        ASSERT_EQ(mc_foc_f32_init(&st, &c), MC_FOC_ERR_NONE);
        float vd = 0.0f;
        float vq = 0.0f;
        for (int k = 0; k < 2000; ++k) {
            ASSERT_EQ(mc_foc_f32_step_dq(&st, 0.0f, 200.0f, 0.0f, 0.0f, 0.0f, 12.0f, &vd, &vq),
                      MC_FOC_ERR_NONE);
        }
        const float vq_sat = vq;
        int steps = 0;
        for (int k = 1; k <= 5000 && steps == 0; ++k) {
            ASSERT_EQ(mc_foc_f32_step_dq(&st, 0.0f, 0.0f, 0.0f, 10.0f, 0.0f, 12.0f, &vd, &vq),
                      MC_FOC_ERR_NONE);
            if (vq < vq_sat - 1e-3f) {
                steps = k;
            }
        }
        if (aw == MC_PI_AW_NONE) {
            EXPECT_GT(steps, 100) << "aw=" << aw;
        } else {
            EXPECT_EQ(steps, 1) << "aw=" << aw;
        }
    }
}

TEST(FocF32, NonFiniteInputGivesZeroVoltageAndKeepsIntegrators)
{
    mc_foc_f32_cfg_t c = BaseCfg();
    mc_foc_f32_t st;
    ASSERT_EQ(mc_foc_f32_init(&st, &c), MC_FOC_ERR_NONE);
    float vd = 0.0f;
    float vq = 0.0f;
    for (int k = 0; k < 10; ++k) {
        ASSERT_EQ(mc_foc_f32_step_dq(&st, 1.0f, 5.0f, 0.0f, 0.0f, 100.0f, 24.0f, &vd, &vq),
                  MC_FOC_ERR_NONE);
    }
    const mc_pi_f32_t pd = st.pi_d;
    const mc_pi_f32_t pq = st.pi_q;
    const float good[6] = {1.0f, 5.0f, 0.5f, 2.0f, 100.0f, 24.0f};
    for (int which = 0; which < 6; ++which) {
        for (float bad : {kNaN, kInf, -kInf}) {
            float in[6];
            std::memcpy(in, good, sizeof in);
            in[which] = bad;
            vd = 9.0f;
            vq = 9.0f;
            EXPECT_EQ(mc_foc_f32_step_dq(&st, in[0], in[1], in[2], in[3], in[4], in[5], &vd, &vq),
                      MC_FOC_ERR_NAN_INPUT)
                << which;
            EXPECT_EQ(vd, 0.0f);
            EXPECT_EQ(vq, 0.0f);
            EXPECT_EQ(std::memcmp(&pd, &st.pi_d, sizeof pd), 0) << which;
            EXPECT_EQ(std::memcmp(&pq, &st.pi_q, sizeof pq), 0) << which;
        }
    }
    EXPECT_EQ(st.flags, MC_FOC_ERR_NAN_INPUT);
    for (float vbus : {0.0f, -12.0f}) {
        EXPECT_EQ(mc_foc_f32_step_dq(&st, 1.0f, 5.0f, 0.0f, 0.0f, 100.0f, vbus, &vd, &vq),
                  MC_FOC_ERR_VBUS);
        EXPECT_EQ(vd, 0.0f);
        EXPECT_EQ(std::memcmp(&pd, &st.pi_d, sizeof pd), 0);
    }
    // Finite inputs whose feed-forward overflows (omega Ld id = 3e44): the
    // PI refuses, the FOC reports it, both integrators stay.
    EXPECT_EQ(mc_foc_f32_step_dq(&st, 1.0f, 5.0f, 1e10f, 0.0f, 3e38f, 24.0f, &vd, &vq),
              MC_FOC_ERR_PI);
    EXPECT_EQ(vq, 0.0f);
    EXPECT_EQ(std::memcmp(&pd, &st.pi_d, sizeof pd), 0);
    EXPECT_EQ(std::memcmp(&pq, &st.pi_q, sizeof pq), 0);
    // Sticky until reset; running again works meanwhile.
    EXPECT_EQ(mc_foc_f32_step_dq(&st, 1.0f, 5.0f, 0.0f, 0.0f, 100.0f, 24.0f, &vd, &vq),
              MC_FOC_ERR_NONE);
    EXPECT_EQ(st.flags, MC_FOC_ERR_NAN_INPUT | MC_FOC_ERR_VBUS | MC_FOC_ERR_PI);
    EXPECT_EQ(mc_foc_f32_reset(&st), MC_FOC_ERR_NONE);
    EXPECT_EQ(st.flags, MC_FOC_ERR_NONE);
    EXPECT_EQ(st.pi_d.integ, 0.0f);
    EXPECT_EQ(mc_foc_f32_reset(nullptr), MC_FOC_ERR_NULL);

    // The whole step: duties exactly 0.5, integrators untouched.
    ASSERT_EQ(mc_foc_f32_init(&st, &c), MC_FOC_ERR_NONE);
    mc_foc_f32_in_t in{};
    in.ia_a = 1.0f;
    in.ib_a = -0.5f;
    in.ic_a = -0.5f;
    in.three_phase = true;
    in.theta_e_rad = 0.3f;
    in.omega_e_rad_s = 100.0f;
    in.vbus_v = 24.0f;
    in.id_ref_a = 0.0f;
    in.iq_ref_a = 3.0f;
    mc_foc_f32_out_t out{};
    ASSERT_EQ(mc_foc_f32_step(&st, &in, &out), MC_FOC_ERR_NONE);
    const mc_foc_f32_t before = st;
    float *fields[] = {&in.ia_a,          &in.ib_a,   &in.ic_a,     &in.theta_e_rad,
                       &in.omega_e_rad_s, &in.vbus_v, &in.id_ref_a, &in.iq_ref_a};
    for (float *f : fields) {
        const float keep = *f;
        *f = kNaN;
        EXPECT_EQ(mc_foc_f32_step(&st, &in, &out), MC_FOC_ERR_NAN_INPUT);
        EXPECT_EQ(out.duty_a, 0.5f);
        EXPECT_EQ(out.duty_b, 0.5f);
        EXPECT_EQ(out.duty_c, 0.5f);
        EXPECT_EQ(out.vd_v, 0.0f);
        EXPECT_EQ(out.v_beta_v, 0.0f);
        EXPECT_EQ(out.flags, MC_FOC_ERR_NAN_INPUT);
        EXPECT_EQ(std::memcmp(&before.pi_d, &st.pi_d, sizeof st.pi_d), 0);
        EXPECT_EQ(std::memcmp(&before.pi_q, &st.pi_q, sizeof st.pi_q), 0);
        *f = keep;
    }
    // Two-phase measurement: ic is not read, a NaN there is harmless.
    in.three_phase = false;
    in.ic_a = kNaN;
    EXPECT_EQ(mc_foc_f32_step(&st, &in, &out), MC_FOC_ERR_NONE);
    EXPECT_EQ(mc_foc_f32_step(nullptr, &in, &out), MC_FOC_ERR_NULL);
}

// Inverse Park then inverse Clarke in double: phase voltages of vd, vq.
void PhaseVoltages(double vd, double vq, double th, double v[3])
{
    const double al = vd * std::cos(th) - vq * std::sin(th);
    const double be = vd * std::sin(th) + vq * std::cos(th);
    v[0] = al;
    v[1] = -0.5 * al + 0.5 * std::sqrt(3.0) * be;
    v[2] = -0.5 * al - 0.5 * std::sqrt(3.0) * be;
}

TEST(FocF32, WholeStepLineToLineMatchesInverseTransforms)
{
    // A constant dq reference at a given angle: the duties' average
    // line-to-line voltages (d_x - d_y) * vbus must be those of the applied
    // vd, vq through inverse Park and inverse Clarke (computed here in
    // double with libm). The measured currents are a balanced set for a
    // known id, iq at the same angle: the telemetry id, iq must match them.
    // Tolerances:
    // - line-to-line: 2e-5 * vbus. The angle enters through mc_sincos_f32
    //   (error ~1e-7) and the transforms and modulator are a few float
    //   operations on values below vbus (2^-24 relative each); 2e-5 leaves
    //   room for those and catches any wrong sign, axis or scale (1e-2).
    // - id, iq: 2e-5 * |i|, same reasoning.
    const double vbus = 24.0;
    const double id_true = 1.5;
    const double iq_true = -2.0;
    for (double th : {0.0, 0.7, 2.0, -1.2, 3.1, 5.5, 13.0}) {
        for (bool three : {false, true}) {
            for (mc_svpwm_limit_t mode : {MC_SVPWM_LIMIT_CIRCLE, MC_SVPWM_LIMIT_HEXAGON}) {
                mc_foc_f32_cfg_t c = BaseCfg();
                c.limit_mode = mode;
                mc_foc_f32_t st;
                ASSERT_EQ(mc_foc_f32_init(&st, &c), MC_FOC_ERR_NONE);
                double ph[3];
                PhaseVoltages(id_true, iq_true, th, ph); // same maths for currents
                mc_foc_f32_in_t in{};
                in.ia_a = static_cast<float>(ph[0]);
                in.ib_a = static_cast<float>(ph[1]);
                in.ic_a = static_cast<float>(ph[2]);
                in.three_phase = three;
                in.theta_e_rad = static_cast<float>(th);
                in.omega_e_rad_s = 300.0f;
                in.vbus_v = static_cast<float>(vbus);
                in.id_ref_a = 3.0f;
                in.iq_ref_a = 8.0f;
                mc_foc_f32_out_t out{};
                for (int k = 0; k < 5; ++k) {
                    ASSERT_EQ(mc_foc_f32_step(&st, &in, &out), MC_FOC_ERR_NONE);
                    EXPECT_NEAR(out.id_a, id_true, 2e-5 * 2.5);
                    EXPECT_NEAR(out.iq_a, iq_true, 2e-5 * 2.5);
                    double v[3];
                    // the inverse Park at the voltage angle theta + 1.5 T omega
                    // (mc_foc.h, computation delay)
                    PhaseVoltages(out.vd_v, out.vq_v,
                                  static_cast<double>(in.theta_e_rad) +
                                      1.5 * static_cast<double>(kDt) * in.omega_e_rad_s,
                                  v);
                    const double d[3] = {out.duty_a, out.duty_b, out.duty_c};
                    for (int p = 0; p < 3; ++p) {
                        const int n = (p + 1) % 3;
                        EXPECT_NEAR((d[p] - d[n]) * vbus, v[p] - v[n], 2e-5 * vbus)
                            << "th " << th << " phase " << p;
                        EXPECT_GE(d[p], 0.0);
                        EXPECT_LE(d[p], 1.0);
                    }
                    // Telemetry alpha/beta is inverse Park of vd, vq.
                    EXPECT_NEAR(out.v_alpha_v, v[0], 2e-5 * vbus);
                    // The voltage is not trivially zero.
                    EXPECT_GT(std::hypot(out.vd_v, out.vq_v), 0.5);
                }
            }
        }
    }
}

TEST(FocF32, HexagonCutIsFedBackToThePis)
{
    // Hexagon limit: the dq circle is 2 vbus / 3, but midway between two
    // vertices (voltage angle pi/6 + n pi/3) only vbus / sqrt(3) is
    // available. Asking the full circle there makes the modulator cut the
    // vector; the PIs must then hold the applied (cut) voltages as their
    // last outputs. Tolerance 1e-4 V: Park of the cut alpha/beta, a few
    // float roundings on ~14 V.
    mc_foc_f32_cfg_t c = BaseCfg();
    c.limit_mode = MC_SVPWM_LIMIT_HEXAGON;
    c.decouple = false;
    mc_foc_f32_t st;
    ASSERT_EQ(mc_foc_f32_init(&st, &c), MC_FOC_ERR_NONE);
    mc_foc_f32_in_t in{};
    in.theta_e_rad = static_cast<float>(kPi / 6.0); // d axis on a flat side
    in.vbus_v = 24.0f;
    in.id_ref_a = 100.0f; // kp*e = 10 V, the integrator adds up to the 16 V circle
    in.iq_ref_a = 0.0f;
    mc_foc_f32_out_t out{};
    for (int k = 0; k < 20; ++k) {
        ASSERT_EQ(mc_foc_f32_step(&st, &in, &out), MC_FOC_ERR_NONE);
    }
    EXPECT_NE(out.svpwm_flags & MC_SVPWM_FLAG_LIMITED, 0u);
    EXPECT_NEAR(out.vd_v, 24.0 / std::sqrt(3.0), 1e-4);
    EXPECT_NEAR(st.pi_d.out, out.vd_v, 1e-4);
    EXPECT_NEAR(st.pi_q.out, out.vq_v, 1e-4);
    // Clamp anti-windup: the d integrator holds what the cut output needs
    // (kp*e + I = applied, e = 100 A, kp = 0.1 V/A), not the 6 V the circle
    // would allow; tolerance 1e-3 V: one integral increment
    // (ki dt e = 5e-4 V) can sit on top before the next cut.
    EXPECT_NEAR(st.pi_d.integ + 0.1 * 100.0, out.vd_v, 1e-3);
}

TEST(FocF32, InitRejectsEveryBadRuleWithItsFlag)
{
    struct Case {
        const char *what;
        void (*mutate)(mc_foc_f32_cfg_t &);
        uint32_t flags;
    };
    const Case cases[] = {
        {"R < 0", [](mc_foc_f32_cfg_t &c) { c.r_ohm = -0.1f; }, MC_FOC_ERR_MOTOR},
        {"Ld = 0", [](mc_foc_f32_cfg_t &c) { c.ld_h = 0.0f; }, MC_FOC_ERR_MOTOR},
        {"Lq NaN", [](mc_foc_f32_cfg_t &c) { c.lq_h = kNaN; }, MC_FOC_ERR_MOTOR},
        {"psi < 0", [](mc_foc_f32_cfg_t &c) { c.flux_wb = -1.0f; }, MC_FOC_ERR_MOTOR},
        {"kp_d < 0", [](mc_foc_f32_cfg_t &c) { c.kp_d_v_per_a = -1.0f; }, MC_FOC_ERR_GAIN_D},
        {"ki_d NaN", [](mc_foc_f32_cfg_t &c) { c.ki_d_v_per_as = kNaN; }, MC_FOC_ERR_GAIN_D},
        {"kp_q inf", [](mc_foc_f32_cfg_t &c) { c.kp_q_v_per_a = kInf; }, MC_FOC_ERR_GAIN_Q},
        {"ki_q < 0", [](mc_foc_f32_cfg_t &c) { c.ki_q_v_per_as = -1.0f; }, MC_FOC_ERR_GAIN_Q},
        {"dt = 0", [](mc_foc_f32_cfg_t &c) { c.dt_s = 0.0f; }, MC_FOC_ERR_DT},
        {"limit mode", [](mc_foc_f32_cfg_t &c) { c.limit_mode = static_cast<mc_svpwm_limit_t>(5); },
         MC_FOC_ERR_LIMIT_MODE},
        {"ratio 0", [](mc_foc_f32_cfg_t &c) { c.v_limit_ratio = 0.0f; }, MC_FOC_ERR_V_LIMIT},
        {"ratio > 1", [](mc_foc_f32_cfg_t &c) { c.v_limit_ratio = 1.1f; }, MC_FOC_ERR_V_LIMIT},
        {"v_abs_max NaN", [](mc_foc_f32_cfg_t &c) { c.v_abs_max_v = kNaN; }, MC_FOC_ERR_V_LIMIT},
        {"aw unknown", [](mc_foc_f32_cfg_t &c) { c.aw = static_cast<mc_pi_aw_t>(9); },
         MC_FOC_ERR_AW},
        {"kaw*dt > 1",
         [](mc_foc_f32_cfg_t &c) {
             c.aw = MC_PI_AW_BACK_CALC;
             c.kaw_per_s = 1e6f;
         },
         MC_FOC_ERR_AW},
        {"R < 0 and dt NaN",
         [](mc_foc_f32_cfg_t &c) {
             c.r_ohm = -1.0f;
             c.dt_s = kNaN;
         },
         MC_FOC_ERR_MOTOR | MC_FOC_ERR_DT},
    };
    for (const Case &tc : cases) {
        mc_foc_f32_cfg_t c = BaseCfg();
        tc.mutate(c);
        mc_foc_f32_t st;
        std::memset(&st, 0x5A, sizeof st);
        mc_foc_f32_t before = st;
        EXPECT_EQ(mc_foc_f32_init(&st, &c), tc.flags) << tc.what;
        EXPECT_EQ(std::memcmp(&before, &st, sizeof st), 0) << tc.what;
    }
    mc_foc_f32_cfg_t c = BaseCfg();
    mc_foc_f32_t st;
    EXPECT_EQ(mc_foc_f32_init(nullptr, &c), MC_FOC_ERR_NULL);
    EXPECT_EQ(mc_foc_f32_init(&st, nullptr), MC_FOC_ERR_NULL);
    c.r_ohm = 0.0f; // R = 0 (superconducting limit) and psi = 0 are valid
    c.flux_wb = 0.0f;
    EXPECT_EQ(mc_foc_f32_init(&st, &c), MC_FOC_ERR_NONE);
}

} // namespace

// A warm winding (issue 33 item 2): the plant's R 1.4 times the configured
// one. With ki from the configured R the PI's zero misses the plant's pole
// and a slow mode (rate about R/L) trails the step; set_r_scale(1.4) moves
// ki to 1.4 R bw and restores the designed response. Bounds: the same
// 2.5 % shape tolerance as ClosedLoopStepMatchesDesignedBandwidth (the
// sampled loop's own departure) with the scale; without it the mismatch's
// residue is about (1 - 1/1.4) of the step at the start of the slow mode,
// decaying with R/L = 1000/s (as fast as bw here): measured well above
// 5 %, so the scale is what keeps it inside.
TEST(FocF32, RScaleRestoresTheDesignedStepOnAWarmWinding)
{
    const double r_hot = 1.4 * kR;
    const RlAxis axis(r_hot, kL, kDt);
    double worst[2] = {0.0, 0.0};
    for (int with = 0; with < 2; ++with) {
        mc_foc_f32_cfg_t c = BaseCfg();
        mc_foc_f32_t st;
        ASSERT_EQ(mc_foc_f32_init(&st, &c), MC_FOC_ERR_NONE);
        if (with == 1) {
            ASSERT_EQ(mc_foc_f32_set_r_scale(&st, 1.4f), MC_FOC_ERR_NONE);
            EXPECT_NEAR(st.pi_q.ki_per_s, 1.4 * c.ki_q_v_per_as, 1e-6 * c.ki_q_v_per_as);
            EXPECT_EQ(st.pi_d.kp, c.kp_d_v_per_a); // kp = L bw does not move
        }
        double iq = 0.0;
        for (int k = 1; k <= 400; ++k) {
            float vd = 0.0f;
            float vq = 0.0f;
            ASSERT_EQ(mc_foc_f32_step_dq(&st, 0.0f, 10.0f, 0.0f, static_cast<float>(iq), 0.0f,
                                         24.0f, &vd, &vq),
                      MC_FOC_ERR_NONE);
            iq = axis.Next(iq, vq);
            const double shape = 1.0 - std::exp(-static_cast<double>(kBw) * k * kDt);
            worst[with] = std::max(worst[with], std::fabs(iq - 10.0 * shape) / 10.0);
        }
    }
    EXPECT_LT(worst[1], 0.025);
    EXPECT_GT(worst[0], 0.05);
}

// Scales outside [MC_R_SCALE_MIN, MC_R_SCALE_MAX], NaN and NULL are refused
// and change nothing; reset keeps the scale.
TEST(FocF32, RScaleRefusesBadScalesAndSurvivesReset)
{
    mc_foc_f32_cfg_t c = BaseCfg();
    mc_foc_f32_t st;
    ASSERT_EQ(mc_foc_f32_init(&st, &c), MC_FOC_ERR_NONE);
    ASSERT_EQ(mc_foc_f32_set_r_scale(&st, 1.2f), MC_FOC_ERR_NONE);
    mc_foc_f32_t before;
    std::memcpy(&before, &st, sizeof st);
    for (float bad : {kNaN, kInf, 0.0f, 0.2f, 3.5f, -1.0f}) {
        EXPECT_EQ(mc_foc_f32_set_r_scale(&st, bad), MC_FOC_ERR_MOTOR) << bad;
        EXPECT_EQ(std::memcmp(&before, &st, sizeof st), 0) << bad;
    }
    EXPECT_EQ(mc_foc_f32_set_r_scale(nullptr, 1.0f), MC_FOC_ERR_NULL);
    ASSERT_EQ(mc_foc_f32_reset(&st), MC_FOC_ERR_NONE);
    EXPECT_EQ(st.r_scale, 1.2f);
    EXPECT_NEAR(st.pi_d.ki_per_s, 1.2 * c.ki_d_v_per_as, 1e-6 * c.ki_d_v_per_as);
}
