// Unit tests of the PI controller (firmware/kernels/pi): float32 and q31.
//
// Every tolerance below carries the reason for its size. Float bounds are
// expressed with ulp(x) = 2^(floor(log2 x) - 23), half of which is the
// largest rounding error of one float operation whose result is below x.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "pi/mc_pi.h"
#include "pi/mc_pi_q31.h"

namespace
{

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr double kLsb = 1.0 / 2147483648.0; // one q31 LSB in per unit

mc_pi_f32_cfg_t BaseCfg(mc_pi_aw_t aw = MC_PI_AW_CLAMP)
{
    mc_pi_f32_cfg_t c{};
    c.kp = 2.0f;
    c.ki_per_s = 100.0f;
    c.dt_s = 1e-3f;
    c.out_min = -1000.0f;
    c.out_max = 1000.0f;
    c.aw = aw;
    c.kaw_per_s = 100.0f; // kaw*dt = 0.1
    return c;
}

const mc_pi_aw_t kAllAw[] = {MC_PI_AW_CLAMP, MC_PI_AW_BACK_CALC, MC_PI_AW_NONE};

// Double-precision reference of the documented law (mc_pi.h), used to bound
// the rounding of both kernels. Same gains as the kernels (the float values).
struct RefPi {
    double kp, ki_dt, kaw_dt, out_min, out_max;
    mc_pi_aw_t aw;
    double integ = 0.0;

