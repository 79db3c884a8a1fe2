/* See bitexact.h. Inputs come from an integer LCG so they are identical on
 * both machines; outputs are hashed by their bit patterns. NaNs are folded to
 * one canonical pattern before hashing, because x86 and ARM generate
 * different default-NaN bit patterns and the kernels only promise "NaN". */
#include "bitexact.h"

#include <stdint.h>
#include <string.h>

#include "foc/mc_foc.h"
#include "math/mc_math.h"
#include "math/mc_q31.h"
#include "pi/mc_pi.h"
#include "pi/mc_pi_q31.h"
#include "transforms/mc_svpwm.h"
#include "transforms/mc_svpwm_q31.h"
#include "transforms/mc_transforms.h"

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
    static const float edges[] = {0.0f,   -0.0f,   MC_PI_F32, -MC_PI_F32,
                                  1.0e6f, -3.0e9f, 1.0e30f,   1.0e-40f};
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

static q31_t rand_q31(void)
{
    return (q31_t)lcg_next();
}

static void sweep_transforms(void)
{
    bx_acc_t a = acc_new(5u);
    for (int i = 0; i < N_SWEEP; ++i) {
        const float ia = rand_f32(-50.0f, 50.0f);
        const float ib = rand_f32(-50.0f, 50.0f);
        const float ic = rand_f32(-50.0f, 50.0f);
        const float th = rand_f32(-4.0f, 4.0f);
        float al, be, d, q, s, c, al2, be2, pa, pb, pc;
        mc_sincos_f32(th, &s, &c);
        mc_clarke_f32(ia, ib, &al, &be);
        mc_park_f32(al, be, s, c, &d, &q);
        mc_inv_park_f32(d, q, s, c, &al2, &be2);
        mc_inv_clarke_f32(al2, be2, &pa, &pb, &pc);
        acc_f32(&a, d);
        acc_f32(&a, q);
        acc_f32(&a, pa);
        acc_f32(&a, pc);
        mc_clarke3_f32(ia, ib, ic, &al, &be);
        acc_f32(&a, al);
        acc_f32(&a, be);
    }
    report("transforms_f32", &a);

    a = acc_new(6u);
    for (int i = 0; i < N_SWEEP; ++i) {
        const q31_t ia = rand_q31();
        const q31_t ib = rand_q31();
        const q31_t ic = rand_q31();
        q31_t s, c, al, be, d, q, pa, pb, pc;
        mc_sincos_q31(rand_q31(), &s, &c);
        mc_clarke_q31(ia, ib, &al, &be);
        mc_park_q31(al, be, s, c, &d, &q);
        mc_inv_park_q31(d, q, s, c, &al, &be);
        mc_inv_clarke_q31(al, be, &pa, &pb, &pc);
        acc_q31(&a, d);
        acc_q31(&a, q);
        acc_q31(&a, pa);
        acc_q31(&a, pb);
        acc_q31(&a, pc);
        mc_clarke3_q31(ia, ib, ic, &al, &be);
        acc_q31(&a, al);
        acc_q31(&a, be);
    }
    report("transforms_q31", &a);
}

static void sweep_svpwm(void)
{
    bx_acc_t a = acc_new(7u);
    for (int i = 0; i < N_SWEEP; ++i) {
        const float va = rand_f32(-300.0f, 300.0f);
        const float vb = rand_f32(-300.0f, 300.0f);
        const float vbus = rand_f32(10.0f, 400.0f);
        const mc_svpwm_limit_t lim = (i & 1) ? MC_SVPWM_LIMIT_HEXAGON : MC_SVPWM_LIMIT_CIRCLE;
        float da, db, dc;
        acc_u32(&a, mc_svpwm_f32(va, vb, vbus, lim, &da, &db, &dc));
        acc_f32(&a, da);
        acc_f32(&a, db);
        acc_f32(&a, dc);
    }
    report("svpwm_f32", &a);

    a = acc_new(8u);
    for (int i = 0; i < N_SWEEP; ++i) {
        const q31_t va = rand_q31();
        const q31_t vb = rand_q31();
        const q31_t vbus = (q31_t)(lcg_next() >> 1);
        const mc_svpwm_limit_t lim = (i & 1) ? MC_SVPWM_LIMIT_HEXAGON : MC_SVPWM_LIMIT_CIRCLE;
        q31_t da, db, dc;
        acc_u32(&a, mc_svpwm_q31(va, vb, vbus, lim, &da, &db, &dc));
        acc_q31(&a, da);
        acc_q31(&a, db);
        acc_q31(&a, dc);
    }
    report("svpwm_q31", &a);
}

