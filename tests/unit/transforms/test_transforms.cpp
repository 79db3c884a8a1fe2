// Unit tests for the Clarke / Park transforms (f32 and q31 twins).
//
// References are computed here in double from the textbook formulas
// (amplitude invariant, alpha on phase a), independently of the kernels.
// Float tolerances are stated relative to the magnitude of the values
// involved: FLT_EPSILON = 2^-23 is one ulp at 1, a single rounding is at most
// half an ulp.

#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <random>

#include "transforms/mc_transforms.h"

namespace
{

constexpr double kPi = 3.14159265358979323846;
constexpr double kQ31 = 2147483648.0; // 2^31

double ToDouble(q31_t x)
{
    return static_cast<double>(x) / kQ31;
}

// Exact q31 from a double in (-1, 1), rounded to nearest (test helper, not
// the kernel's mc_q31_from_f32, so the tests do not depend on it).
q31_t ToQ31(double x)
{
    double r = std::nearbyint(x * kQ31);
    if (r >= kQ31) {
        return MC_Q31_MAX;
    }
    if (r < -kQ31) {
        return MC_Q31_MIN;
    }
    return static_cast<q31_t>(r);
}

// A q31 value with its low 8 bits cleared: 23 significant bits, so it
// converts to float exactly and the f32 twin sees the same input.
q31_t FloatExactQ31(std::mt19937 &rng, double lo, double hi)
{
    std::uniform_real_distribution<double> dist(lo, hi);
    q31_t v = ToQ31(dist(rng));
    return static_cast<q31_t>(v & ~static_cast<q31_t>(0xFF));
}

// Difference in q31 LSB between a q31 result and a real value.
double LsbDiff(q31_t q, double ref)
{
    return std::fabs(static_cast<double>(q) - ref * kQ31);
}

} // namespace

// --------------------------------------------------------------- f32

TEST(TransformsF32, KnownValuesFixTheConvention)
{
    float alpha = 0.0f;
    float beta = 0.0f;
    // Balanced set at angle 0: a = 1, b = c = -1/2 lies on the alpha axis
    // with amplitude 1 (amplitude invariance).
    mc_clarke3_f32(1.0f, -0.5f, -0.5f, &alpha, &beta);
    // Tolerance 1 ulp at 1: (2 + 0.5 + 0.5) * (1/3 rounded) is one rounding.
    EXPECT_NEAR(alpha, 1.0f, FLT_EPSILON);
    EXPECT_NEAR(beta, 0.0f, FLT_EPSILON);

    // Phase b axis (120 degrees): a = -1/2, b = 1, c = -1/2.
    mc_clarke_f32(-0.5f, 1.0f, &alpha, &beta);
    // Tolerance 2 ulp at 1: two roundings (sum exact, product, constant).
    EXPECT_NEAR(alpha, -0.5f, 2.0f * FLT_EPSILON);
    EXPECT_NEAR(beta, static_cast<float>(std::sqrt(3.0) / 2.0), 2.0f * FLT_EPSILON);

    // q leads d by 90 degrees: d = 0, q = 1 at theta = 0 is +beta; at theta
    // = 90 degrees (sin 1, cos 0) d = 1 points along +beta and q along -alpha.
    mc_inv_park_f32(0.0f, 1.0f, 0.0f, 1.0f, &alpha, &beta);
    EXPECT_EQ(alpha, 0.0f); // exact: products with 0 and 1 are exact
    EXPECT_EQ(beta, 1.0f);
    mc_inv_park_f32(1.0f, 0.0f, 1.0f, 0.0f, &alpha, &beta);
    EXPECT_EQ(alpha, 0.0f);
    EXPECT_EQ(beta, 1.0f);
    float d = 0.0f;
    float q = 0.0f;
    mc_park_f32(-1.0f, 0.0f, 1.0f, 0.0f, &d, &q);
    EXPECT_EQ(d, 0.0f);
    EXPECT_EQ(q, 1.0f);

    float a = 0.0f;
    float b = 0.0f;
    float c = 0.0f;
    mc_inv_clarke_f32(0.0f, 1.0f, &a, &b, &c);
    EXPECT_EQ(a, 0.0f);
    // Tolerance 1 ulp: sqrt(3)/2 rounded once, times 1.
    EXPECT_NEAR(b, static_cast<float>(std::sqrt(3.0) / 2.0), FLT_EPSILON);
    EXPECT_NEAR(c, -static_cast<float>(std::sqrt(3.0) / 2.0), FLT_EPSILON);
}