    double Step(double e, double ff, double lo, double hi)
    {
        lo = std::max(lo, out_min);
        hi = std::min(hi, out_max);
        const double p = kp * e;
        const double inc = ki_dt * e;
        double i = integ + inc;
        if (aw == MC_PI_AW_CLAMP) {
            const double u_try = p + i + ff;
            if (u_try > hi && inc > 0) {
                i = std::max(integ, hi - p - ff);
            } else if (u_try < lo && inc < 0) {
                i = std::min(integ, lo - p - ff);
            }
        } else if (aw == MC_PI_AW_BACK_CALC) {
            const double uu = p + i + ff;
            i += kaw_dt * (std::min(std::max(uu, lo), hi) - uu);
        }
        integ = std::min(std::max(i, out_min), out_max);
        return std::min(std::max(p + integ + ff, lo), hi);
    }
};

// A step's output through its out-pointer; the step must have run
// (MC_PI_ERR_NONE). Refusals are tested with the kernel calls themselves.
float Step(mc_pi_f32_t *st, float e)
{
    float u = kNaN;
    EXPECT_EQ(mc_pi_f32_step(st, e, &u), MC_PI_ERR_NONE);
    return u;
}

float StepFf(mc_pi_f32_t *st, float e, float ff)
{
    float u = kNaN;
    EXPECT_EQ(mc_pi_f32_step_ff(st, e, ff, &u), MC_PI_ERR_NONE);
    return u;
}

float StepLim(mc_pi_f32_t *st, float e, float ff, float lo, float hi)
{
    float u = kNaN;
    EXPECT_EQ(mc_pi_f32_step_lim(st, e, ff, lo, hi, &u), MC_PI_ERR_NONE);
    return u;
}

q31_t StepQ(mc_pi_q31_t *st, q31_t e)
{
    q31_t u = 0x5A5A5A5A;
    EXPECT_EQ(mc_pi_q31_step(st, e, &u), MC_PI_ERR_NONE);
    return u;
}

q31_t StepQFf(mc_pi_q31_t *st, q31_t e, q31_t ff)
{
    q31_t u = 0x5A5A5A5A;
    EXPECT_EQ(mc_pi_q31_step_ff(st, e, ff, &u), MC_PI_ERR_NONE);
    return u;
}

RefPi MakeRef(const mc_pi_f32_cfg_t &c)
{
    RefPi r{};
    r.kp = c.kp;
    r.ki_dt = static_cast<double>(c.ki_per_s * c.dt_s); // the float product the kernel uses
    r.kaw_dt = (c.aw == MC_PI_AW_BACK_CALC) ? static_cast<double>(c.kaw_per_s * c.dt_s) : 0.0;
    r.out_min = c.out_min;
    r.out_max = c.out_max;
    r.aw = c.aw;
    return r;
}

// ---------------------------------------------------------------- float32

TEST(PiF32, StepResponseMatchesClosedForm)
{
    // Constant error e from a zero integrator, no saturation:
    //   u[k] = kp*e + ki*dt*e*(k+1)   (backward-Euler integral).
    // Tolerance 1e-4: the integrator reaches 10 after 200 steps; each add
    // rounds by at most ulp(16)/2 = 9.5e-7, so 200 adds stay below 1.9e-4 in
    // the worst case and the observed error is far smaller; a forward-Euler
    // kernel (k instead of k+1) is off by 0.05, 500 times the tolerance.
    for (mc_pi_aw_t aw : kAllAw) {
        mc_pi_f32_cfg_t c = BaseCfg(aw);
        mc_pi_f32_t st;
        ASSERT_EQ(mc_pi_f32_init(&st, &c), MC_PI_ERR_NONE);
        const double e = 0.5;
        for (int k = 0; k < 200; ++k) {
            const float u = Step(&st, static_cast<float>(e));
            const double expect = 2.0 * e + 0.1 * e * (k + 1);
            ASSERT_NEAR(u, expect, 1e-4) << "aw=" << aw << " k=" << k;
        }
    }
}

TEST(PiF32, VaryingErrorMatchesSum)
{
    // u[k] = kp*e[k] + ki*dt*sum_{j<=k} e[j] plus a feed-forward, with no
    // saturation. Tolerance 2e-5: |integral| < 1 and |u| < 4, so each of the
    // 500 integrator adds rounds by at most ulp(1)/2 = 6e-8 (3e-5 worst
    // case, random-walk far less) plus ulp(4)/2 on the output sum.
    mc_pi_f32_cfg_t c = BaseCfg();
    mc_pi_f32_t st;
    ASSERT_EQ(mc_pi_f32_init(&st, &c), MC_PI_ERR_NONE);
    double sum = 0.0;
    double max_err = 0.0;
    for (int k = 0; k < 500; ++k) {
        const float e = static_cast<float>(0.7 * std::sin(0.05 * k) + 0.2 * std::cos(0.31 * k));
        const float ff = static_cast<float>(0.3 * std::sin(0.02 * k));
        sum += static_cast<double>(e);
        const float u = StepFf(&st, e, ff);
        const double expect = 2.0 * e + static_cast<double>(c.ki_per_s * c.dt_s) * sum + ff;
        max_err = std::max(max_err, std::fabs(u - expect));
    }
    EXPECT_LT(max_err, 2e-5);
}

TEST(PiF32, OutputAndIntegratorStayWithinLimits)
{
    // Limits are applied with exact comparisons: the saturated output is the
    // limit value itself (tolerance 0).
    for (mc_pi_aw_t aw : kAllAw) {
        mc_pi_f32_cfg_t c = BaseCfg(aw);
        c.kp = 10.0f;
        c.ki_per_s = 1000.0f;
        c.out_min = -2.0f;
        c.out_max = 3.0f;
        mc_pi_f32_t st;
        ASSERT_EQ(mc_pi_f32_init(&st, &c), MC_PI_ERR_NONE);
        for (int k = 0; k < 100; ++k) {
            EXPECT_EQ(Step(&st, 5.0f), 3.0f);
            EXPECT_LE(st.integ, 3.0f);
            EXPECT_GE(st.integ, -2.0f);
        }
        for (int k = 0; k < 100; ++k) {
            EXPECT_EQ(Step(&st, -5.0f), -2.0f);
            EXPECT_LE(st.integ, 3.0f);
            EXPECT_GE(st.integ, -2.0f);
        }
        // A large feed-forward alone saturates too.
        EXPECT_EQ(StepFf(&st, 0.0f, 100.0f), 3.0f);
        EXPECT_EQ(StepFf(&st, 0.0f, -100.0f), -2.0f);
    }
}

// Steps after the error reverses until the output leaves the upper limit.
int RecoverySteps(mc_pi_aw_t aw, bool dynamic_limit)
{
    mc_pi_f32_cfg_t c = BaseCfg(aw);
    c.kp = 0.1f;
    c.ki_per_s = 50.0f;   // ki*dt*|e| = 0.025 per step for e = -0.5
    c.kaw_per_s = 500.0f; // kaw*dt = 0.5
    float ff = 0.0f;
    float hi = 1.0f;
    if (dynamic_limit) {
        c.out_min = -10.0f; // static limits wide, the output cut to +-1 per step
        c.out_max = 10.0f;
    } else {
        c.out_min = -1.0f;
        c.out_max = 1.0f;
        ff = 0.8f; // feed-forward uses most of the range
    }
    mc_pi_f32_t st;
    EXPECT_EQ(mc_pi_f32_init(&st, &c), MC_PI_ERR_NONE);
    float u = 0.0f;
    for (int k = 0; k < 1000; ++k) {
        u = StepLim(&st, 1.0f, ff, -hi, hi);
    }
    EXPECT_EQ(u, hi); // deep in saturation for the last ~980 steps
    for (int k = 1; k <= 2000; ++k) {
        if (StepLim(&st, -0.5f, ff, -hi, hi) < hi) {
            return k;
        }
    }
    return -1;
}

TEST(PiF32, WindupRecoveryAfterLongSaturation)
{
    // Without anti-windup the integrator winds up to its clamp (the static
    // limit): with the dynamic limit +-1 inside static +-10 it must unwind
    // from 10 to 1.05 at 0.025 per step: the output leaves saturation at step
    // 359 (10 - 0.025 k - 0.05 < 1  <=>  k > 358). With ff = 0.8 inside
    // static +-1 it unwinds from 1 to 0.25: step 31. Window +-3 steps: the
    // float sums can move the crossing by one step, not more.
    EXPECT_NEAR(RecoverySteps(MC_PI_AW_NONE, true), 359, 3);
    EXPECT_NEAR(RecoverySteps(MC_PI_AW_NONE, false), 31, 3);
    // With anti-windup (clamping or back-calculation, kaw*dt = 0.5) the
    // integrator holds no excess, so the output leaves saturation at the
    // first step after the error reverses: stated bound 1 step.
    for (mc_pi_aw_t aw : {MC_PI_AW_CLAMP, MC_PI_AW_BACK_CALC}) {
        EXPECT_EQ(RecoverySteps(aw, true), 1) << "aw=" << aw;
        EXPECT_EQ(RecoverySteps(aw, false), 1) << "aw=" << aw;
    }
}

TEST(PiF32, BumplessGainChange)
{
    // After set_gains the next step with the same error differs from the last
    // output only by the new integral increment ki_new*dt*e = 0.09.
    // Tolerance 1e-6: outputs are about 2, ulp(2)/2 = 1.2e-7 per operation,
    // a handful of operations. A plain gain change jumps by
    // (kp_new - kp_old)*e = 0.9, which the second check shows.
    mc_pi_f32_cfg_t c = BaseCfg();
    mc_pi_f32_t st;
    ASSERT_EQ(mc_pi_f32_init(&st, &c), MC_PI_ERR_NONE);
    float u_last = 0.0f;
    for (int k = 0; k < 20; ++k) {
        u_last = Step(&st, 0.3f);
    }
    mc_pi_f32_t plain = st;
    plain.kp = 5.0f;
    plain.ki_per_s = 300.0f;
    plain.ki_dt = 0.3f;

    ASSERT_EQ(mc_pi_f32_set_gains(&st, 5.0f, 300.0f), MC_PI_ERR_NONE);
    const float u_next = Step(&st, 0.3f);
    EXPECT_NEAR(u_next - u_last, 300.0 * 1e-3 * 0.3, 1e-6);
    const float u_plain = Step(&plain, 0.3f);
    EXPECT_GT(std::fabs(u_plain - u_last - 0.09f), 0.5f);

    // Invalid gains: specific flags, state unchanged.
    mc_pi_f32_t before = st;
    EXPECT_EQ(mc_pi_f32_set_gains(&st, kNaN, 1.0f), MC_PI_ERR_KP);
    EXPECT_EQ(mc_pi_f32_set_gains(&st, 1.0f, -1.0f), MC_PI_ERR_KI);
    EXPECT_EQ(mc_pi_f32_set_gains(&st, -1.0f, kInf), MC_PI_ERR_KP | MC_PI_ERR_KI);
    EXPECT_EQ(std::memcmp(&before, &st, sizeof st), 0);
    EXPECT_EQ(mc_pi_f32_set_gains(nullptr, 1.0f, 1.0f), MC_PI_ERR_NULL);
}

TEST(PiF32, Reset)
{
    mc_pi_f32_cfg_t c = BaseCfg();
    c.out_min = -10.0f;
    c.out_max = 10.0f;
    mc_pi_f32_t st;
    ASSERT_EQ(mc_pi_f32_init(&st, &c), MC_PI_ERR_NONE);
    for (int k = 0; k < 500; ++k) {
        (void)Step(&st, 50.0f);
    }
    float u = 0.0f;
    EXPECT_EQ(mc_pi_f32_step(&st, kNaN, &u), MC_PI_ERR_NAN_INPUT);
    ASSERT_NE(st.flags, 0u);
    // Exact values: reset copies the preset, a zero error adds nothing.
    EXPECT_EQ(mc_pi_f32_reset(&st, 0.25f), MC_PI_ERR_NONE);
    EXPECT_EQ(st.integ, 0.25f);
    EXPECT_EQ(st.out, 0.25f);
    EXPECT_EQ(st.flags, 0u);
    EXPECT_EQ(Step(&st, 0.0f), 0.25f);
    EXPECT_EQ(mc_pi_f32_reset(&st, 100.0f), MC_PI_ERR_NONE); // clamped
    EXPECT_EQ(st.integ, 10.0f);
    mc_pi_f32_t before = st;
    EXPECT_EQ(mc_pi_f32_reset(&st, kNaN), MC_PI_ERR_NAN_INPUT);
    EXPECT_EQ(std::memcmp(&before, &st, sizeof st), 0);
    EXPECT_EQ(mc_pi_f32_reset(nullptr, 0.0f), MC_PI_ERR_NULL);
}

TEST(PiF32, InitRejectsEveryBadRuleWithItsFlag)
{
    struct Case {
        const char *what;
        void (*mutate)(mc_pi_f32_cfg_t &);
        uint32_t flags;
    };
    const Case cases[] = {
        {"kp < 0", [](mc_pi_f32_cfg_t &c) { c.kp = -0.1f; }, MC_PI_ERR_KP},
        {"kp NaN", [](mc_pi_f32_cfg_t &c) { c.kp = kNaN; }, MC_PI_ERR_KP},
        {"kp inf", [](mc_pi_f32_cfg_t &c) { c.kp = kInf; }, MC_PI_ERR_KP},
        {"ki < 0", [](mc_pi_f32_cfg_t &c) { c.ki_per_s = -1.0f; }, MC_PI_ERR_KI},
        {"ki NaN", [](mc_pi_f32_cfg_t &c) { c.ki_per_s = kNaN; }, MC_PI_ERR_KI},
        {"ki*dt overflows",
         [](mc_pi_f32_cfg_t &c) {
             c.ki_per_s = 1e30f;
             c.dt_s = 1e10f;
         },
         MC_PI_ERR_KI},
        {"dt = 0", [](mc_pi_f32_cfg_t &c) { c.dt_s = 0.0f; }, MC_PI_ERR_DT},
        {"dt < 0", [](mc_pi_f32_cfg_t &c) { c.dt_s = -1e-3f; }, MC_PI_ERR_DT},
        {"dt NaN", [](mc_pi_f32_cfg_t &c) { c.dt_s = kNaN; }, MC_PI_ERR_DT},
        {"dt inf", [](mc_pi_f32_cfg_t &c) { c.dt_s = kInf; }, MC_PI_ERR_DT},
        {"min > max",
         [](mc_pi_f32_cfg_t &c) {
             c.out_min = 1.0f;
             c.out_max = -1.0f;
         },
         MC_PI_ERR_LIMITS},
        {"min NaN", [](mc_pi_f32_cfg_t &c) { c.out_min = kNaN; }, MC_PI_ERR_LIMITS},
        {"max inf", [](mc_pi_f32_cfg_t &c) { c.out_max = kInf; }, MC_PI_ERR_LIMITS},
        {"aw unknown", [](mc_pi_f32_cfg_t &c) { c.aw = static_cast<mc_pi_aw_t>(7); },
         MC_PI_ERR_AW_MODE},
        {"kaw = 0",
         [](mc_pi_f32_cfg_t &c) {
             c.aw = MC_PI_AW_BACK_CALC;
             c.kaw_per_s = 0.0f;
         },
         MC_PI_ERR_KAW},
        {"kaw NaN",
         [](mc_pi_f32_cfg_t &c) {
             c.aw = MC_PI_AW_BACK_CALC;
             c.kaw_per_s = kNaN;
         },
         MC_PI_ERR_KAW},
        {"kaw*dt > 1",
         [](mc_pi_f32_cfg_t &c) {
             c.aw = MC_PI_AW_BACK_CALC;
             c.kaw_per_s = 1500.0f;
         },
         MC_PI_ERR_KAW},
        {"kp < 0 and dt = 0",
         [](mc_pi_f32_cfg_t &c) {
             c.kp = -1.0f;
             c.dt_s = 0.0f;
         },
         MC_PI_ERR_KP | MC_PI_ERR_DT},
    };
    for (const Case &tc : cases) {
        mc_pi_f32_cfg_t c = BaseCfg();
        tc.mutate(c);
        mc_pi_f32_t st;
        std::memset(&st, 0x5A, sizeof st);
        mc_pi_f32_t before = st;
        EXPECT_EQ(mc_pi_f32_init(&st, &c), tc.flags) << tc.what;
        EXPECT_EQ(std::memcmp(&before, &st, sizeof st), 0) << tc.what;
    }
    // Edge configs that are valid: zero gains, equal limits, kaw*dt = 1,
    // kaw ignored (even NaN) when back-calculation is not selected.
    mc_pi_f32_t st;
    mc_pi_f32_cfg_t c = BaseCfg();
    c.kp = 0.0f;
    c.ki_per_s = 0.0f;
    c.out_min = c.out_max = 2.0f;
    c.kaw_per_s = kNaN;
    EXPECT_EQ(mc_pi_f32_init(&st, &c), MC_PI_ERR_NONE);
    EXPECT_EQ(st.out, 2.0f); // 0 is outside [2, 2]: starts at the nearest limit
    c = BaseCfg(MC_PI_AW_BACK_CALC);
    c.kaw_per_s = 1000.0f;
    EXPECT_EQ(mc_pi_f32_init(&st, &c), MC_PI_ERR_NONE);
    EXPECT_EQ(mc_pi_f32_init(nullptr, &c), MC_PI_ERR_NULL);
    EXPECT_EQ(mc_pi_f32_init(&st, nullptr), MC_PI_ERR_NULL);
}

TEST(PiF32, NonFiniteInputIsRefusedAndSticky)
{
    mc_pi_f32_cfg_t c = BaseCfg();
    mc_pi_f32_t st;
    ASSERT_EQ(mc_pi_f32_init(&st, &c), MC_PI_ERR_NONE);
    const float u0 = Step(&st, 0.4f);
    const mc_pi_f32_t good = st;
    // Each refused step returns MC_PI_ERR_NAN_INPUT, writes the last output
    // and changes nothing but the sticky flag.
    const float bad[][4] = {{kNaN, 0.0f, -1.0f, 1.0f},
                            {kInf, 0.0f, -1.0f, 1.0f},
                            {0.1f, kNaN, -1.0f, 1.0f},
                            {0.1f, 0.0f, kNaN, 1.0f},
                            {0.1f, 0.0f, -1.0f, -kInf}};
    for (const auto &b : bad) {
        float u = 0.0f;
        EXPECT_EQ(mc_pi_f32_step_lim(&st, b[0], b[1], b[2], b[3], &u), MC_PI_ERR_NAN_INPUT);
        EXPECT_EQ(u, u0);
        EXPECT_EQ(st.integ, good.integ);
        EXPECT_EQ(st.out, good.out);
        EXPECT_EQ(st.last_error, good.last_error);
        EXPECT_EQ(st.flags, MC_PI_ERR_NAN_INPUT);
    }
    // Dynamic limits out of order: refused with their own flag.
    float u = 0.0f;
    EXPECT_EQ(mc_pi_f32_step_lim(&st, 0.1f, 0.0f, 1.0f, -1.0f, &u), MC_PI_ERR_DYN_LIMIT);
    EXPECT_EQ(u, u0);
    EXPECT_EQ(st.integ, good.integ);
    EXPECT_EQ(st.flags, MC_PI_ERR_NAN_INPUT | MC_PI_ERR_DYN_LIMIT);
    // Finite steps run again; the flags stay until reset.
    EXPECT_NE(Step(&st, 0.4f), u0);
    EXPECT_EQ(st.flags, MC_PI_ERR_NAN_INPUT | MC_PI_ERR_DYN_LIMIT);
    // Overflow inside a step (finite inputs): refused too, never stores NaN.
    mc_pi_f32_cfg_t big = BaseCfg();
    big.kp = 1e30f;
    ASSERT_EQ(mc_pi_f32_init(&st, &big), MC_PI_ERR_NONE);
    (void)mc_pi_f32_step_ff(&st, 1e30f, -3e38f, &u);
    EXPECT_TRUE(std::isfinite(st.integ));
    EXPECT_TRUE(std::isfinite(st.out));
}

TEST(PiF32, StepsRefuseNullPointersAndWriteNothing)
{
    // The return convention (kernels/README.md): a NULL state or output
    // pointer gives MC_PI_ERR_NULL, and neither the state nor the output
    // changes (compared bit for bit).
    mc_pi_f32_cfg_t c = BaseCfg();
    mc_pi_f32_t st;
    ASSERT_EQ(mc_pi_f32_init(&st, &c), MC_PI_ERR_NONE);
    (void)Step(&st, 0.4f);
    const mc_pi_f32_t before = st;
    float u = 42.0f;
    EXPECT_EQ(mc_pi_f32_step(nullptr, 0.1f, &u), MC_PI_ERR_NULL);
    EXPECT_EQ(mc_pi_f32_step_ff(nullptr, 0.1f, 0.0f, &u), MC_PI_ERR_NULL);
    EXPECT_EQ(mc_pi_f32_step_lim(nullptr, 0.1f, 0.0f, -1.0f, 1.0f, &u), MC_PI_ERR_NULL);
    EXPECT_EQ(u, 42.0f);
    EXPECT_EQ(mc_pi_f32_step(&st, 0.1f, nullptr), MC_PI_ERR_NULL);
    EXPECT_EQ(mc_pi_f32_step_ff(&st, 0.1f, 0.0f, nullptr), MC_PI_ERR_NULL);
    EXPECT_EQ(mc_pi_f32_step_lim(&st, 0.1f, 0.0f, -1.0f, 1.0f, nullptr), MC_PI_ERR_NULL);
    EXPECT_EQ(std::memcmp(&before, &st, sizeof st), 0);
}

TEST(PiF32, TrackEqualsRunningWithTheAppliedLimit)
{
    // A PI told afterwards that its output was cut to 1 (mc_pi_f32_track)
    // must end with the same integrator as one that ran with the limit 1
    // from the start (mc_pi_f32_step_lim). Tolerance 1e-6: both compute the
    // same quantities in a different order, values below 10, ulp(16)/2 =
    // 9.5e-7 for one rounding.
    for (mc_pi_aw_t aw : {MC_PI_AW_CLAMP, MC_PI_AW_BACK_CALC, MC_PI_AW_NONE}) {
        mc_pi_f32_cfg_t c = BaseCfg(aw);
        c.kp = 0.1f;
        c.ki_per_s = 50.0f;
        c.kaw_per_s = 500.0f;
        c.out_min = -10.0f;
        c.out_max = 10.0f;
        mc_pi_f32_t a;
        mc_pi_f32_t b;
        ASSERT_EQ(mc_pi_f32_init(&a, &c), MC_PI_ERR_NONE);
        ASSERT_EQ(mc_pi_f32_init(&b, &c), MC_PI_ERR_NONE);
        for (int k = 0; k < 1500; ++k) {
            const float e = (k < 1000) ? 1.0f : -0.5f;
            const float ua = StepLim(&a, e, 0.0f, -10.0f, 1.0f);
            const float ub_raw = Step(&b, e);
            if (ub_raw > 1.0f) {
                ASSERT_EQ(mc_pi_f32_track(&b, 1.0f), MC_PI_ERR_NONE);
            }
            if (aw != MC_PI_AW_NONE) {
                ASSERT_NEAR(a.integ, b.integ, 1e-6) << "aw=" << aw << " k=" << k;
                ASSERT_NEAR(ua, b.out, 1e-6) << "aw=" << aw << " k=" << k;
            }
        }
    }
    mc_pi_f32_cfg_t c = BaseCfg();
    mc_pi_f32_t st;
    ASSERT_EQ(mc_pi_f32_init(&st, &c), MC_PI_ERR_NONE);
    EXPECT_EQ(mc_pi_f32_track(&st, kNaN), MC_PI_ERR_NAN_INPUT);
    EXPECT_EQ(st.flags, MC_PI_ERR_NAN_INPUT);
}

// ---------------------------------------------------------------- q31

mc_pi_q31_cfg_t BaseQ(mc_pi_aw_t aw = MC_PI_AW_CLAMP)
{
    mc_pi_q31_cfg_t q{};
    q.kp_mant = 1 << 30; // 0.5
    q.kp_shift = 0;
    q.ki_dt_mant = 1 << 21; // 2^-10 per step
    q.ki_shift = 0;
    q.out_min = MC_Q31_MIN;
    q.out_max = MC_Q31_MAX;
    q.aw = aw;
    q.kaw_dt = 1 << 30; // 0.5
    return q;
}

TEST(PiQ31, StepResponseIsExactOnDyadicValues)
{
    // kp = 0.5 (and 2 with shift 2), ki*dt = 2^-10, e = 2^-4: every value of
    // u[k] = kp*e + ki*dt*e*(k+1) is a multiple of 2^-14, exactly
    // representable, so the kernel must hit it to the LSB (tolerance 0).
    for (mc_pi_aw_t aw : kAllAw) {
        for (int32_t shift : {0, 2}) {
            mc_pi_q31_cfg_t q = BaseQ(aw);
            q.kp_shift = shift;
            mc_pi_q31_t st;
            ASSERT_EQ(mc_pi_q31_init(&st, &q), MC_PI_ERR_NONE);
            const int64_t e = int64_t{1} << 27;
            const int64_t p = (int64_t{1} << 26) << shift;
            for (int k = 0; k < 100; ++k) {
                const q31_t u = StepQ(&st, static_cast<q31_t>(e));
                ASSERT_EQ(u, p + (int64_t{1} << 17) * (k + 1)) << "k=" << k;
            }
        }
    }
}

double Uniform(std::mt19937 &rng, double lo, double hi)
{
    return std::uniform_real_distribution<double>(lo, hi)(rng);
}

// A value in [lo, hi) that float and q31 both hold exactly (a multiple of 2^-23).
double Grid(std::mt19937 &rng, double lo, double hi)
{
    return std::floor(Uniform(rng, lo, hi) * 8388608.0) / 8388608.0;
}

TEST(PiQ31, TwinOfF32OnRandomInputs)
{
    // Same config through mc_pi_q31_cfg_from_f32 (bases 1), same inputs (on a
    // 2^-23 grid, exact in both formats), 200 steps per trial, 300 trials
    // over all anti-windup schemes, random gains, limits and feed-forward.
    //
    // Bounds, against a double reference of the same law:
    // - q31 against a reference with the q31 kernel's own gains: 1 LSB. One
    //   rounding of the output to q31 (0.5 LSB); the Q17.46 integrator and
    //   products round by 2^-16 LSB per step (200 steps: 0.003 LSB).
    // - gain quantisation: kp (a 2^-23 grid value) is exact in q31; ki*dt
    //   (and kaw*dt) below 2^-8 has float bits below the q31 grid and is off
    //   by at most 2^-32 per unit, i.e. 0.5 LSB per unit of error, per step:
    //   N * 0.5 LSB after N steps (|e| <= 1).
    // - f32: every internal value is below 4, so one float operation rounds by
    //   at most ulp(4)/2 = 2^-22 = 512 LSB. An integrator update is at most 4
    //   such roundings, the map from integrator to integrator never expands
    //   an error (slope 0, 1 or 1 - kaw*dt), so after N steps the integrator
    //   is within N*4*512 LSB and the output within that plus 3*512 LSB.
    // - twin: the sum of the three. Observed errors are much smaller (the
    //   roundings do not all add up); the test also reports the maximum.
    std::mt19937 rng(12345);
    double worst_q = 0.0;
    double worst_twin = 0.0;
    const int kSteps = 200;
    for (int trial = 0; trial < 300; ++trial) {
        mc_pi_f32_cfg_t c{};
        c.kp = static_cast<float>(Grid(rng, 0.0, 2.0));
        c.ki_per_s = static_cast<float>(Grid(rng, 0.0, 50.0));
        c.dt_s = 1e-3f;
        c.out_min = static_cast<float>(Grid(rng, -0.95, -0.05));
        c.out_max = static_cast<float>(Grid(rng, 0.05, 0.95));
        c.aw = kAllAw[trial % 3];
        c.kaw_per_s = static_cast<float>(Grid(rng, 10.0, 1000.0));
        mc_pi_q31_cfg_t q;
        ASSERT_EQ(mc_pi_q31_cfg_from_f32(&c, 1.0f, 1.0f, &q), MC_PI_ERR_NONE);
        mc_pi_f32_t sf;
        mc_pi_q31_t sq;
        ASSERT_EQ(mc_pi_f32_init(&sf, &c), MC_PI_ERR_NONE);
        ASSERT_EQ(mc_pi_q31_init(&sq, &q), MC_PI_ERR_NONE);
        RefPi ref = MakeRef(c);
        // The q31 kernel's own gains (ki*dt below 2^-8 and kaw*dt are
        // rounded to the q31 grid) for the q31 reference.
        RefPi ref_q = ref;
        ref_q.kp = std::ldexp(static_cast<double>(q.kp_mant), q.kp_shift - 31);
        ref_q.ki_dt = std::ldexp(static_cast<double>(q.ki_dt_mant), q.ki_shift - 31);
        ref_q.kaw_dt = std::ldexp(static_cast<double>(q.kaw_dt), -31);
        for (int k = 0; k < kSteps; ++k) {
            const double e = Grid(rng, -1.0, 1.0);
            const double ff = Grid(rng, -0.5, 0.5);
            const q31_t eq = static_cast<q31_t>(std::llround(e * 2147483648.0));
            const q31_t ffq = static_cast<q31_t>(std::llround(ff * 2147483648.0));
            const double ur = ref.Step(e, ff, -1.0, 1.0);
            const double urq = ref_q.Step(e, ff, -1.0, 1.0);
            const double uf = StepFf(&sf, static_cast<float>(e), static_cast<float>(ff));
            const double uq = StepQFf(&sq, eq, ffq) * kLsb;
            const double bound_f = ((k + 1) * 4.0 + 3.0) * 512.0;
            const double bound_gain = (k + 1) * 0.5 * 1.0;
            ASSERT_LE(std::fabs(uq - urq) / kLsb, 1.0) << "trial " << trial << " k " << k;
            ASSERT_LE(std::fabs(uf - ur) / kLsb, bound_f) << "trial " << trial << " k " << k;
            ASSERT_LE(std::fabs(uq - uf) / kLsb, bound_f + bound_gain + 1.0) << "trial " << trial;
            worst_q = std::max(worst_q, std::fabs(uq - urq) / kLsb);
            worst_twin = std::max(worst_twin, std::fabs(uq - uf) / kLsb);
        }
    }
    RecordProperty("worst_q31_vs_double_lsb", std::to_string(worst_q));
    RecordProperty("worst_q31_vs_f32_lsb", std::to_string(worst_twin));
    std::printf("q31 vs double: %.3f LSB, q31 vs f32: %.1f LSB\n", worst_q, worst_twin);
}

TEST(PiQ31, SaturatesAtRangeEdgesNeverWraps)
{
    // Largest gains (mantissa MAX, shift 15: 32768 per unit), extreme errors
    // and feed-forward, full-range limits: the output must be exactly the
    // limit with the sign of the demand (a wrap would flip it), and the
    // integrator must stay within the limits. UBSan (MC_SANITIZE build)
    // additionally checks that no signed overflow happens inside.
    for (mc_pi_aw_t aw : kAllAw) {
        mc_pi_q31_cfg_t q = BaseQ(aw);
        q.kp_mant = MC_Q31_MAX;
        q.kp_shift = MC_PI_Q31_MAX_SHIFT;
        q.ki_dt_mant = MC_Q31_MAX;
        q.ki_shift = MC_PI_Q31_MAX_SHIFT;
        q.kaw_dt = MC_Q31_MAX;
        mc_pi_q31_t st;
        ASSERT_EQ(mc_pi_q31_init(&st, &q), MC_PI_ERR_NONE);
        const q31_t edges[] = {MC_Q31_MIN, MC_Q31_MAX, -1, 1, 0};
        const int64_t lo46 = static_cast<int64_t>(MC_Q31_MIN) * 32768;
        const int64_t hi46 = static_cast<int64_t>(MC_Q31_MAX) * 32768;
        for (q31_t e : edges) {
            for (q31_t ff : edges) {
                for (int rep = 0; rep < 3; ++rep) {
                    const q31_t u = StepQFf(&st, e, ff);
                    // |kp*e| = 32768 per unit for the extreme errors, far
                    // beyond |I + ff| <= 2; for the small errors only the
                    // range is checked.
                    if (e == MC_Q31_MAX) {
                        EXPECT_EQ(u, MC_Q31_MAX) << "aw " << aw << " ff " << ff;
                    } else if (e == MC_Q31_MIN) {
                        EXPECT_EQ(u, MC_Q31_MIN) << "aw " << aw << " ff " << ff;
                    }
                    EXPECT_GE(st.integ_q46, lo46);
                    EXPECT_LE(st.integ_q46, hi46);
                }
            }
        }
    }
    // The f32 twin saturates to the same values: -1 exactly, and +1, which is
    // MC_Q31_MAX + 1 LSB (float cannot hold 1 - 2^-31): tolerance 1 LSB.
    mc_pi_f32_cfg_t c = BaseCfg();
    c.kp = 32767.0f;
    c.ki_per_s = 1000.0f;
    c.out_min = -1.0f;
    c.out_max = 1.0f;
    mc_pi_q31_cfg_t q;
    ASSERT_EQ(mc_pi_q31_cfg_from_f32(&c, 1.0f, 1.0f, &q), MC_PI_ERR_NONE);
    mc_pi_f32_t sf;
    mc_pi_q31_t sq;
    ASSERT_EQ(mc_pi_f32_init(&sf, &c), MC_PI_ERR_NONE);
    ASSERT_EQ(mc_pi_q31_init(&sq, &q), MC_PI_ERR_NONE);
    for (q31_t e : {MC_Q31_MIN, MC_Q31_MAX, MC_Q31_MIN}) {
        const double uf = Step(&sf, mc_q31_to_f32(e));
        const double uq = StepQ(&sq, e);
        EXPECT_LE(std::fabs(uf - uq * kLsb) / kLsb, 1.0);
    }
}

TEST(PiQ31, BumplessGainChangeAndReset)
{
    // The integer arithmetic keeps kp*e_last + I exact, so the next output
    // differs from the last by the new integral increment, to the output
    // rounding: 1 LSB.
    mc_pi_q31_t st;
    mc_pi_q31_cfg_t q = BaseQ();
    ASSERT_EQ(mc_pi_q31_init(&st, &q), MC_PI_ERR_NONE);
    const q31_t e = 123456789; // about 0.0575 per unit
    q31_t u_last = 0;
    for (int k = 0; k < 20; ++k) {
        u_last = StepQ(&st, e);
    }
    const q31_t ki_new = 1 << 24;                                               // 2^-7 per step
    ASSERT_EQ(mc_pi_q31_set_gains(&st, 3 << 28, 2, ki_new, 0), MC_PI_ERR_NONE); // kp 1.5
    const q31_t u_next = StepQ(&st, e);
    const double inc = static_cast<double>(e) / 128.0;
    EXPECT_NEAR(static_cast<double>(u_next) - u_last, inc, 1.0);

    mc_pi_q31_t before = st;
    EXPECT_EQ(mc_pi_q31_set_gains(&st, -1, 0, 1, 0), MC_PI_ERR_KP);
    EXPECT_EQ(mc_pi_q31_set_gains(&st, 1, 16, 1, 0), MC_PI_ERR_KP);
    EXPECT_EQ(mc_pi_q31_set_gains(&st, 1, 0, 1, -1), MC_PI_ERR_KI);
    EXPECT_EQ(std::memcmp(&before, &st, sizeof st), 0);

    EXPECT_EQ(mc_pi_q31_reset(&st, 1 << 29), MC_PI_ERR_NONE);
    EXPECT_EQ(st.out, 1 << 29);
    EXPECT_EQ(StepQ(&st, 0), 1 << 29); // zero error: exact
    // Dynamic limits out of order: refused (the last output written), sticky flag.
    q31_t u = 0;
    EXPECT_EQ(mc_pi_q31_step_lim(&st, 5, 0, 10, -10, &u), MC_PI_ERR_DYN_LIMIT);
    EXPECT_EQ(u, 1 << 29);
    EXPECT_EQ(st.flags, MC_PI_ERR_DYN_LIMIT);
    EXPECT_EQ(mc_pi_q31_reset(nullptr, 0), MC_PI_ERR_NULL);
}

TEST(PiQ31, StepsRefuseNullPointersAndWriteNothing)
{
    // As the f32 kernel: MC_PI_ERR_NULL, state and output untouched.
    mc_pi_q31_cfg_t q = BaseQ();
    mc_pi_q31_t st;
    ASSERT_EQ(mc_pi_q31_init(&st, &q), MC_PI_ERR_NONE);
    (void)StepQ(&st, 1 << 20);
    const mc_pi_q31_t before = st;
    q31_t u = 42;
    EXPECT_EQ(mc_pi_q31_step(nullptr, 1, &u), MC_PI_ERR_NULL);
    EXPECT_EQ(mc_pi_q31_step_ff(nullptr, 1, 0, &u), MC_PI_ERR_NULL);
    EXPECT_EQ(mc_pi_q31_step_lim(nullptr, 1, 0, -10, 10, &u), MC_PI_ERR_NULL);
    EXPECT_EQ(u, 42);
    EXPECT_EQ(mc_pi_q31_step(&st, 1, nullptr), MC_PI_ERR_NULL);
    EXPECT_EQ(mc_pi_q31_step_ff(&st, 1, 0, nullptr), MC_PI_ERR_NULL);
    EXPECT_EQ(mc_pi_q31_step_lim(&st, 1, 0, -10, 10, nullptr), MC_PI_ERR_NULL);
    EXPECT_EQ(std::memcmp(&before, &st, sizeof st), 0);
}

TEST(PiQ31, InitRejectsEveryBadRuleWithItsFlag)
{
    struct Case {
        const char *what;
        void (*mutate)(mc_pi_q31_cfg_t &);
        uint32_t flags;
    };
    const Case cases[] = {
        {"kp mant < 0", [](mc_pi_q31_cfg_t &q) { q.kp_mant = -1; }, MC_PI_ERR_KP},
        {"kp shift 16", [](mc_pi_q31_cfg_t &q) { q.kp_shift = 16; }, MC_PI_ERR_KP},
        {"kp shift -1", [](mc_pi_q31_cfg_t &q) { q.kp_shift = -1; }, MC_PI_ERR_KP},
        {"ki mant < 0", [](mc_pi_q31_cfg_t &q) { q.ki_dt_mant = MC_Q31_MIN; }, MC_PI_ERR_KI},
        {"ki shift 99", [](mc_pi_q31_cfg_t &q) { q.ki_shift = 99; }, MC_PI_ERR_KI},
        {"min > max",
         [](mc_pi_q31_cfg_t &q) {
             q.out_min = 10;
             q.out_max = 9;
         },
         MC_PI_ERR_LIMITS},
        {"aw unknown", [](mc_pi_q31_cfg_t &q) { q.aw = static_cast<mc_pi_aw_t>(3); },
         MC_PI_ERR_AW_MODE},
        {"kaw 0",
         [](mc_pi_q31_cfg_t &q) {
             q.aw = MC_PI_AW_BACK_CALC;
             q.kaw_dt = 0;
         },
         MC_PI_ERR_KAW},
    };
    for (const Case &tc : cases) {
        mc_pi_q31_cfg_t q = BaseQ();
        tc.mutate(q);
        mc_pi_q31_t st;
        std::memset(&st, 0x5A, sizeof st);
        mc_pi_q31_t before = st;
        EXPECT_EQ(mc_pi_q31_init(&st, &q), tc.flags) << tc.what;
        EXPECT_EQ(std::memcmp(&before, &st, sizeof st), 0) << tc.what;
    }

    // Float-to-q31 config conversion.
    mc_pi_f32_cfg_t c = BaseCfg();
    mc_pi_q31_cfg_t q;
    std::memset(&q, 0x5A, sizeof q);
    const mc_pi_q31_cfg_t q_before = q;
    EXPECT_EQ(mc_pi_q31_cfg_from_f32(&c, 0.0f, 1.0f, &q), MC_PI_ERR_SCALE);
    EXPECT_EQ(mc_pi_q31_cfg_from_f32(&c, 1.0f, kNaN, &q), MC_PI_ERR_SCALE);
    c.kp = 40000.0f; // >= 2^15 per unit
    EXPECT_EQ(mc_pi_q31_cfg_from_f32(&c, 1.0f, 1.0f, &q), MC_PI_ERR_SCALE);
    c = BaseCfg();
    c.dt_s = -1.0f;
    EXPECT_EQ(mc_pi_q31_cfg_from_f32(&c, 1.0f, 1.0f, &q), MC_PI_ERR_DT);
    EXPECT_EQ(std::memcmp(&q, &q_before, sizeof q), 0);
    // Per-unit scaling: kp = 2 V/A with 10 A and 40 V bases is 0.5 per unit.
    c = BaseCfg();
    c.out_min = -20.0f;
    c.out_max = 20.0f;
    ASSERT_EQ(mc_pi_q31_cfg_from_f32(&c, 10.0f, 40.0f, &q), MC_PI_ERR_NONE);
    EXPECT_EQ(q.kp_mant, 1 << 30);
    EXPECT_EQ(q.kp_shift, 0);
    EXPECT_EQ(q.out_max, 1 << 30);
    EXPECT_EQ(q.out_min, -(1 << 30));
}

} // namespace
