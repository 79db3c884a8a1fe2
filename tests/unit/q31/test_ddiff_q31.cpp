// Dirty-derivative filter: q31 twin against the f32 kernel.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "q31_test_util.hpp"

extern "C" {
#include "filters/mc_ddiff_q31.h"
}

using namespace q31t;

namespace
{
struct Pair {
    mc_ddiff_f32_t f;
    mc_ddiff_q31_t q;
    double yb, ob;
};
Pair make(float a, float b, float dt, double yb, double ob)
{
    Pair p{};
    mc_ddiff_q31_cfg_t c{{a, b, dt}, static_cast<float>(yb), static_cast<float>(ob)};
    EXPECT_EQ(mc_ddiff_f32_init(&p.f, &c.f), 0u);
    EXPECT_EQ(mc_ddiff_q31_init(&p.q, &c), 0u);
    p.yb = yb;
    p.ob = ob;
    return p;
}
// One step of each twin: theta_f; the step must have run (ERR_NONE).
double step_f(mc_ddiff_f32_t *f, float y)
{
    float th = NAN;
    EXPECT_EQ(mc_ddiff_f32_step(f, y, &th), MC_DDIFF_ERR_NONE);
    return th;
}
q31_t step_q(mc_ddiff_q31_t *q, q31_t y)
{
    q31_t th = 0x5A5A5A5A;
    EXPECT_EQ(mc_ddiff_q31_step(q, y, &th), MC_DDIFF_ERR_NONE);
    return th;
}
} // namespace

TEST(DdiffQ31, InitRejectsBadBasesAndKeepsF32Rules)
{
    mc_ddiff_q31_t q{};
    q.out = 1234;
    mc_ddiff_q31_cfg_t c{{50.0f, 50.0f, 1e-4f}, 0.0f, 1.0f};
    EXPECT_EQ(mc_ddiff_q31_init(&q, &c), MC_DDIFF_ERR_SCALE);
    c.y_base = 1.0f;
    c.out_base = NAN;
    EXPECT_EQ(mc_ddiff_q31_init(&q, &c), MC_DDIFF_ERR_SCALE);
    c.out_base = 1.0f;
    c.f.a_per_s = -1.0f;
    EXPECT_EQ(mc_ddiff_q31_init(&q, &c), MC_DDIFF_ERR_A);
    c.f.a_per_s = 50.0f;
    c.y_base = 1.0e-12f; // g y_base/out_base: far beyond nothing, but b*ratio tiny: accepted
    EXPECT_EQ(mc_ddiff_q31_init(&q, &c), 0u);
    c.y_base = 1.0e12f; // b y_base/out_base = 5e13 >= 2^30: no gain format holds it
    mc_ddiff_q31_t q2{};
    q2.out = 77;
    EXPECT_EQ(mc_ddiff_q31_init(&q2, &c), MC_DDIFF_ERR_SCALE);
    EXPECT_EQ(q2.out, 77); // state not written
    // NULL state or output: MC_DDIFF_ERR_NULL, nothing written.
    q31_t th = 42;
    EXPECT_EQ(mc_ddiff_q31_step(nullptr, 1, &th), MC_DDIFF_ERR_NULL);
    EXPECT_EQ(th, 42);
    const int64_t out_q46 = q.out_q46;
    EXPECT_EQ(mc_ddiff_q31_step(&q, 1 << 20, nullptr), MC_DDIFF_ERR_NULL);
    EXPECT_EQ(q.out_q46, out_q46);
    EXPECT_FALSE(q.primed);
    EXPECT_EQ(mc_ddiff_q31_reset(nullptr, 0), MC_DDIFF_ERR_NULL);
}