TEST(TransformsF32, ClarkeInverseClarkeRoundTrip)
{
    std::mt19937 rng(12345u);
    std::uniform_real_distribution<float> dist(-100.0f, 100.0f);
    for (int i = 0; i < 10000; ++i) {
        const float alpha = dist(rng);
        const float beta = dist(rng);
        const float mag = std::fabs(alpha) + std::fabs(beta);
        float a = 0.0f;
        float b = 0.0f;
        float c = 0.0f;
        mc_inv_clarke_f32(alpha, beta, &a, &b, &c);
        // Tolerance 4 ulp of the magnitude: inverse Clarke rounds each phase
        // twice, Clarke rounds twice more, each at most 1/2 ulp of values of
        // size <= |alpha| + |beta| (the 1/3 and 1/sqrt(3) gains shrink the
        // errors, the factor 2 grows them; 4 ulp covers both paths).
        const float tol = 4.0f * FLT_EPSILON * mag;
        float alpha3 = 0.0f;
        float beta3 = 0.0f;
        mc_clarke3_f32(a, b, c, &alpha3, &beta3);
        EXPECT_NEAR(alpha3, alpha, tol);
        EXPECT_NEAR(beta3, beta, tol);
        float alpha2 = 0.0f;
        float beta2 = 0.0f;
        mc_clarke_f32(a, b, &alpha2, &beta2);
        EXPECT_NEAR(alpha2, alpha, tol);
        EXPECT_NEAR(beta2, beta, tol);
        // The phase values of a vector sum to zero (same rounding budget).
        EXPECT_NEAR(a + b + c, 0.0f, tol);
    }
}

TEST(TransformsF32, PhasesClarkeInverseClarkeRoundTrip)
{
    std::mt19937 rng(777u);
    std::uniform_real_distribution<float> dist(-50.0f, 50.0f);
    for (int i = 0; i < 10000; ++i) {
        const float ia = dist(rng);
        const float ib = dist(rng);
        const float ic = -ia - ib; // balanced (rounded once)
        float alpha = 0.0f;
        float beta = 0.0f;
        mc_clarke3_f32(ia, ib, ic, &alpha, &beta);
        float a = 0.0f;
        float b = 0.0f;
        float c = 0.0f;
        mc_inv_clarke_f32(alpha, beta, &a, &b, &c);
        // Tolerance 6 ulp of the largest phase value (<= 100 A): 2 roundings
        // in Clarke, 2 in inverse Clarke, plus the rounding of ic, each
        // below one ulp of values up to twice the largest phase.
        const float mag = std::fmax(std::fabs(ia), std::fmax(std::fabs(ib), std::fabs(ic)));
        const float tol = 6.0f * FLT_EPSILON * mag;
        EXPECT_NEAR(a, ia, tol);
        EXPECT_NEAR(b, ib, tol);
        EXPECT_NEAR(c, ic, tol);
    }
}

TEST(TransformsF32, ParkInverseParkRoundTrip)
{
    std::mt19937 rng(4242u);
    std::uniform_real_distribution<float> val(-400.0f, 400.0f);
    std::uniform_real_distribution<double> ang(-kPi, kPi);
    for (int i = 0; i < 10000; ++i) {
        const float alpha = val(rng);
        const float beta = val(rng);
        const double th = ang(rng);
        const float s = static_cast<float>(std::sin(th));
        const float c = static_cast<float>(std::cos(th));
        float d = 0.0f;
        float q = 0.0f;
        mc_park_f32(alpha, beta, s, c, &d, &q);
        float alpha2 = 0.0f;
        float beta2 = 0.0f;
        mc_inv_park_f32(d, q, s, c, &alpha2, &beta2);
        // Tolerance 6 ulp of |alpha| + |beta|: 3 roundings per transform
        // (two products, one sum), plus sin^2 + cos^2 = 1 within 2 ulp
        // because sin and cos are rounded to float.
        const float tol = 6.0f * FLT_EPSILON * (std::fabs(alpha) + std::fabs(beta));
        EXPECT_NEAR(alpha2, alpha, tol);
        EXPECT_NEAR(beta2, beta, tol);
    }
}

