// Unit tests for the SVPWM (f32 and q31 twins).
//
// The reference below is written from the definition, independently of the
// kernel's formulation: limit the request by scaling the vector (circle:
// to vbus/sqrt(3); hexagon: so that the largest line-to-line voltage is
// vbus), then centre the phase voltages (min-max injection) and divide by
// vbus. The kernel instead divides by D = max(vbus, L); both must agree.

#include <gtest/gtest.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>

#include "svpwm_raw_limit.h"
#include "transforms/mc_svpwm.h"
#include "transforms/mc_svpwm_q31.h"

namespace
{

constexpr double kPi = 3.14159265358979323846;
constexpr double kQ31 = 2147483648.0; // 2^31
const double kSqrt3 = std::sqrt(3.0);

// Float duty tolerance, 16 * 2^-24 (about 1e-6): a duty is 0.5 + x with
// |x| <= 0.5; the f32 path rounds about 8 times (normalisation 2, inverse
// Clarke 2, mid 2, difference, product with 1/D plus the rounding of 1/D,
// the final sum), each at most 1/2 ulp of values <= 1 (ulp 2^-23 at 1,
// 2^-24 below 1), plus the mc_sqrt_f32 error (a few ulp) on the circle
// limit; 16 * 2^-24 leaves room for these to add up.
constexpr double kDutyTol = 16.0 / 16777216.0;

struct Duties {
    double d[3];
    bool limited;
};

void Phases(double alpha, double beta, double v[3])
{
    v[0] = alpha;
    v[1] = -0.5 * alpha + 0.5 * kSqrt3 * beta;
    v[2] = -0.5 * alpha - 0.5 * kSqrt3 * beta;
}

double Max3(const double v[3])
{
    return std::fmax(v[0], std::fmax(v[1], v[2]));
}
double Min3(const double v[3])
{
    return std::fmin(v[0], std::fmin(v[1], v[2]));
}

Duties RefSvpwm(double alpha, double beta, double vbus, mc_svpwm_limit_t limit)
{
    double v[3];
    Phases(alpha, beta, v);
    double scale = 1.0;
    if (limit == MC_SVPWM_LIMIT_CIRCLE) {
        const double mag = std::hypot(alpha, beta);
        if (mag > vbus / kSqrt3) {
            scale = vbus / kSqrt3 / mag;
        }
    } else {
        const double spread = Max3(v) - Min3(v);
        if (spread > vbus) {
            scale = vbus / spread;
        }
    }
    Duties out{};
    out.limited = scale < 1.0;
    for (double &x : v) {
        x *= scale;
    }
    const double mid = 0.5 * (Max3(v) + Min3(v));
    for (int i = 0; i < 3; ++i) {
        out.d[i] = 0.5 + (v[i] - mid) / vbus;
    }
    return out;
}

// Radius of the hexagon (max line-to-line voltage = vbus) along angle th.
double HexRadius(double vbus, double th)
{
    double v[3];
    Phases(std::cos(th), std::sin(th), v);
    return vbus / (Max3(v) - Min3(v));
}

// The average voltage vector the duties apply (inverse of the modulator):
// pole voltages d_x * vbus, Clarke removes their common mode.
void Applied(double da, double db, double dc, double vbus, double *p_alpha, double *p_beta)
{
    *p_alpha = vbus * (2.0 * da - db - dc) / 3.0;
    *p_beta = vbus * (db - dc) / kSqrt3;
}

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

double ToDouble(q31_t x)
{
    return static_cast<double>(x) / kQ31;
}

const mc_svpwm_limit_t kLimits[] = {MC_SVPWM_LIMIT_CIRCLE, MC_SVPWM_LIMIT_HEXAGON};

} // namespace

// --------------------------------------------------------------- f32

