/**
 * @file bench_cases_q31.c
 * @brief Instruction-count cases of the q31 twin kernels (issue 10), and
 *        of their f32 twins on the same inputs, for the Cortex-M4F bench
 *        (bench_m4f.c) and the Cortex-M3 run (tests/target/q31).
 *
 * Each case is one kernel step (the state runs on, as in a loop) on inputs
 * drawn once at setup from the operating range of the SIL scenarios (the
 * configurations of tests/target/q31/q31_kernels_cfg.c), the same values in
 * both formats. Hook-in for bench_m4f.c: call bench_setup_q31() after
 * bench_setup() and run the cases of bench_cases_q31() after those of
 * bench_cases() (both tables end with fn == NULL).
 */
#include <stdint.h>

#include "bench_cases.h"
#include "math/mc_math.h"
#include "q31_kernels_cfg.h"

int bench_setup_q31(void);
const bench_case_t *bench_cases_q31(void);
const bench_case_t *bench_cases_q31_f32twins(void);

static volatile uint32_t g_q31_sink;

static void sink(uint32_t v)
{
    g_q31_sink = v;
}

/* ---- state ------------------------------------------------------------- */
static mc_ddiff_q31_t s_dd_q;
static mc_ddiff_f32_t s_dd_f;
static mc_spdpll_q31_t s_pll_q;
static mc_spdpll_f32_t s_pll_f;
static mc_fluxobs_q31_t s_obs_q;
static mc_fluxobs_f32_t s_obs_f;
static mc_foc_q31_t s_foc_q;
static mc_foc_f32_t s_foc_f;
static mc_pi2d_q31_t s_pi2d_q;
static mc_pi2d_f32_t s_pi2d_f;
static mc_csmc_q31_t s_csmc_q;
static mc_csmc_f32_t s_csmc_f;
static mc_hgo_q31_t s_hgo_q;
static mc_hgo_f32_t s_hgo_f;

/* ---- inputs (same values, both formats) -------------------------------- */
static q31_t in_y_q[BENCH_N]; /* ddiff input, rad (base 1) */
static float in_y_f[BENCH_N];
static q31_t in_th_q[BENCH_N]; /* PLL angle (turn) */
static float in_th_f[BENCH_N];
static q31_t in_v_q[BENCH_N][2]; /* observer voltages (400 V base) */
static float in_v_f[BENCH_N][2];
static q31_t in_i_q[BENCH_N][2]; /* currents (20 A base) */
static float in_i_f[BENCH_N][2];
static mc_foc_q31_in_t in_foc_q[BENCH_N];
static mc_foc_f32_in_t in_foc_f[BENCH_N];
static mc_pi2d_q31_in_t in_pi2d_q[BENCH_N];
static mc_pi2d_f32_in_t in_pi2d_f[BENCH_N];
static mc_csmc_q31_in_t in_csmc_q[BENCH_N];
static mc_csmc_f32_in_t in_csmc_f[BENCH_N];

static uint32_t g_lcg = 12345u;

/* uniform in [-1, 1) with 24 bits: exact in float, same in q31 */
static float rnd_unit(void)
{
    g_lcg = (g_lcg * 1664525u) + 1013904223u;
    return ((float)(int32_t)((g_lcg >> 8) & 0xFFFFFFu) - 8388608.0f) * 1.1920929e-7f;
}

static void pair(float v, float base, q31_t *p_q, float *p_f)
{
    *p_q = mc_q31_from_f32(v / base);
    *p_f = mc_q31_to_f32(*p_q) * base;
}