TEST(TransformsF32, BalancedCurrentsGiveConstantDq)
{
    // i_x = I cos(theta + phi - k 2pi/3): in the frame at theta, d = I cos phi,
    // q = I sin phi, whatever theta.
    const double amp_a = 25.0;
    const double phis[] = {0.0, 0.3, kPi / 2.0, -2.0, 3.0};
    for (double phi : phis) {
        const double d_ref = amp_a * std::cos(phi);
        const double q_ref = amp_a * std::sin(phi);
        for (int k = 0; k < 720; ++k) {
            const double th = -2.0 * kPi + k * (4.0 * kPi / 720.0);
            const float ia = static_cast<float>(amp_a * std::cos(th + phi));
            const float ib = static_cast<float>(amp_a * std::cos(th + phi - 2.0 * kPi / 3.0));
            const float ic = static_cast<float>(amp_a * std::cos(th + phi + 2.0 * kPi / 3.0));
            const float s = static_cast<float>(std::sin(th));
            const float c = static_cast<float>(std::cos(th));
            float alpha = 0.0f;
            float beta = 0.0f;
            float d = 0.0f;
            float q = 0.0f;
            // Tolerance 8 ulp of I (about 2.4e-5 A at 25 A): inputs are
            // float-rounded (1/2 ulp each, amplified by at most 2/sqrt(3)
            // in beta), Clarke adds 2 roundings, Park 3, sin/cos 1/2 ulp.
            const double tol = 8.0 * FLT_EPSILON * amp_a;
            mc_clarke3_f32(ia, ib, ic, &alpha, &beta);
            mc_park_f32(alpha, beta, s, c, &d, &q);
            EXPECT_NEAR(d, d_ref, tol) << "theta " << th << " phi " << phi;
            EXPECT_NEAR(q, q_ref, tol) << "theta " << th << " phi " << phi;
            mc_clarke_f32(ia, ib, &alpha, &beta);
            mc_park_f32(alpha, beta, s, c, &d, &q);
            EXPECT_NEAR(d, d_ref, tol) << "two-phase, theta " << th;
            EXPECT_NEAR(q, q_ref, tol) << "two-phase, theta " << th;
        }
    }
}

TEST(TransformsF32, TwoAndThreePhaseClarkeAgreeForBalancedInput)
{
    std::mt19937 rng(99u);
    std::uniform_real_distribution<float> dist(-30.0f, 30.0f);
    for (int i = 0; i < 10000; ++i) {
        const float ia = dist(rng);
        const float ib = dist(rng);
        const float ic = -ia - ib;
        float alpha2 = 0.0f;
        float beta2 = 0.0f;
        float alpha3 = 0.0f;
        float beta3 = 0.0f;
        mc_clarke_f32(ia, ib, &alpha2, &beta2);
        mc_clarke3_f32(ia, ib, ic, &alpha3, &beta3);
        // Tolerance 4 ulp of 60 A (the largest phase magnitude): each form
        // rounds twice, and ic carries one more rounding.
        const float tol = 4.0f * FLT_EPSILON * 60.0f;
        EXPECT_NEAR(alpha2, alpha3, tol);
        EXPECT_NEAR(beta2, beta3, tol);
    }
}