TEST(SvpwmF32, LinearRegionReproducesLineToLineVoltages)
{
    std::mt19937 rng(1u);
    std::uniform_real_distribution<double> ang(-kPi, kPi);
    std::uniform_real_distribution<double> frac(0.0, 1.0);
    std::uniform_real_distribution<double> bus(12.0, 600.0);
    for (mc_svpwm_limit_t limit : kLimits) {
        for (int i = 0; i < 20000; ++i) {
            const double vbus = static_cast<float>(bus(rng));
            const double th = ang(rng);
            // Inside the inscribed circle (the linear region of both limits).
            const double mag = 0.9999 * frac(rng) * vbus / kSqrt3;
            const float alpha = static_cast<float>(mag * std::cos(th));
            const float beta = static_cast<float>(mag * std::sin(th));
            float d[3] = {-1.0f, -1.0f, -1.0f};
            const uint32_t flags =
                mc_svpwm_f32(alpha, beta, static_cast<float>(vbus), limit, &d[0], &d[1], &d[2]);
            ASSERT_EQ(flags, MC_SVPWM_FLAG_NONE) << "limit " << limit << " |v| " << mag;
            double v[3];
            Phases(alpha, beta, v);
            for (int k = 0; k < 3; ++k) {
                EXPECT_GE(d[k], 0.0f);
                EXPECT_LE(d[k], 1.0f);
                // Line-to-line: two duties, each within kDutyTol, times vbus.
                const int n = (k + 1) % 3;
                EXPECT_NEAR((static_cast<double>(d[k]) - d[n]) * vbus, v[k] - v[n],
                            2.0 * kDutyTol * vbus);
            }
            // Min-max injection centres the duties: max + min = 1 (two
            // duties, each within kDutyTol).
            const double dd[3] = {d[0], d[1], d[2]};
            EXPECT_NEAR(Max3(dd) + Min3(dd), 1.0, 2.0 * kDutyTol);
            const Duties ref = RefSvpwm(alpha, beta, vbus, limit);
            for (int k = 0; k < 3; ++k) {
                EXPECT_NEAR(d[k], ref.d[k], kDutyTol);
            }
        }
    }
}

TEST(SvpwmF32, HexagonIsLinearBeyondTheCircleWhereTheCircleLimits)
{
    std::mt19937 rng(2u);
    std::uniform_real_distribution<double> ang(-kPi, kPi);
    std::uniform_real_distribution<double> frac(0.0, 1.0);
    const float vbus = 48.0f;
    int tested = 0;
    for (int i = 0; i < 20000; ++i) {
        const double th = ang(rng);
        const double r_hex = HexRadius(vbus, th);
        const double r_circle = vbus / kSqrt3;
        if (r_hex < 1.01 * r_circle) {
            continue; // near a flat side: no room between circle and hexagon
        }
        ++tested;
        const double mag = 1.002 * r_circle + frac(rng) * (0.998 * r_hex - 1.002 * r_circle);
        const float alpha = static_cast<float>(mag * std::cos(th));
        const float beta = static_cast<float>(mag * std::sin(th));
        float d[3];
        uint32_t flags =
            mc_svpwm_f32(alpha, beta, vbus, MC_SVPWM_LIMIT_HEXAGON, &d[0], &d[1], &d[2]);
        EXPECT_EQ(flags, MC_SVPWM_FLAG_NONE);
        double v[3];
        Phases(alpha, beta, v);
        for (int k = 0; k < 3; ++k) {
            const int n = (k + 1) % 3;
            // Same reasoning as in the linear-region test.
            EXPECT_NEAR((static_cast<double>(d[k]) - d[n]) * vbus, v[k] - v[n],
                        2.0 * kDutyTol * vbus);
        }
        flags = mc_svpwm_f32(alpha, beta, vbus, MC_SVPWM_LIMIT_CIRCLE, &d[0], &d[1], &d[2]);
        EXPECT_EQ(flags, MC_SVPWM_FLAG_LIMITED);
    }
    EXPECT_GT(tested, 5000); // about 70 % of the directions qualify
}

