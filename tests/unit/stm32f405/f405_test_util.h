// Helpers for the STM32F405 HAL host tests: register files in RAM and
// byte-wise snapshots to check that a rejected call wrote nothing.
#ifndef F405_TEST_UTIL_H
#define F405_TEST_UTIL_H

#include <cstdint>
#include <cstring>
#include <vector>

#include "mc_f405_hal.h"

// Byte copy of a register file or driver struct (volatile members: copy
// through a const volatile byte view, not memcpy).
template <typename T> std::vector<uint8_t> snapshot(const T &obj)
{
    const volatile uint8_t *p = reinterpret_cast<const volatile uint8_t *>(&obj);
    std::vector<uint8_t> v(sizeof(T));
    for (size_t i = 0; i < sizeof(T); ++i) {
        v[i] = p[i];
    }
    return v;
}

// Fill a struct with a pattern so that "unchanged" is a strong statement.
template <typename T> void poison(T &obj)
{
    volatile uint8_t *p = reinterpret_cast<volatile uint8_t *>(&obj);
    for (size_t i = 0; i < sizeof(T); ++i) {
        p[i] = 0xA5u;
    }
}

// Relative tolerance for float results of a few multiplications on values
// of order 1..100: float has 2^-24 = 6e-8 relative rounding per operation,
// at most ~5 operations; 1e-5 leaves two orders of margin while still
// catching any wrong constant (the smallest scale error tested is 1/4096).
inline double rel_tol(double expected)
{
    const double a = expected < 0 ? -expected : expected;
    return 1e-5 * a + 1e-6;
}

#endif