TEST(TransformsF32, ThreePhaseClarkeRejectsCommonMode)
{
    float alpha = 0.0f;
    float beta = 0.0f;
    float alpha_cm = 0.0f;
    float beta_cm = 0.0f;
    mc_clarke3_f32(3.0f, -1.0f, -2.0f, &alpha, &beta);
    mc_clarke3_f32(3.0f + 7.0f, -1.0f + 7.0f, -2.0f + 7.0f, &alpha_cm, &beta_cm);
    // Exact: all values are small integers, the sums are exact and both
    // sides multiply the same sum by the same constant.
    EXPECT_EQ(alpha, alpha_cm);
    EXPECT_EQ(beta, beta_cm);
    // (2*3 + 1 + 2) / 3 = 3; (-1 + 2)/sqrt(3). 1 ulp: one rounding.
    EXPECT_NEAR(alpha, 3.0f, 3.0f * FLT_EPSILON);
    EXPECT_NEAR(beta, static_cast<float>(1.0 / std::sqrt(3.0)), FLT_EPSILON);
}

// --------------------------------------------------------------- q31

// Maximum over random cases of |q31 result - exact result on the same q31
// inputs| in LSB, and of |q31 result - f32 twin on the same inputs|.
TEST(TransformsQ31, ClarkePairAgainstExactAndF32)
{
    std::mt19937 rng(2024u);
    double worst_exact = 0.0;
    double worst_f32 = 0.0;
    for (int i = 0; i < 20000; ++i) {
        // Balanced set with amplitude < 1: no result saturates.
        std::uniform_real_distribution<double> ang(-kPi, kPi);
        std::uniform_real_distribution<double> amp(0.0, 0.99);
        const double th = ang(rng);
        const double m = amp(rng);
        const q31_t ia = ToQ31(m * std::cos(th));
        const q31_t ib = ToQ31(m * std::cos(th - 2.0 * kPi / 3.0));
        const q31_t ic = ToQ31(m * std::cos(th + 2.0 * kPi / 3.0));
        const double a = ToDouble(ia);
        const double b = ToDouble(ib);
        const double c = ToDouble(ic);
        q31_t alpha = 0;
        q31_t beta = 0;
        mc_clarke_q31(ia, ib, &alpha, &beta);
        worst_exact = std::fmax(worst_exact, LsbDiff(alpha, a));
        worst_exact = std::fmax(worst_exact, LsbDiff(beta, (a + 2.0 * b) / std::sqrt(3.0)));
        mc_clarke3_q31(ia, ib, ic, &alpha, &beta);
        worst_exact = std::fmax(worst_exact, LsbDiff(alpha, (2.0 * a - b - c) / 3.0));
        worst_exact = std::fmax(worst_exact, LsbDiff(beta, (b - c) / std::sqrt(3.0)));

        // f32 twin on float-exact, unbalanced inputs; |x| < 0.49 keeps every
        // result below 1 (no saturation): |2a - b - c| / 3 < 0.66.
        const q31_t fa = FloatExactQ31(rng, -0.49, 0.49);
        const q31_t fb = FloatExactQ31(rng, -0.49, 0.49);
        const q31_t fc = FloatExactQ31(rng, -0.49, 0.49);
        const float xa = static_cast<float>(ToDouble(fa));
        const float xb = static_cast<float>(ToDouble(fb));
        const float xc = static_cast<float>(ToDouble(fc));
        float falpha = 0.0f;
        float fbeta = 0.0f;
        mc_clarke3_q31(fa, fb, fc, &alpha, &beta);
        mc_clarke3_f32(xa, xb, xc, &falpha, &fbeta);
        worst_f32 = std::fmax(worst_f32, LsbDiff(alpha, falpha));
        worst_f32 = std::fmax(worst_f32, LsbDiff(beta, fbeta));
        q31_t pa = 0;
        q31_t pb = 0;
        q31_t pc = 0;
        float ga = 0.0f;
        float gb = 0.0f;
        float gc = 0.0f;
        const q31_t va = fa;
        const q31_t vb = fb;
        mc_inv_clarke_q31(va, vb, &pa, &pb, &pc);
        mc_inv_clarke_f32(static_cast<float>(ToDouble(va)), static_cast<float>(ToDouble(vb)), &ga,
                          &gb, &gc);
        worst_exact = std::fmax(
            worst_exact, LsbDiff(pb, -0.5 * ToDouble(va) + std::sqrt(3.0) / 2.0 * ToDouble(vb)));
        worst_exact = std::fmax(
            worst_exact, LsbDiff(pc, -0.5 * ToDouble(va) - std::sqrt(3.0) / 2.0 * ToDouble(vb)));
        worst_f32 = std::fmax(worst_f32, LsbDiff(pa, ga));
        worst_f32 = std::fmax(worst_f32, LsbDiff(pb, gb));
        worst_f32 = std::fmax(worst_f32, LsbDiff(pc, gc));
    }
    // 1.5 LSB: the header's bound for unsaturated results (0.5 LSB final
    // rounding + at most 1 LSB from the Q31 constant 1/3 times a sum <= 3).
    EXPECT_LE(worst_exact, 1.5);
    // 400 LSB: the f32 twin rounds 2-3 times; with results below 2 one f32
    // ulp is at most 2^-23 = 256 LSB, so 1.5 ulp is 384 LSB, plus the q31
    // twin's own 1.5 LSB.
    EXPECT_LE(worst_f32, 400.0);
}