TEST(SvpwmF32, CircleLimitKeepsDirectionAndGivesVbusOverSqrt3)
{
    std::mt19937 rng(3u);
    std::uniform_real_distribution<double> ang(-kPi, kPi);
    std::uniform_real_distribution<double> over(1.001, 100.0);
    std::uniform_real_distribution<double> bus(12.0, 600.0);
    for (int i = 0; i < 20000; ++i) {
        const float vbus = static_cast<float>(bus(rng));
        const double th = ang(rng);
        const double r_circle = vbus / kSqrt3;
        const double mag = over(rng) * r_circle;
        const float alpha = static_cast<float>(mag * std::cos(th));
        const float beta = static_cast<float>(mag * std::sin(th));
        float d[3];
        const uint32_t flags =
            mc_svpwm_f32(alpha, beta, vbus, MC_SVPWM_LIMIT_CIRCLE, &d[0], &d[1], &d[2]);
        ASSERT_EQ(flags, MC_SVPWM_FLAG_LIMITED);
        double ra = 0.0;
        double rb = 0.0;
        Applied(d[0], d[1], d[2], vbus, &ra, &rb);
        // Magnitude: the applied vector is a combination of duties each
        // within kDutyTol, so it is within about 2 * kDutyTol * vbus.
        EXPECT_NEAR(std::hypot(ra, rb), r_circle, 2.0 * kDutyTol * vbus);
        // Direction: the component across the request, same bound.
        const double cross = (ra * beta - rb * alpha) / std::hypot(alpha, beta);
        EXPECT_NEAR(cross, 0.0, 2.0 * kDutyTol * vbus);
        EXPECT_GT(ra * alpha + rb * beta, 0.0);
        for (float x : d) {
            EXPECT_GE(x, 0.0f);
            EXPECT_LE(x, 1.0f);
        }
        // The applied vector reported for anti-windup matches the duties.
        float la = alpha;
        float lb = beta;
        EXPECT_EQ(mc_svpwm_limit_f32(&la, &lb, vbus, MC_SVPWM_LIMIT_CIRCLE), MC_SVPWM_FLAG_LIMITED);
        EXPECT_NEAR(la, ra, 2.0 * kDutyTol * vbus);
        EXPECT_NEAR(lb, rb, 2.0 * kDutyTol * vbus);
    }
}

TEST(SvpwmF32, HexagonLimitHitsTheBoundaryAlongTheRequest)
{
    std::mt19937 rng(4u);
    std::uniform_real_distribution<double> ang(-kPi, kPi);
    std::uniform_real_distribution<double> over(1.001, 100.0);
    const float vbus = 24.0f;
    for (int i = 0; i < 20000; ++i) {
        const double th = ang(rng);
        const double r_hex = HexRadius(vbus, th);
        const double mag = over(rng) * r_hex;
        const float alpha = static_cast<float>(mag * std::cos(th));
        const float beta = static_cast<float>(mag * std::sin(th));
        float d[3];
        const uint32_t flags =
            mc_svpwm_f32(alpha, beta, vbus, MC_SVPWM_LIMIT_HEXAGON, &d[0], &d[1], &d[2]);
        ASSERT_EQ(flags, MC_SVPWM_FLAG_LIMITED);
        const double dd[3] = {d[0], d[1], d[2]};
        // On the boundary: one phase always high, one always low (duty
        // rounding, kDutyTol).
        EXPECT_NEAR(Min3(dd), 0.0, kDutyTol);
        EXPECT_NEAR(Max3(dd), 1.0, kDutyTol);
        EXPECT_GE(Min3(dd), 0.0);
        EXPECT_LE(Max3(dd), 1.0);
        double ra = 0.0;
        double rb = 0.0;
        Applied(d[0], d[1], d[2], vbus, &ra, &rb);
        // Same bounds as for the circle limit.
        EXPECT_NEAR(std::hypot(ra, rb), r_hex, 2.0 * kDutyTol * vbus);
        const double cross = (ra * beta - rb * alpha) / std::hypot(alpha, beta);
        EXPECT_NEAR(cross, 0.0, 2.0 * kDutyTol * vbus);
        EXPECT_GT(ra * alpha + rb * beta, 0.0);
        float la = alpha;
        float lb = beta;
        EXPECT_EQ(mc_svpwm_limit_f32(&la, &lb, vbus, MC_SVPWM_LIMIT_HEXAGON),
                  MC_SVPWM_FLAG_LIMITED);
        EXPECT_NEAR(la, ra, 2.0 * kDutyTol * vbus);
        EXPECT_NEAR(lb, rb, 2.0 * kDutyTol * vbus);
    }
}