int bench_setup_q31(void)
{
    mc_ddiff_q31_cfg_t dd;
    mc_spdpll_q31_cfg_t pl;
    mc_fluxobs_q31_cfg_t ob;
    mc_foc_q31_cfg_t fc;
    mc_pi2d_q31_cfg_t pc;
    mc_csmc_q31_cfg_t cc;
    mc_hgo_q31_cfg_t hc;
    uint32_t err = 0u;

    mc_q31cfg_ddiff(&dd);
    mc_q31cfg_spdpll(&pl);
    mc_q31cfg_fluxobs(&ob);
    mc_q31cfg_foc(&fc);
    mc_q31cfg_pi2d(&pc);
    mc_q31cfg_csmc(&cc);
    mc_q31cfg_hgo(&hc);
    err |= mc_ddiff_q31_init(&s_dd_q, &dd) | mc_ddiff_f32_init(&s_dd_f, &dd.f);
    err |= mc_spdpll_q31_init(&s_pll_q, &pl) | mc_spdpll_f32_init(&s_pll_f, &pl.f);
    err |= mc_fluxobs_q31_init(&s_obs_q, &ob) | mc_fluxobs_f32_init(&s_obs_f, &ob.f);
    err |= mc_foc_q31_init(&s_foc_q, &fc) | mc_foc_f32_init(&s_foc_f, &fc.f);
    err |= mc_pi2d_q31_init(&s_pi2d_q, &pc) | mc_pi2d_f32_init(&s_pi2d_f, &pc.f);
    err |= mc_csmc_q31_init(&s_csmc_q, &cc) | mc_csmc_f32_init(&s_csmc_f, &cc.f);
    err |= mc_hgo_q31_init(&s_hgo_q, &hc) | mc_hgo_f32_init(&s_hgo_f, &hc.f);
    for (uint32_t i = 0u; i < BENCH_N; ++i) {
        const float t = (float)i * 1.25e-4f;
        pair(0.01f * rnd_unit(), 1.0f, &in_y_q[i], &in_y_f[i]);
        in_th_q[i] = mc_q31_angle_from_rad_f32(300.0f * t + 0.02f * rnd_unit());
        in_th_f[i] = mc_q31_angle_to_rad_f32(in_th_q[i]);
        for (uint32_t k = 0u; k < 2u; ++k) {
            pair(40.0f * rnd_unit(), 400.0f, &in_v_q[i][k], &in_v_f[i][k]);
            pair(5.0f * rnd_unit(), 20.0f, &in_i_q[i][k], &in_i_f[i][k]);
        }
        /* FOC: running at 600 rad/s electrical, 200 V bus, currents near
         * the references (unsaturated) */
        {
            mc_foc_q31_in_t *q = &in_foc_q[i];
            mc_foc_f32_in_t *f = &in_foc_f[i];
            float th = 0.0f;
            pair(5.0f * rnd_unit(), 50.0f, &q->ia, &f->ia_a);
            pair(5.0f * rnd_unit(), 50.0f, &q->ib, &f->ib_a);
            q->ic = 0;
            f->ic_a = 0.0f;
            q->three_phase = false;
            f->three_phase = false;
            q->theta_e = mc_q31_angle_from_rad_f32(3.0f * rnd_unit());
            th = mc_q31_angle_to_rad_f32(q->theta_e);
            f->theta_e_rad = th;
            pair(600.0f, 1000.0f, &q->omega_e, &f->omega_e_rad_s);
            pair(200.0f, 400.0f, &q->vbus, &f->vbus_v);
            pair(0.0f, 50.0f, &q->id_ref, &f->id_ref_a);
            pair(4.0f + rnd_unit(), 50.0f, &q->iq_ref, &f->iq_ref_a);
        }
        /* PI2D: paper Section V, tracking phase (limits do not act) */
        {
            const mc_pi2d_q31_bases_t *b = &pc.base;
            mc_pi2d_q31_in_t *q = &in_pi2d_q[i];
            mc_pi2d_f32_in_t *f = &in_pi2d_f[i];
            pair(0.05f * rnd_unit(), b->i_base_a, &q->id, &f->id_a);
            pair(2.0f + 0.05f * rnd_unit(), b->i_base_a, &q->iq, &f->iq_a);
            pair(0.3f + 1e-3f * rnd_unit(), b->theta_base_rad, &q->theta_m, &f->theta_m_rad);
            pair(0.3f, b->theta_base_rad, &q->theta_ref, &f->theta_ref_rad);
            pair(5.25f, b->omega_base_rad_s, &q->omega_ref, &f->omega_ref_rad_s);
            pair(0.0f, b->alpha_base_rad_s2, &q->alpha_ref, &f->alpha_ref_rad_s2);
            pair(0.0f, b->jerk_base_rad_s3, &q->jerk_ref, &f->jerk_ref_rad_s3);
            q->id_ref = 0;
            f->id_ref_a = 0.0f;
            q->did_ref = 0;
            f->did_ref_a_s = 0.0f;
        }
        /* CSMC: paper Fig. 2 state feedback near the set point */
        {
            const mc_csmc_q31_bases_t *b = &cc.base;
            mc_csmc_q31_in_t *q = &in_csmc_q[i];
            mc_csmc_f32_in_t *f = &in_csmc_f[i];
            pair(0.05f * rnd_unit(), b->i_base_a, &q->e1, &f->e1_a);
            pair(1e-3f * rnd_unit(), b->theta_base_rad, &q->e2, &f->e2_rad);
            pair(0.1f * rnd_unit(), b->omega_base_rad_s, &q->de2, &f->de2_rad_s);
            pair(50.0f * rnd_unit(), b->alpha_base_rad_s2, &q->dde2, &f->dde2_rad_s2);
            q->i_d = q->e1;
            f->i_d_a = f->e1_a;
            pair(1.5f + 0.1f * rnd_unit(), b->i_base_a, &q->i_q, &f->i_q_a);
            pair(0.1f * rnd_unit(), b->omega_base_rad_s, &q->omega_m, &f->omega_m_rad_s);
            q->di_dd = 0;
            f->di_dd_a_s = 0.0f;
            q->dddphi_d = 0;
            f->dddphi_d_rad_s3 = 0.0f;
        }
    }
    return (err == 0u) ? 0 : 1;
}