TEST(TransformsQ31, ParkPairAgainstExactAndF32)
{
    std::mt19937 rng(31u);
    std::uniform_real_distribution<double> ang(-kPi, kPi);
    std::uniform_real_distribution<double> amp(0.0, 0.99);
    double worst_exact = 0.0;
    double worst_f32 = 0.0;
    double worst_round_trip = 0.0;
    for (int i = 0; i < 20000; ++i) {
        const double m = amp(rng);
        const double phi = ang(rng);
        const double th = ang(rng);
        // Low 8 bits cleared: every input converts to float exactly.
        const q31_t alpha = ToQ31(m * std::cos(phi)) & ~static_cast<q31_t>(0xFF);
        const q31_t beta = ToQ31(m * std::sin(phi)) & ~static_cast<q31_t>(0xFF);
        const q31_t s = ToQ31(std::sin(th)) & ~static_cast<q31_t>(0xFF);
        const q31_t c = ToQ31(std::cos(th)) & ~static_cast<q31_t>(0xFF);
        const double xa = ToDouble(alpha);
        const double xb = ToDouble(beta);
        const double xs = ToDouble(s);
        const double xc = ToDouble(c);
        q31_t d = 0;
        q31_t q = 0;
        mc_park_q31(alpha, beta, s, c, &d, &q);
        worst_exact = std::fmax(worst_exact, LsbDiff(d, xa * xc + xb * xs));
        worst_exact = std::fmax(worst_exact, LsbDiff(q, xb * xc - xa * xs));
        float fd = 0.0f;
        float fq = 0.0f;
        mc_park_f32(static_cast<float>(xa), static_cast<float>(xb), static_cast<float>(xs),
                    static_cast<float>(xc), &fd, &fq);
        worst_f32 = std::fmax(worst_f32, LsbDiff(d, fd));
        worst_f32 = std::fmax(worst_f32, LsbDiff(q, fq));

        q31_t a2 = 0;
        q31_t b2 = 0;
        mc_inv_park_q31(d, q, s, c, &a2, &b2);
        worst_exact = std::fmax(worst_exact, LsbDiff(a2, ToDouble(d) * xc - ToDouble(q) * xs));
        worst_exact = std::fmax(worst_exact, LsbDiff(b2, ToDouble(d) * xs + ToDouble(q) * xc));

        // Round trip with full-precision sin/cos (rounded to nearest q31).
        const q31_t s_full = ToQ31(std::sin(th));
        const q31_t c_full = ToQ31(std::cos(th));
        mc_park_q31(alpha, beta, s_full, c_full, &d, &q);
        mc_inv_park_q31(d, q, s_full, c_full, &a2, &b2);
        worst_round_trip = std::fmax(worst_round_trip, LsbDiff(a2, xa));
        worst_round_trip = std::fmax(worst_round_trip, LsbDiff(b2, xb));
    }
    // 1 LSB: one rounding (0.5 LSB) plus two dropped bits of weight 2^-61.
    EXPECT_LE(worst_exact, 1.0);
    // 400 LSB: f32 Park rounds 3 times (two products, one sum) on values
    // below 1.5, each at most 1/2 ulp = 128 LSB, plus the q31 1 LSB.
    EXPECT_LE(worst_f32, 400.0);
    // 3 LSB: two transforms of 1 LSB each, plus |v| * |sin^2 + cos^2 - 1|
    // with sin and cos each rounded by 0.5 LSB (at most sqrt(2) LSB).
    EXPECT_LE(worst_round_trip, 3.0);
}