TEST(SvpwmF32, ZeroRequestGivesHalfDuty)
{
    for (mc_svpwm_limit_t limit : kLimits) {
        float d[3] = {0.0f, 0.0f, 0.0f};
        EXPECT_EQ(mc_svpwm_f32(0.0f, 0.0f, 48.0f, limit, &d[0], &d[1], &d[2]), MC_SVPWM_FLAG_NONE);
        // Exact: 0.5 + 0 * (1/D).
        EXPECT_EQ(d[0], 0.5f);
        EXPECT_EQ(d[1], 0.5f);
        EXPECT_EQ(d[2], 0.5f);
    }
}

TEST(SvpwmF32, BadVbusAndNonFiniteInputGiveZeroVoltage)
{
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    const float bad_vbus[] = {nan, 0.0f, -0.0f, -12.0f, inf, -inf};
    for (mc_svpwm_limit_t limit : kLimits) {
        for (float vbus : bad_vbus) {
            float d[3] = {0.0f, 0.0f, 0.0f};
            EXPECT_EQ(mc_svpwm_f32(5.0f, -3.0f, vbus, limit, &d[0], &d[1], &d[2]),
                      MC_SVPWM_FLAG_BAD_VBUS)
                << "vbus " << vbus;
            for (float x : d) {
                EXPECT_EQ(x, 0.5f); // exact by definition
            }
            float la = 5.0f;
            float lb = -3.0f;
            EXPECT_EQ(mc_svpwm_limit_f32(&la, &lb, vbus, limit), MC_SVPWM_FLAG_BAD_VBUS);
            EXPECT_EQ(la, 0.0f);
            EXPECT_EQ(lb, 0.0f);
            EXPECT_EQ(mc_svpwm_max_voltage_f32(vbus, limit), 0.0f);
        }
        const float bad_v[][2] = {{nan, 1.0f}, {1.0f, nan}, {inf, 0.0f}, {0.0f, -inf}};
        for (const auto &v : bad_v) {
            float d[3] = {0.0f, 0.0f, 0.0f};
            EXPECT_EQ(mc_svpwm_f32(v[0], v[1], 48.0f, limit, &d[0], &d[1], &d[2]),
                      MC_SVPWM_FLAG_BAD_INPUT);
            for (float x : d) {
                EXPECT_EQ(x, 0.5f);
            }
            float la = v[0];
            float lb = v[1];
            EXPECT_EQ(mc_svpwm_limit_f32(&la, &lb, 48.0f, limit), MC_SVPWM_FLAG_BAD_INPUT);
            EXPECT_EQ(la, 0.0f);
            EXPECT_EQ(lb, 0.0f);
        }
        float d[3] = {0.0f, 0.0f, 0.0f};
        EXPECT_EQ(mc_svpwm_f32(nan, 0.0f, nan, limit, &d[0], &d[1], &d[2]),
                  MC_SVPWM_FLAG_BAD_VBUS | MC_SVPWM_FLAG_BAD_INPUT);
        EXPECT_EQ(d[0], 0.5f);
    }
}

