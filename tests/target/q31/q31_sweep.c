/* The q31 bit-exactness sweep (see q31_sweep.h). Inputs: a 32-bit LCG,
 * mixed with the range edges (MIN, MAX, 0, +-1) every few samples so the
 * saturating paths run too. Every output integer goes into the hash. */
#include "q31_sweep.h"

#include <stdint.h>

#include "q31_kernels_cfg.h"

typedef struct {
    uint32_t hash;
    uint32_t count;
} acc_t;

static uint32_t g_lcg;

static uint32_t lcg(void)
{
    g_lcg = (g_lcg * 1664525u) + 1013904223u;
    return g_lcg;
}

static int32_t i32_of(uint32_t u)
{
    if (u <= 0x7FFFFFFFu) {
        return (int32_t)u;
    }
    return -(int32_t)(~u) - 1;
}

/* A q31 input: mostly within +-2^-shift of full scale, sometimes an edge. */
static q31_t rnd_q(uint32_t k, uint32_t shift)
{
    static const q31_t edges[5] = {MC_Q31_MIN, MC_Q31_MAX, 0, 1, -1};
    const uint32_t r = lcg();
    if ((k % 37u) == 36u) {
        return edges[(r >> 8) % 5u];
    }
    return i32_of(r) >> shift;
}

static void acc_u32(acc_t *a, uint32_t v)
{
    for (int i = 0; i < 4; ++i) {
        a->hash ^= (v >> (8 * i)) & 0xFFu;
        a->hash *= 16777619u;
    }
    a->count++;
}

static void acc_i32(acc_t *a, int32_t v)
{
    acc_u32(a, (uint32_t)v);
}

static void acc_i64(acc_t *a, int64_t v)
{
    const uint64_t u = (uint64_t)v;
    acc_u32(a, (uint32_t)(u & 0xFFFFFFFFu));
    acc_u32(a, (uint32_t)(u >> 32));
}

static void acc_gain(acc_t *a, mc_q46_gain_t g)
{
    acc_i32(a, g.mant);
    acc_i32(a, g.shift);
}

static acc_t acc_new(uint32_t seed)
{
    acc_t a = {2166136261u, 0u};
    g_lcg = seed;
    return a;
}

static void hex8(char *out, uint32_t v)
{
    static const char d[] = "0123456789abcdef";
    for (int i = 7; i >= 0; --i) {
        out[i] = d[v & 0xFu];
        v >>= 4;
    }
    out[8] = '\0';
}

static void dec(char *out, uint32_t v)
{
    char t[11];
    int n = 0;
    do {
        t[n++] = (char)('0' + (char)(v % 10u));
        v /= 10u;
    } while (v != 0u);
    for (int i = 0; i < n; ++i) {
        out[i] = t[n - 1 - i];
    }
    out[n] = '\0';
}

static void report(const char *name, const acc_t *a)
{
    char num[12];
    char hex[9];
    dec(num, a->count);
    hex8(hex, a->hash);
    mc_q31_emit(name);
    mc_q31_emit(" ");
    mc_q31_emit(num);
    mc_q31_emit(" ");
    mc_q31_emit(hex);
    mc_q31_emit("\n");
}

#define N_STEPS 3000u

static int sweep_q46(void)
{
    acc_t a = acc_new(11u);
    for (uint32_t k = 0u; k < N_STEPS; ++k) {
        mc_q46_gain_t g;
        const float gf = (float)rnd_q(k, 4u) * 1.0e-6f; /* float from an integer */
        (void)mc_q46_gain_from_f32(gf, &g);
        acc_gain(&a, g);
        acc_i64(&a, mc_q46_mul_q31(g, rnd_q(k, 0u)));
        const q31_t x0 = rnd_q(k, 0u);
        const q31_t x1 = rnd_q(k, 8u);
        int64_t x = (int64_t)x0 * (int64_t)x1;
        acc_i64(&a, mc_q46_mul(g, x));
        acc_i64(&a, mc_q46_mul_q46(x, (int64_t)rnd_q(k, 0u) * ((int64_t)1 << 12)));
        int64_t u = x;
        int64_t v = (int64_t)rnd_q(k, 0u) * ((int64_t)1 << 20);
        (void)mc_q46_limit_vec(&u, &v, ((int64_t)1 << 40) + (int64_t)(lcg() & 0xFFFFFu));
        acc_i64(&a, u);
        acc_i64(&a, v);
    }
    report("q46", &a);
    return 0;
}