/* ---- q31 cases --------------------------------------------------------- */
static void c_ddiff_q(uint32_t i)
{
    q31_t th;
    (void)mc_ddiff_q31_step(&s_dd_q, in_y_q[i], &th);
    sink((uint32_t)th);
}
static void c_pll_q(uint32_t i)
{
    q31_t w;
    (void)mc_spdpll_q31_step(&s_pll_q, in_th_q[i], &w);
    sink((uint32_t)w);
}
static void c_obs_q(uint32_t i)
{
    sink(mc_fluxobs_q31_step(&s_obs_q, in_v_q[i][0], in_v_q[i][1], in_i_q[i][0], in_i_q[i][1]) +
         (uint32_t)s_obs_q.theta);
}
static void c_foc_dq_q(uint32_t i)
{
    const mc_foc_q31_in_t *in = &in_foc_q[i];
    q31_t vd;
    q31_t vq;
    (void)mc_foc_q31_step_dq(&s_foc_q, in->id_ref, in->iq_ref, in->ia, in->ib, in->omega_e,
                             in->vbus, &vd, &vq);
    sink((uint32_t)(vd ^ vq));
}
static void c_foc_q(uint32_t i)
{
    mc_foc_q31_out_t o;
    (void)mc_foc_q31_step(&s_foc_q, &in_foc_q[i], &o);
    sink((uint32_t)o.duty_a);
}
static void c_pi2d_q(uint32_t i)
{
    mc_pi2d_q31_out_t o;
    mc_pi2d_q31_step(&s_pi2d_q, &in_pi2d_q[i], &o);
    sink((uint32_t)o.vq);
}
static void c_csmc_q(uint32_t i)
{
    mc_csmc_q31_out_t o;
    mc_csmc_q31_step(&s_csmc_q, &in_csmc_q[i], &o);
    sink((uint32_t)o.v_q);
}
static void c_hgo_q(uint32_t i)
{
    mc_hgo_q31_est_t e;
    mc_hgo_q31_step(&s_hgo_q, in_csmc_q[i].e2 >> 2, &e);
    sink((uint32_t)e.z3);
}