TEST(SvpwmF32, InvalidLimitAndNullPointersAreRejected)
{
    float d[3] = {0.0f, 0.0f, 0.0f};
    EXPECT_EQ(svpwm_f32_raw_limit(5.0f, 1.0f, 48.0f, 2, &d[0], &d[1], &d[2]),
              MC_SVPWM_FLAG_BAD_INPUT);
    EXPECT_EQ(d[0], 0.5f);
    EXPECT_EQ(d[1], 0.5f);
    EXPECT_EQ(d[2], 0.5f);
    EXPECT_EQ(svpwm_f32_raw_limit(5.0f, 1.0f, 48.0f, -1, &d[0], &d[1], &d[2]),
              MC_SVPWM_FLAG_BAD_INPUT);
    EXPECT_EQ(svpwm_max_voltage_raw_limit(48.0f, 7), 0.0f);

    d[0] = 0.25f;
    d[1] = 0.25f;
    EXPECT_EQ(mc_svpwm_f32(5.0f, 1.0f, 48.0f, MC_SVPWM_LIMIT_CIRCLE, &d[0], &d[1], nullptr),
              MC_SVPWM_FLAG_BAD_INPUT);
    EXPECT_EQ(d[0], 0.25f); // nothing written
    EXPECT_EQ(d[1], 0.25f);
    float lb = 1.0f;
    EXPECT_EQ(mc_svpwm_limit_f32(nullptr, &lb, 48.0f, MC_SVPWM_LIMIT_CIRCLE),
              MC_SVPWM_FLAG_BAD_INPUT);
    EXPECT_EQ(lb, 1.0f);
}

TEST(SvpwmF32, HugeFiniteRequestsDoNotOverflow)
{
    const float big = FLT_MAX;
    const float requests[][3] = {
        {big, -big, 48.0f}, {-big, big / 3.0f, 48.0f}, {1e30f, 2e30f, 1e-30f}, {0.0f, -big, 1e-3f}};
    for (mc_svpwm_limit_t limit : kLimits) {
        for (const auto &r : requests) {
            float d[3];
            const uint32_t flags = mc_svpwm_f32(r[0], r[1], r[2], limit, &d[0], &d[1], &d[2]);
            EXPECT_EQ(flags, MC_SVPWM_FLAG_LIMITED);
            for (float x : d) {
                EXPECT_GE(x, 0.0f);
                EXPECT_LE(x, 1.0f);
            }
            // Direction kept: compare the applied direction with the
            // request's in units where vbus = 1 (kDutyTol per duty).
            double ra = 0.0;
            double rb = 0.0;
            Applied(d[0], d[1], d[2], 1.0, &ra, &rb);
            const double ra_req = r[0];
            const double rb_req = r[1];
            const double cross = (ra * rb_req - rb * ra_req) / std::hypot(ra_req, rb_req);
            EXPECT_NEAR(cross, 0.0, 2.0 * kDutyTol);
            EXPECT_GT(ra * ra_req + rb * rb_req, 0.0);
        }
    }
}

TEST(SvpwmF32, MaxVoltage)
{
    // 1 ulp: one rounded product.
    EXPECT_NEAR(mc_svpwm_max_voltage_f32(48.0f, MC_SVPWM_LIMIT_CIRCLE), 48.0 / kSqrt3,
                48.0 * FLT_EPSILON);
    EXPECT_NEAR(mc_svpwm_max_voltage_f32(48.0f, MC_SVPWM_LIMIT_HEXAGON), 32.0, 32.0 * FLT_EPSILON);
    // A request of exactly this size along a phase axis is not limited by
    // the hexagon; along a flat side (30 degrees) the circle radius is.
    float d[3];
    const float vmax = mc_svpwm_max_voltage_f32(48.0f, MC_SVPWM_LIMIT_HEXAGON);
    EXPECT_EQ(mc_svpwm_f32(0.999f * vmax, 0.0f, 48.0f, MC_SVPWM_LIMIT_HEXAGON, &d[0], &d[1], &d[2]),
              MC_SVPWM_FLAG_NONE);
    EXPECT_EQ(mc_svpwm_f32(1.001f * vmax, 0.0f, 48.0f, MC_SVPWM_LIMIT_HEXAGON, &d[0], &d[1], &d[2]),
              MC_SVPWM_FLAG_LIMITED);
}