static int sweep_ddiff(void)
{
    mc_ddiff_q31_cfg_t c;
    mc_ddiff_q31_t s;
    acc_t a = acc_new(12u);
    mc_q31cfg_ddiff(&c);
    if (mc_ddiff_q31_init(&s, &c) != 0u) {
        return 1;
    }
    acc_gain(&a, s.c_q);
    acc_gain(&a, s.g);
    for (uint32_t k = 0u; k < N_STEPS; ++k) {
        q31_t th = 0;
        (void)mc_ddiff_q31_step(&s, rnd_q(k, 6u), &th);
        acc_i32(&a, th);
    }
    report("ddiff_q31", &a);
    return 0;
}

static int sweep_spdpll(void)
{
    mc_spdpll_q31_cfg_t c;
    mc_spdpll_q31_t s;
    acc_t a = acc_new(13u);
    uint32_t th = 0u;
    mc_q31cfg_spdpll(&c);
    if (mc_spdpll_q31_init(&s, &c) != 0u) {
        return 1;
    }
    for (uint32_t k = 0u; k < N_STEPS; ++k) {
        th += 3000000u + (lcg() >> 12);
        q31_t w = 0;
        (void)mc_spdpll_q31_step(&s, i32_of(th), &w);
        acc_i32(&a, w);
        acc_i32(&a, s.theta);
        acc_u32(&a, s.flags);
    }
    report("spdpll_q31", &a);
    return 0;
}

static int sweep_fluxobs(void)
{
    mc_fluxobs_q31_cfg_t c;
    mc_fluxobs_q31_t s;
    acc_t a = acc_new(14u);
    mc_q31cfg_fluxobs(&c);
    if (mc_fluxobs_q31_init(&s, &c) != 0u) {
        return 1;
    }
    {
        acc_t g = acc_new(0u);
        acc_gain(&g, s.g_v);
        acc_gain(&g, s.g_r);
        acc_gain(&g, s.g_l);
        acc_gain(&g, s.g_k);
        acc_i32(&g, s.flux_pu);
        acc_i32(&g, s.resid_tol);
        acc_u32(&g, s.resid_steps);
        report("fluxobs_q31_init", &g);
        g_lcg = 14u;
    }
    for (uint32_t k = 0u; k < N_STEPS; ++k) {
        /* inputs drawn in a fixed order (argument evaluation order is unspecified) */
        const q31_t va = rnd_q(k, 3u);
        const q31_t vb = rnd_q(k, 3u);
        const q31_t ia = rnd_q(k, 4u);
        const q31_t ib = rnd_q(k, 4u);
        acc_u32(&a, mc_fluxobs_q31_step(&s, va, vb, ia, ib));
        acc_i32(&a, s.theta);
        acc_i64(&a, s.x_alpha_q46);
        acc_i64(&a, s.x_beta_q46);
        acc_i32(&a, s.resid);
    }
    report("fluxobs_q31", &a);
    return 0;
}

static int sweep_foc(void)
{
    mc_foc_q31_cfg_t c;
    mc_foc_q31_t s;
    acc_t a = acc_new(15u);
    mc_q31cfg_foc(&c);
    if (mc_foc_q31_init(&s, &c) != 0u) {
        return 1;
    }
    {
        acc_t g = acc_new(0u);
        acc_gain(&g, s.g_ff_d);
        acc_gain(&g, s.g_ff_q);
        acc_gain(&g, s.g_ff_psi);
        acc_gain(&g, s.g_vmax);
        acc_i32(&g, s.pi_d.kp_mant);
        acc_i32(&g, s.pi_d.kp_shift);
        acc_i32(&g, s.pi_d.ki_dt_mant);
        acc_i32(&g, s.pi_d.ki_shift);
        acc_i32(&g, s.pi_d.out_max);
        report("foc_q31_init", &g);
        g_lcg = 15u;
    }
    for (uint32_t k = 0u; k < N_STEPS; ++k) {
        mc_foc_q31_in_t in;
        mc_foc_q31_out_t out;
        q31_t vd;
        q31_t vq;
        in.ia = rnd_q(k, 2u);
        in.ib = rnd_q(k, 2u);
        in.ic = rnd_q(k, 2u);
        in.three_phase = (k & 1u) != 0u;
        in.theta_e = i32_of(lcg());
        in.omega_e = rnd_q(k, 1u);
        in.vbus = (q31_t)((lcg() >> 2) | 0x10000000u);
        in.id_ref = rnd_q(k, 4u);
        in.iq_ref = rnd_q(k, 2u);
        acc_u32(&a, mc_foc_q31_step(&s, &in, &out));
        acc_i32(&a, out.duty_a);
        acc_i32(&a, out.duty_b);
        acc_i32(&a, out.duty_c);
        acc_i32(&a, out.vd);
        acc_i32(&a, out.vq);
        {
            q31_t x[6];
            for (uint32_t j = 0u; j < 6u; ++j) {
                x[j] = rnd_q(k, (j < 4u) ? 3u : 1u);
            }
            acc_u32(&a, mc_foc_q31_step_dq(&s, x[0], x[1], x[2], x[3], x[4], x[5], &vd, &vq));
        }
        acc_i32(&a, vd);
        acc_i32(&a, vq);
    }
    report("foc_q31", &a);
    return 0;
}