TEST(TransformsQ31, BalancedCurrentsGiveConstantDq)
{
    const double amp = 0.8;
    const double phi = 0.7;
    for (int k = 0; k < 720; ++k) {
        const double th = -kPi + k * (2.0 * kPi / 720.0);
        const q31_t ia = ToQ31(amp * std::cos(th + phi));
        const q31_t ib = ToQ31(amp * std::cos(th + phi - 2.0 * kPi / 3.0));
        const q31_t s = ToQ31(std::sin(th));
        const q31_t c = ToQ31(std::cos(th));
        q31_t alpha = 0;
        q31_t beta = 0;
        q31_t d = 0;
        q31_t q = 0;
        mc_clarke_q31(ia, ib, &alpha, &beta);
        mc_park_q31(alpha, beta, s, c, &d, &q);
        // 4 LSB: inputs rounded to q31 (0.5 LSB each, gain up to 2/sqrt(3)
        // in beta), Clarke <= 1 LSB, sin/cos rounded (0.5 LSB times 0.8),
        // Park <= 1 LSB.
        EXPECT_LE(LsbDiff(d, amp * std::cos(phi)), 4.0) << "theta " << th;
        EXPECT_LE(LsbDiff(q, amp * std::sin(phi)), 4.0) << "theta " << th;
    }
}