// --------------------------------------------------------------- q31

namespace
{

// Error bound of the q31 twin in LSB, as derived in mc_svpwm.h: 0.5 for the
// rounded division, 0.26 for the Q31 constant sqrt(3)/2 (0.38 LSB times
// |beta| / D <= 2/3), and, when limited, the rounding of the divisor D to
// Q31 seen through an offset of at most 1/2: 0.5 * 1.37 LSB / D (circle:
// |v| rounded to 0.5 LSB, times sqrt(3), plus 0.5) or 0.5 * 0.5 LSB / D
// (hexagon: max - min rounded once), D in per unit.
double Q31BoundLsb(mc_svpwm_limit_t limit, double den_pu)
{
    const double den_term = (limit == MC_SVPWM_LIMIT_CIRCLE) ? 0.69 : 0.25;
    return 0.77 + den_term / den_pu;
}

// Exact D = max(vbus, L) for a request, in per unit.
double RefDen(double alpha, double beta, double vbus, mc_svpwm_limit_t limit)
{
    double v[3];
    Phases(alpha, beta, v);
    const double measure =
        (limit == MC_SVPWM_LIMIT_CIRCLE) ? kSqrt3 * std::hypot(alpha, beta) : Max3(v) - Min3(v);
    return std::fmax(vbus, measure);
}

// Worst ratio |q31 duty - exact reference| / Q31BoundLsb over random
// requests of every size (1 or less: the bound holds).
double WorstQ31VsReference(mc_svpwm_limit_t limit, double vbus_lo, std::mt19937 &rng)
{
    std::uniform_int_distribution<int32_t> any(MC_Q31_MIN, MC_Q31_MAX);
    std::uniform_real_distribution<double> bus(vbus_lo, 0.999);
    double worst = 0.0;
    for (int i = 0; i < 50000; ++i) {
        // A third of the cases small, a third tiny, a third anywhere.
        q31_t alpha = any(rng);
        q31_t beta = any(rng);
        if ((i % 3) == 1) {
            alpha /= 4;
            beta /= 4;
        } else if ((i % 3) == 2) {
            alpha /= 256;
            beta /= 256;
        }
        const q31_t vbus = ToQ31(bus(rng));
        q31_t d[3] = {-1, -1, -1};
        const uint32_t flags = mc_svpwm_q31(alpha, beta, vbus, limit, &d[0], &d[1], &d[2]);
        const double xa = ToDouble(alpha);
        const double xb = ToDouble(beta);
        const double xv = ToDouble(vbus);
        const Duties ref = RefSvpwm(xa, xb, xv, limit);
        EXPECT_EQ((flags & MC_SVPWM_FLAG_LIMITED) != 0u, ref.limited)
            << "alpha " << alpha << " beta " << beta << " vbus " << vbus;
        const double bound = Q31BoundLsb(limit, RefDen(xa, xb, xv, limit));
        for (int k = 0; k < 3; ++k) {
            EXPECT_GE(d[k], 0);
            const double ref_q31 = std::fmin(ref.d[k] * kQ31, static_cast<double>(MC_Q31_MAX));
            worst = std::fmax(worst, std::fabs(static_cast<double>(d[k]) - ref_q31) / bound);
        }
    }
    return worst;
}

} // namespace

TEST(SvpwmQ31, AgainstExactReference)
{
    std::mt19937 rng(5u);
    for (mc_svpwm_limit_t limit : kLimits) {
        // vbus from 0.25 pu up (a base voltage up to 4 x vbus): within the
        // derived bound (at most 3.5 LSB for the circle, 1.8 for the hexagon).
        EXPECT_LE(WorstQ31VsReference(limit, 0.25, rng), 1.0) << "limit " << limit;
        // The LIMITED flag could differ from the reference for a request
        // within an LSB of the limit; random inputs do not hit that.
    }
}