TEST(DdiffQ31, MatchesF32OnRandomInputs)
{
    // Paper 000 filter (a = b = 50, dt = 1e-4) on a position error: a
    // random walk plus a sine, 2e5 steps. The f32 kernel's own rounding of
    // theta_f (ulp ~ 6e-8 of its size, accumulated through the slow pole
    // 1/(a dt) = 200 steps) dominates; the q31 state is exact to 2^-47.
    Pair p = make(50.0f, 50.0f, 1e-4f, 1.0, 4.0);
    std::mt19937 rng(10);
    std::normal_distribution<double> n(0.0, 1e-5);
    double y = 0.0, worst = 0.0, peak = 0.0;
    for (int k = 0; k < 200000; ++k) {
        y += n(rng);
        const double yy = y + 0.02 * std::sin(2.0 * kPi * 3.0 * k * 1e-4);
        const q31_t yq = to_q(yy, p.yb);
        const float yf = static_cast<float>(from_q(yq, p.yb)); // same input
        const double of = step_f(&p.f, yf);
        const double oq = from_q(step_q(&p.q, yq), p.ob);
        worst = std::max(worst, std::abs(of - oq));
        peak = std::max(peak, std::abs(of));
    }
    // Bound: 2e-7 of the output range (4 rad base: 430 LSB, 8e-7 rad):
    // f32 rounding ~ 1e-7 relative times the peak, accumulated.
    const double bound = 8.0e-7;
    report("ddiff |theta_f32 - theta_q31|", worst, bound, "rad");
    report("ddiff same in output LSB", worst / p.ob * kQ31, bound / p.ob * kQ31, "LSB");
    std::printf("[ measured ] ddiff peak |theta_f| %.4g rad\n", peak);
    EXPECT_LE(worst, bound);
}

TEST(DdiffQ31, EdgeStepsSaturateNeverWrap)
{
    // Full-scale steps of y with a large b: the output saturates at the
    // range edge with the right sign (a wrap would flip it) and recovers.
    Pair p = make(50.0f, 50.0f, 1e-4f, 1.0, 1.0);
    EXPECT_EQ(step_q(&p.q, 0), 0);
    EXPECT_EQ(step_q(&p.q, MC_Q31_MAX), MC_Q31_MAX);
    EXPECT_EQ(step_q(&p.q, MC_Q31_MIN), MC_Q31_MIN);
    EXPECT_EQ(step_q(&p.q, MC_Q31_MAX), MC_Q31_MAX);
    // hold: the filter decays from the clamped value towards 0 with c_q
    q31_t last = MC_Q31_MAX;
    for (int k = 0; k < 5000; ++k) {
        const q31_t o = step_q(&p.q, MC_Q31_MAX);
        EXPECT_LE(o, last);
        EXPECT_GE(o, 0);
        last = o;
    }
    EXPECT_LT(last, 1 << 10); // (1 - a dt)^5000 ~ 1.4e-11 of full scale
    // first step after reset: q0 + b y saturates too
    ASSERT_EQ(mc_ddiff_q31_reset(&p.q, MC_Q31_MAX), MC_DDIFF_ERR_NONE);
    EXPECT_EQ(step_q(&p.q, MC_Q31_MAX), MC_Q31_MAX);
    ASSERT_EQ(mc_ddiff_q31_reset(&p.q, MC_Q31_MIN), MC_DDIFF_ERR_NONE);
    EXPECT_EQ(step_q(&p.q, MC_Q31_MIN), MC_Q31_MIN);
}

TEST(DdiffQ31, DifferentiatesARampExactly)
{
    // As the f32 kernel (mc_ddiff.h): a ramp v settles at (b/a) v. With
    // integer arithmetic the settled value is within 1 LSB of the discrete
    // filter's exact fixed point (the rounding of the state is 2^-16 LSB).
    Pair p = make(100.0f, 2.0f, 1e-4f, 1.0, 1.0);
    const q31_t step = 21475; // 1e-5 per step: v = 0.1 per second
    q31_t y = 0, o = 0;
    for (int k = 0; k < 20000; ++k) {
        o = step_q(&p.q, y);
        y += step;
    }
    // settled value of the discrete filter with its (float) coefficients:
    // g dy / (1 - c_q) = (b/a) v up to the coefficients' float rounding
    const double expect =
        static_cast<double>(p.f.g) * (step / kQ31) / (1.0 - static_cast<double>(p.f.c_q));
    report("ddiff ramp settle error", std::abs(from_q(o, 1.0) - expect) * kQ31, 1.0, "LSB");
    EXPECT_LE(std::abs(from_q(o, 1.0) - expect) * kQ31, 1.0);
}