TEST(TransformsQ31, SaturatesAtTheRangeEdgesInsteadOfWrapping)
{
    q31_t alpha = 0;
    q31_t beta = 0;
    // (1 + 2) / sqrt(3) = 1.73: saturates high; (-1 - 2)/sqrt(3) low.
    mc_clarke_q31(MC_Q31_MAX, MC_Q31_MAX, &alpha, &beta);
    EXPECT_EQ(alpha, MC_Q31_MAX);
    EXPECT_EQ(beta, MC_Q31_MAX);
    mc_clarke_q31(MC_Q31_MIN, MC_Q31_MIN, &alpha, &beta);
    EXPECT_EQ(alpha, MC_Q31_MIN);
    EXPECT_EQ(beta, MC_Q31_MIN);

    // alpha = (2 + 1 + 1) / 3 = 4/3 saturates; beta = (b - c) / sqrt(3) = 0.
    mc_clarke3_q31(MC_Q31_MAX, MC_Q31_MIN, MC_Q31_MIN, &alpha, &beta);
    EXPECT_EQ(alpha, MC_Q31_MAX);
    EXPECT_EQ(beta, 0);
    mc_clarke3_q31(MC_Q31_MIN, MC_Q31_MAX, MC_Q31_MAX, &alpha, &beta);
    EXPECT_EQ(alpha, MC_Q31_MIN);
    EXPECT_EQ(beta, 0);
    // beta = (1 + 1) / sqrt(3) = 1.15 saturates; alpha = (0 - b - c) / 3 is
    // 2^-31 / 3 (rounds to 0).
    mc_clarke3_q31(0, MC_Q31_MAX, MC_Q31_MIN, &alpha, &beta);
    EXPECT_EQ(alpha, 0);
    EXPECT_EQ(beta, MC_Q31_MAX);
    mc_clarke3_q31(0, MC_Q31_MIN, MC_Q31_MAX, &alpha, &beta);
    EXPECT_EQ(alpha, 0);
    EXPECT_EQ(beta, MC_Q31_MIN);

    // Park with every operand -1: d = 1 + 1 = 2 -> MAX (a Q2.62 sum would
    // have overflowed here), q = -1 + 1 = 0.
    q31_t d = 0;
    q31_t q = 0;
    mc_park_q31(MC_Q31_MIN, MC_Q31_MIN, MC_Q31_MIN, MC_Q31_MIN, &d, &q);
    EXPECT_EQ(d, MC_Q31_MAX);
    EXPECT_EQ(q, 0);
    // alpha = beta = -1, sin = cos = 1 - 2^-31: d = -2 -> MIN; q is the
    // difference of two identical products, exactly 0.
    mc_park_q31(MC_Q31_MIN, MC_Q31_MIN, MC_Q31_MAX, MC_Q31_MAX, &d, &q);
    EXPECT_EQ(d, MC_Q31_MIN);
    EXPECT_EQ(q, 0);
    // alpha = 1, beta = -1, sin = 1, cos = -1: d = -1 - 1 -> MIN;
    // q = (-1)(-1) - (1 - 2^-31)^2 = 2^-30 - 2^-62, not saturated.
    mc_park_q31(MC_Q31_MAX, MC_Q31_MIN, MC_Q31_MAX, MC_Q31_MIN, &d, &q);
    EXPECT_EQ(d, MC_Q31_MIN);
    const double one_minus = ToDouble(MC_Q31_MAX);
    // 1 LSB: the header's bound for an unsaturated Park result.
    EXPECT_LE(LsbDiff(q, 1.0 - one_minus * one_minus), 1.0);

    // d = -1, q = 1, sin = 1, cos = -1: alpha = d c - q s = 1 - 1 (+2^-30),
    // beta = d s + q c = -2 -> MIN.
    mc_inv_park_q31(MC_Q31_MIN, MC_Q31_MAX, MC_Q31_MAX, MC_Q31_MIN, &alpha, &beta);
    EXPECT_LE(LsbDiff(alpha, 1.0 - one_minus * one_minus), 1.0); // 1 LSB as above
    EXPECT_EQ(beta, MC_Q31_MIN);
    mc_inv_park_q31(MC_Q31_MIN, MC_Q31_MIN, MC_Q31_MIN, MC_Q31_MIN, &alpha, &beta);
    // alpha = 1 - 1 = 0, beta = 1 + 1 -> MAX.
    EXPECT_EQ(alpha, 0);
    EXPECT_EQ(beta, MC_Q31_MAX);

    q31_t a = 0;
    q31_t b = 0;
    q31_t c = 0;
    // b = 1/2 + 0.87 = 1.37 -> MAX, c = 1/2 - 0.87 = -0.37.
    mc_inv_clarke_q31(MC_Q31_MIN, MC_Q31_MAX, &a, &b, &c);
    EXPECT_EQ(a, MC_Q31_MIN);
    EXPECT_EQ(b, MC_Q31_MAX);
    // 1 LSB: the header's bound for an unsaturated inverse Clarke result.
    EXPECT_LE(LsbDiff(c, 0.5 - std::sqrt(3.0) / 2.0 * ToDouble(MC_Q31_MAX)), 1.0);
    // c = -1/2 - 0.87 -> MIN.
    mc_inv_clarke_q31(MC_Q31_MAX, MC_Q31_MAX, &a, &b, &c);
    EXPECT_EQ(c, MC_Q31_MIN);
}

TEST(TransformsQ31, KnownValues)
{
    q31_t alpha = 0;
    q31_t beta = 0;
    // a = 1/2, b = c = -1/4: alpha = 1/2 exactly, beta = 0 exactly.
    mc_clarke3_q31(ToQ31(0.5), ToQ31(-0.25), ToQ31(-0.25), &alpha, &beta);
    // 1 LSB: (1 + 0.5) * round(2^31/3) carries the constant's 1/3 LSB error.
    EXPECT_LE(LsbDiff(alpha, 0.5), 1.0);
    EXPECT_EQ(beta, 0);
    mc_clarke_q31(ToQ31(0.5), ToQ31(-0.25), &alpha, &beta);
    EXPECT_EQ(alpha, ToQ31(0.5));
    EXPECT_EQ(beta, 0);
}