TEST(SvpwmQ31, SmallVbusLosesResolutionAsDocumented)
{
    std::mt19937 rng(6u);
    for (mc_svpwm_limit_t limit : kLimits) {
        // vbus down to 1/64 pu: the divisor's rounding weighs up to 64 times
        // more, still within the same derived bound.
        EXPECT_LE(WorstQ31VsReference(limit, 1.0 / 64.0, rng), 1.0) << "limit " << limit;
    }
}

TEST(SvpwmQ31, AgainstF32Twin)
{
    std::mt19937 rng(7u);
    std::uniform_real_distribution<double> ang(-kPi, kPi);
    std::uniform_real_distribution<double> mag(0.0, 1.0);
    std::uniform_real_distribution<double> bus(0.25, 0.999);
    for (mc_svpwm_limit_t limit : kLimits) {
        double worst = 0.0;
        for (int i = 0; i < 50000; ++i) {
            const double th = ang(rng);
            const double m = mag(rng);
            // Low 8 bits cleared: the f32 twin sees exactly the same inputs.
            const q31_t alpha = ToQ31(m * std::cos(th)) & ~static_cast<q31_t>(0xFF);
            const q31_t beta = ToQ31(m * std::sin(th)) & ~static_cast<q31_t>(0xFF);
            const q31_t vbus = ToQ31(bus(rng)) & ~static_cast<q31_t>(0xFF);
            q31_t dq[3];
            float df[3];
            const uint32_t fq = mc_svpwm_q31(alpha, beta, vbus, limit, &dq[0], &dq[1], &dq[2]);
            const uint32_t ff = mc_svpwm_f32(
                static_cast<float>(ToDouble(alpha)), static_cast<float>(ToDouble(beta)),
                static_cast<float>(ToDouble(vbus)), limit, &df[0], &df[1], &df[2]);
            EXPECT_EQ(fq, ff);
            for (int k = 0; k < 3; ++k) {
                worst = std::fmax(worst, std::fabs(static_cast<double>(dq[k]) -
                                                   static_cast<double>(df[k]) * kQ31));
            }
        }
        // kDutyTol (16 * 2^-24 = 2048 LSB) for the f32 twin plus the q31
        // twin's bound at vbus >= 0.25 pu (3.6 LSB, AgainstExactReference).
        EXPECT_LE(worst, kDutyTol * kQ31 + Q31BoundLsb(limit, 0.25)) << "limit " << limit;
    }
}

TEST(SvpwmQ31, HexagonLimitHitsTheRails)
{
    std::mt19937 rng(8u);
    std::uniform_real_distribution<double> ang(-kPi, kPi);
    for (int i = 0; i < 10000; ++i) {
        const double th = ang(rng);
        const q31_t vbus = ToQ31(0.5);
        // Magnitude 0.9 pu > 2/3 * 0.5: always outside the hexagon.
        const q31_t alpha = ToQ31(0.9 * std::cos(th));
        const q31_t beta = ToQ31(0.9 * std::sin(th));
        q31_t d[3];
        EXPECT_EQ(mc_svpwm_q31(alpha, beta, vbus, MC_SVPWM_LIMIT_HEXAGON, &d[0], &d[1], &d[2]),
                  MC_SVPWM_FLAG_LIMITED);
        const q31_t dmin = std::min(d[0], std::min(d[1], d[2]));
        const q31_t dmax = std::max(d[0], std::max(d[1], d[2]));
        // 2 LSB: D is max - min rounded to Q31, so (v - mid) / D lands
        // within about 1 LSB of +-1/2, plus the division's rounding.
        EXPECT_GE(dmin, 0);
        EXPECT_LE(dmin, 2);
        EXPECT_GE(dmax, MC_Q31_MAX - 2);
    }
}