static int sweep_pi2d(void)
{
    mc_pi2d_q31_cfg_t c;
    mc_pi2d_q31_t s;
    acc_t a = acc_new(16u);
    mc_q31cfg_pi2d(&c);
    if (mc_pi2d_q31_init(&s, &c) != 0u) {
        return 1;
    }
    for (uint32_t k = 0u; k < N_STEPS; ++k) {
        mc_pi2d_q31_in_t in;
        mc_pi2d_q31_out_t out;
        in.id = rnd_q(k, 4u);
        in.iq = rnd_q(k, 3u);
        in.theta_m = rnd_q(k, 8u);
        in.theta_ref = rnd_q(k, 8u);
        in.omega_ref = rnd_q(k, 2u);
        in.alpha_ref = rnd_q(k, 4u);
        in.jerk_ref = rnd_q(k, 6u);
        in.id_ref = rnd_q(k, 6u);
        in.did_ref = rnd_q(k, 6u);
        mc_pi2d_q31_step(&s, &in, &out);
        acc_i32(&a, out.vd);
        acc_i32(&a, out.vq);
        acc_i32(&a, out.iq_ref);
        acc_i32(&a, out.theta_f);
        acc_i32(&a, out.nu);
        acc_u32(&a, (out.iq_limited ? 1u : 0u) | (out.v_limited ? 2u : 0u));
    }
    report("pi2d_q31", &a);
    return 0;
}

static int sweep_csmc(void)
{
    mc_csmc_q31_cfg_t c;
    mc_csmc_q31_t s;
    mc_hgo_q31_cfg_t hc;
    mc_hgo_q31_t h;
    acc_t a = acc_new(17u);
    mc_q31cfg_csmc(&c);
    mc_q31cfg_hgo(&hc);
    if ((mc_csmc_q31_init(&s, &c) != 0u) || (mc_hgo_q31_init(&h, &hc) != 0u)) {
        return 1;
    }
    for (uint32_t i = 0u; i < 9u; ++i) {
        acc_gain(&a, h.phi[i]);
    }
    for (uint32_t k = 0u; k < N_STEPS; ++k) {
        mc_csmc_q31_in_t in;
        mc_csmc_q31_out_t out;
        mc_hgo_q31_est_t e;
        mc_hgo_q31_step(&h, rnd_q(k, 10u), &e);
        in.e1 = rnd_q(k, 5u);
        in.e2 = rnd_q(k, 6u);
        in.de2 = e.z2;
        in.dde2 = e.z3;
        in.i_d = rnd_q(k, 3u);
        in.i_q = rnd_q(k, 3u);
        in.omega_m = rnd_q(k, 3u);
        in.di_dd = rnd_q(k, 8u);
        in.dddphi_d = rnd_q(k, 8u);
        mc_csmc_q31_step(&s, &in, &out);
        acc_i32(&a, e.z1);
        acc_i32(&a, e.z2);
        acc_i32(&a, e.z3);
        acc_i32(&a, out.v_d);
        acc_i32(&a, out.v_q);
        acc_i32(&a, out.s1);
        acc_i32(&a, out.s2);
    }
    report("csmc_hgo_q31", &a);
    return 0;
}

int mc_q31_sweep_run(void)
{
    int bad = 0;
    bad |= sweep_q46();
    bad |= sweep_ddiff();
    bad |= sweep_spdpll();
    bad |= sweep_fluxobs();
    bad |= sweep_foc();
    bad |= sweep_pi2d();
    bad |= sweep_csmc();
    if (bad != 0) {
        mc_q31_emit("q31 sweep: a kernel refused its configuration\n");
    }
    return bad;
}
