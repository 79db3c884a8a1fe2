// Helpers of the q31-twin tests: conversions in double (exact for q31).
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>

extern "C" {
#include "math/mc_q31.h"
}

#include "mc_record.hpp"

namespace q31t
{

constexpr double kQ31 = 2147483648.0; // 2^31
constexpr double kPi = 3.14159265358979323846;

// engineering value -> q31 of base (rounded, saturated)
inline q31_t to_q(double v, double base)
{
    const double x = std::nearbyint(v / base * kQ31);
    if (x >= kQ31 - 1.0)
        return MC_Q31_MAX;
    if (x <= -kQ31)
        return MC_Q31_MIN;
    return static_cast<q31_t>(x);
}
// q31 of base -> engineering value
inline double from_q(q31_t q, double base)
{
    return static_cast<double>(q) / kQ31 * base;
}
// q31 angle (turn) -> rad
inline double ang_rad(q31_t a)
{
    return static_cast<double>(a) * kPi / kQ31;
}
// rad -> q31 angle (turn), wrapped
inline q31_t ang_q(double rad)
{
    const double t = std::remainder(rad, 2.0 * kPi) / kPi * kQ31; // [-2^31, 2^31]
    double r = std::nearbyint(t);
    if (r >= kQ31)
        r -= 2.0 * kQ31;
    return static_cast<q31_t>(r);
}
// |a - b| folded to [0, pi]
inline double ang_diff(double a, double b)
{
    return std::abs(std::remainder(a - b, 2.0 * kPi));
}

// Report a measured value next to its bound (ctest -V shows it; the
// documents read it as a test property, mc_record.hpp).
inline void report(const char *what, double measured, double bound, const char *unit)
{
    std::printf("[ measured ] %-48s %.4g %s (bound %.4g)\n", what, measured, unit, bound);
    mc_record(what, measured, bound, unit);
}

} // namespace q31t