TEST(SvpwmQ31, RangeEdgesSaturateInsteadOfWrapping)
{
    // Every operand at its extreme: |v| = sqrt(2), phase voltages up to
    // 1.37, line-to-line up to 2.45 pu, vbus at either end.
    const q31_t edges[] = {MC_Q31_MIN, MC_Q31_MAX, 0};
    const q31_t buses[] = {MC_Q31_MAX, 1};
    for (mc_svpwm_limit_t limit : kLimits) {
        for (q31_t alpha : edges) {
            for (q31_t beta : edges) {
                for (q31_t vbus : buses) {
                    q31_t d[3] = {-1, -1, -1};
                    const uint32_t flags =
                        mc_svpwm_q31(alpha, beta, vbus, limit, &d[0], &d[1], &d[2]);
                    const Duties ref =
                        RefSvpwm(ToDouble(alpha), ToDouble(beta), ToDouble(vbus), limit);
                    EXPECT_EQ((flags & MC_SVPWM_FLAG_LIMITED) != 0u, ref.limited);
                    for (int k = 0; k < 3; ++k) {
                        EXPECT_GE(d[k], 0);
                        const double ref_q31 =
                            std::fmin(ref.d[k] * kQ31, static_cast<double>(MC_Q31_MAX));
                        // The derived bound (see Q31BoundLsb) with the exact D.
                        EXPECT_LE(std::fabs(static_cast<double>(d[k]) - ref_q31),
                                  Q31BoundLsb(limit, RefDen(ToDouble(alpha), ToDouble(beta),
                                                            ToDouble(vbus), limit)))
                            << "alpha " << alpha << " beta " << beta << " vbus " << vbus;
                    }
                }
            }
        }
    }
}

TEST(SvpwmQ31, BadVbusInvalidLimitAndNullPointers)
{
    const q31_t half = static_cast<q31_t>(1) << 30;
    const q31_t bad_vbus[] = {0, -1, MC_Q31_MIN};
    for (mc_svpwm_limit_t limit : kLimits) {
        for (q31_t vbus : bad_vbus) {
            q31_t d[3] = {0, 0, 0};
            EXPECT_EQ(mc_svpwm_q31(ToQ31(0.1), ToQ31(-0.2), vbus, limit, &d[0], &d[1], &d[2]),
                      MC_SVPWM_FLAG_BAD_VBUS);
            EXPECT_EQ(d[0], half);
            EXPECT_EQ(d[1], half);
            EXPECT_EQ(d[2], half);
        }
        q31_t d[3] = {0, 0, 0};
        EXPECT_EQ(mc_svpwm_q31(0, 0, ToQ31(0.5), limit, &d[0], &d[1], &d[2]), MC_SVPWM_FLAG_NONE);
        EXPECT_EQ(d[0], half); // zero request: exactly 1/2
        EXPECT_EQ(d[1], half);
        EXPECT_EQ(d[2], half);
    }
    q31_t d[3] = {0, 0, 0};
    EXPECT_EQ(svpwm_q31_raw_limit(ToQ31(0.1), 0, ToQ31(0.5), 3, &d[0], &d[1], &d[2]),
              MC_SVPWM_FLAG_BAD_INPUT);
    EXPECT_EQ(d[0], half);
    EXPECT_EQ(svpwm_q31_raw_limit(ToQ31(0.1), 0, 0, 3, &d[0], &d[1], &d[2]),
              MC_SVPWM_FLAG_BAD_INPUT | MC_SVPWM_FLAG_BAD_VBUS);
    d[0] = 7;
    d[1] = 7;
    EXPECT_EQ(mc_svpwm_q31(ToQ31(0.1), 0, ToQ31(0.5), MC_SVPWM_LIMIT_CIRCLE, &d[0], &d[1], nullptr),
              MC_SVPWM_FLAG_BAD_INPUT);
    EXPECT_EQ(d[0], 7); // nothing written
    EXPECT_EQ(d[1], 7);
}