/* ---- f32 twins on the same inputs -------------------------------------- */
static void c_ddiff_f(uint32_t i)
{
    float th;
    (void)mc_ddiff_f32_step(&s_dd_f, in_y_f[i], &th);
    sink((uint32_t)(int32_t)(th * 1e6f));
}
static void c_pll_f(uint32_t i)
{
    float w;
    (void)mc_spdpll_f32_step(&s_pll_f, in_th_f[i], &w);
    sink((uint32_t)(int32_t)w);
}
static void c_obs_f(uint32_t i)
{
    sink(mc_fluxobs_f32_step(&s_obs_f, in_v_f[i][0], in_v_f[i][1], in_i_f[i][0], in_i_f[i][1]) +
         (uint32_t)(int32_t)(s_obs_f.theta_e_rad * 1e6f));
}
static void c_foc_dq_f(uint32_t i)
{
    const mc_foc_f32_in_t *in = &in_foc_f[i];
    float vd;
    float vq;
    (void)mc_foc_f32_step_dq(&s_foc_f, in->id_ref_a, in->iq_ref_a, in->ia_a, in->ib_a,
                             in->omega_e_rad_s, in->vbus_v, &vd, &vq);
    sink((uint32_t)(int32_t)(vd + vq));
}
static void c_foc_f(uint32_t i)
{
    mc_foc_f32_out_t o;
    (void)mc_foc_f32_step(&s_foc_f, &in_foc_f[i], &o);
    sink((uint32_t)(int32_t)(o.duty_a * 1e6f));
}
static void c_pi2d_f(uint32_t i)
{
    mc_pi2d_f32_out_t o;
    (void)mc_pi2d_f32_step(&s_pi2d_f, &in_pi2d_f[i], &o);
    sink((uint32_t)(int32_t)o.vq_v);
}
static void c_csmc_f(uint32_t i)
{
    mc_csmc_f32_out_t o;
    mc_csmc_f32_step(&s_csmc_f, &in_csmc_f[i], &o);
    sink((uint32_t)(int32_t)o.v_q_v);
}
static void c_hgo_f(uint32_t i)
{
    mc_hgo_f32_est_t e;
    mc_hgo_f32_step(&s_hgo_f, 0.25f * in_csmc_f[i].e2_rad, &e);
    sink((uint32_t)(int32_t)e.z3);
}

static const bench_case_t k_q31[] = {
    {"ddiff_step", "q31", "kernel", c_ddiff_q, BENCH_N},
    {"spdpll_step", "q31", "kernel", c_pll_q, BENCH_N},
    {"fluxobs_step", "q31", "kernel", c_obs_q, BENCH_N},
    {"foc_step_dq", "q31", "kernel", c_foc_dq_q, BENCH_N},
    {"foc_step", "q31", "kernel", c_foc_q, BENCH_N},
    {"pi2d_step", "q31", "kernel", c_pi2d_q, BENCH_N},
    {"csmc_model_step", "q31", "kernel", c_csmc_q, BENCH_N},
    {"hgo_step", "q31", "kernel", c_hgo_q, BENCH_N},
    {0, 0, 0, 0, 0u},
};

static const bench_case_t k_f32[] = {
    {"ddiff_step", "f32", "kernel", c_ddiff_f, BENCH_N},
    {"spdpll_step", "f32", "kernel", c_pll_f, BENCH_N},
    {"fluxobs_step", "f32", "kernel", c_obs_f, BENCH_N},
    {"foc_step_dq", "f32", "kernel", c_foc_dq_f, BENCH_N},
    {"foc_step", "f32", "kernel", c_foc_f, BENCH_N},
    {"pi2d_step", "f32", "kernel", c_pi2d_f, BENCH_N},
    {"csmc_model_step", "f32", "kernel", c_csmc_f, BENCH_N},
    {"hgo_step", "f32", "kernel", c_hgo_f, BENCH_N},
    {0, 0, 0, 0, 0u},
};

const bench_case_t *bench_cases_q31(void)
{
    return k_q31;
}

const bench_case_t *bench_cases_q31_f32twins(void)
{
    return k_f32;
}
