/* See bitexact.h. Inputs come from an integer LCG so they are identical on
 * both machines; outputs are hashed by their bit patterns. NaNs are folded to
 * one canonical pattern before hashing, because x86 and ARM generate
 * different default-NaN bit patterns and the kernels only promise "NaN". */
#include "bitexact.h"

#include <stdint.h>
#include <string.h>

#include "math/mc_math.h"
#include "math/mc_q31.h"

typedef struct {
    uint32_t hash;
    uint32_t count;
} bx_acc_t;

static uint32_t lcg_state;

static uint32_t lcg_next(void)
{
    lcg_state = lcg_state * 1664525u + 1013904223u;
    return lcg_state;
}

/* Uniform float in [lo, hi) from 24 random bits (exact in float). */
static float rand_f32(float lo, float hi)
{
    float u = (float)(lcg_next() >> 8) * (1.0f / 16777216.0f);
    return lo + (hi - lo) * u;
}

static void acc_u32(bx_acc_t *a, uint32_t v)
{
    for (int i = 0; i < 4; ++i) {
        a->hash ^= (v >> (8 * i)) & 0xFFu;
        a->hash *= 16777619u;
    }
}

static void acc_f32(bx_acc_t *a, float x)
{
    uint32_t bits;
    if (x != x) {
        bits = 0x7FC00000u;
    } else {
        memcpy(&bits, &x, sizeof bits);
    }
    acc_u32(a, bits);
    a->count++;
}

static void acc_q31(bx_acc_t *a, q31_t x)
{
    acc_u32(a, (uint32_t)x);
    a->count++;
}

static void u32_hex(char *out, uint32_t v)
{
    static const char digits[] = "0123456789abcdef";
    for (int i = 7; i >= 0; --i) {
        out[i] = digits[v & 0xFu];
        v >>= 4;
    }
    out[8] = '\0';
}

static void u32_dec(char *out, uint32_t v)
{
    char tmp[11];
    int n = 0;
    do {
        tmp[n++] = (char)('0' + (char)(v % 10u));
        v /= 10u;
    } while (v != 0u);
    for (int i = 0; i < n; ++i) {
        out[i] = tmp[n - 1 - i];
    }
    out[n] = '\0';
}

static void report(const char *name, const bx_acc_t *a)
{
    char num[12];
    char hex[9];
    u32_dec(num, a->count);
    u32_hex(hex, a->hash);
    mc_bx_emit(name);
    mc_bx_emit(" ");
    mc_bx_emit(num);
    mc_bx_emit(" ");
    mc_bx_emit(hex);
    mc_bx_emit("\n");
}

static bx_acc_t acc_new(uint32_t seed)
{
    bx_acc_t a = {2166136261u, 0u};
    lcg_state = seed;
    return a;
}

#define N_SWEEP 4000

static void sweep_math_f32(void)
{
    bx_acc_t a = acc_new(1u);
    for (int i = 0; i < N_SWEEP; ++i) {
        float s;
        float c;
        mc_sincos_f32(rand_f32(-100.0f, 100.0f), &s, &c);
        acc_f32(&a, s);
        acc_f32(&a, c);
    }
    static const float edges[] = {0.0f, -0.0f, MC_PI_F32, -MC_PI_F32, 1.0e6f,
                                  -3.0e9f, 1.0e30f, 1.0e-40f};
    for (unsigned i = 0; i < sizeof edges / sizeof edges[0]; ++i) {
        float s;
        float c;
        mc_sincos_f32(edges[i], &s, &c);
        acc_f32(&a, s);
        acc_f32(&a, c);
    }
    report("sincos_f32", &a);

    a = acc_new(2u);
    for (int i = 0; i < N_SWEEP; ++i) {
        /* Draw into locals: argument evaluation order is unspecified in C
         * and differs between compilers for x86 and ARM. */
        const float y = rand_f32(-10.0f, 10.0f);
        const float x = rand_f32(-10.0f, 10.0f);
        acc_f32(&a, mc_atan2_f32(y, x));
    }
    report("atan2_f32", &a);

    a = acc_new(3u);
    for (int i = 0; i < N_SWEEP; ++i) {
        acc_f32(&a, mc_sqrt_f32(rand_f32(0.0f, 1000.0f)));
        acc_f32(&a, mc_wrap_pi_f32(rand_f32(-1000.0f, 1000.0f)));
        acc_f32(&a, mc_wrap_2pi_f32(rand_f32(-1000.0f, 1000.0f)));
    }
    report("sqrt_wrap_f32", &a);
}

static void sweep_math_q31(void)
{
    bx_acc_t a = acc_new(4u);
    for (int i = 0; i < N_SWEEP; ++i) {
        q31_t s;
        q31_t c;
        mc_sincos_q31((q31_t)lcg_next(), &s, &c);
        acc_q31(&a, s);
        acc_q31(&a, c);
        const q31_t y = (q31_t)lcg_next();
        const q31_t x = (q31_t)lcg_next();
        acc_q31(&a, mc_atan2_q31(y, x));
        acc_q31(&a, mc_sqrt_q31((q31_t)(lcg_next() >> 1)));
        const q31_t m1 = (q31_t)lcg_next();
        const q31_t m2 = (q31_t)lcg_next();
        acc_q31(&a, mc_q31_mul(m1, m2));
        acc_q31(&a, mc_q31_from_f32(rand_f32(-1.5f, 1.5f)));
    }
    report("math_q31", &a);
}

int mc_bitexact_run(void)
{
    sweep_math_f32();
    sweep_math_q31();
    return 0;
}