static int sweep_pi(void)
{
    const mc_pi_f32_cfg_t cfg = {.kp = 2.5f,
                                 .ki_per_s = 400.0f,
                                 .dt_s = 5.0e-5f,
                                 .out_min = -12.0f,
                                 .out_max = 12.0f,
                                 .aw = MC_PI_AW_BACK_CALC,
                                 .kaw_per_s = 2000.0f};
    mc_pi_f32_t pi;
    bx_acc_t a = acc_new(9u);
    if (mc_pi_f32_init(&pi, &cfg) != 0u) {
        mc_bx_emit("pi_f32 init failed\n");
        return 1;
    }
    for (int i = 0; i < N_SWEEP; ++i) {
        const float e = rand_f32(-8.0f, 8.0f);
        const float ff = rand_f32(-2.0f, 2.0f);
        float u = 0.0f;
        (void)mc_pi_f32_step_lim(&pi, e, ff, -10.0f, 11.0f, &u);
        acc_f32(&a, u);
    }
    report("pi_f32", &a);

    mc_pi_q31_cfg_t qcfg;
    mc_pi_q31_t qpi;
    a = acc_new(10u);
    if (mc_pi_q31_cfg_from_f32(&cfg, 10.0f, 24.0f, &qcfg) != 0u ||
        mc_pi_q31_init(&qpi, &qcfg) != 0u) {
        mc_bx_emit("pi_q31 init failed\n");
        return 1;
    }
    for (int i = 0; i < N_SWEEP; ++i) {
        const q31_t e = rand_q31();
        q31_t u = 0;
        (void)mc_pi_q31_step(&qpi, e, &u);
        acc_q31(&a, u);
    }
    report("pi_q31", &a);
    return 0;
}

static int sweep_foc(void)
{
    mc_foc_f32_cfg_t cfg = {.r_ohm = 0.675f,
                            .ld_h = 1.14e-3f,
                            .lq_h = 1.3e-3f,
                            .flux_wb = 0.11f,
                            .kp_d_v_per_a = 1.43f,
                            .ki_d_v_per_as = 848.0f,
                            .kp_q_v_per_a = 1.6f,
                            .ki_q_v_per_as = 848.0f,
                            .dt_s = 5.0e-5f,
                            .aw = MC_PI_AW_CLAMP,
                            .kaw_per_s = 0.0f,
                            .limit_mode = MC_SVPWM_LIMIT_HEXAGON,
                            .v_limit_ratio = 0.95f,
                            .v_abs_max_v = 200.0f,
                            .decouple = true};
    mc_foc_f32_t foc;
    bx_acc_t a = acc_new(11u);
    if (mc_foc_f32_init(&foc, &cfg) != 0u) {
        mc_bx_emit("foc init failed\n");
        return 1;
    }
    for (int i = 0; i < N_SWEEP; ++i) {
        mc_foc_f32_in_t in;
        in.ia_a = rand_f32(-10.0f, 10.0f);
        in.ib_a = rand_f32(-10.0f, 10.0f);
        in.ic_a = 0.0f;
        in.three_phase = false;
        in.theta_e_rad = rand_f32(0.0f, 6.3f);
        in.omega_e_rad_s = rand_f32(-800.0f, 800.0f);
        in.vbus_v = rand_f32(150.0f, 210.0f);
        in.id_ref_a = rand_f32(-5.0f, 0.0f);
        in.iq_ref_a = rand_f32(-10.0f, 10.0f);
        mc_foc_f32_out_t out;
        acc_u32(&a, mc_foc_f32_step(&foc, &in, &out));
        acc_f32(&a, out.duty_a);
        acc_f32(&a, out.duty_b);
        acc_f32(&a, out.duty_c);
        acc_f32(&a, out.vd_v);
        acc_f32(&a, out.vq_v);
    }
    report("foc_f32", &a);
    return 0;
}

int mc_bitexact_run(void)
{
    sweep_math_f32();
    sweep_math_q31();
    sweep_transforms();
    sweep_svpwm();
    /* A kernel that refuses its config fails the run (exit code), so the
     * comparison can never pass on two identical error messages. */
    int failures = 0;
    failures += sweep_pi();
    failures += sweep_foc();
    return failures;
}
