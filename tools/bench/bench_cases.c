/**
 * @file bench_cases.c
 * @brief Benchmark cases (see bench_cases.h): the f32 and q31 kernels, the
 *        sensored FOC step, and the drive's whole fast loop (mc_drive_fast_step
 *        in current mode on a HAL whose devices are RAM: ADC sample, encoder
 *        count, PWM registers), i.e. the fast loop without the few register
 *        accesses of a real board.
 *
 * Sensorless FOC fast step: Clarke, flux gradient observer (paper 002, with
 * its atan2 for the angle), speed PLL, and the FOC step from the same
 * alpha-beta currents at the estimated angle and speed (mc_foc_f32_step_ab:
 * sin/cos, Park, two PIs with decoupling and the voltage limit, inverse
 * Park, SVPWM).
 *
 * This is the kernel path of the sensorless plug-in's closed-loop phase
 * (firmware/app/mc_ctrl_sensorless.c: mc_fluxobs_f32_step, mc_spdpll_f32_step,
 * mc_foc_f32_step_ab), without its start-up logic and telemetry.
 *
 * PI2D step (pi2d_step): mc_pi2d_f32_step of the pi2d-motor law (paper 000
 * in physical units, 20 kHz) on inputs of its operating range where neither
 * limit acts: the dirty derivative, load adaptation, x2*, rho, v2, both
 * voltages and the voltage-limit test.
 *
 * CSMC with HGO and servocompensator (csmc_hgo_step): the output-feedback
 * loop of paper 001 Sec. V as the CSMC plug-in runs it: mc_csmc_hgo_f32_step
 * on the measured e1 and position error e2 (e2', e2'' from the high-gain
 * observer, advanced in the same step), the constant law (11) and the
 * servocompensators S1 (order 5, d axis) and S2 (order 3, q axis), 100 kHz.
 */
#include "bench_cases.h"

#include <errno.h>
#include <stdbool.h>
#include <stddef.h>
#include <string.h>

#include "csmc/mc_csmc.h"
#include "csmc/mc_csvc.h"
#include "observer/mc_hgo.h"
#include "foc/mc_foc.h"
#include "hal/hal.h"
#include "math/mc_math.h"
#include "math/mc_q31.h"
#include "mc_drive.h"
#include "mc_drive_hallobs.h"
#include "observer/mc_fluxobs.h"
#include "observer/mc_spdpll.h"
#include "pi/mc_pi.h"
#include "pi/mc_pi_q31.h"
#include "pi2d/mc_pi2d.h"
#include "transforms/mc_svpwm.h"
#include "transforms/mc_svpwm_q31.h"
#include "transforms/mc_transforms.h"

static volatile uint32_t g_sink_u32;
static volatile float g_sink_f32;

void bench_sink_u32(uint32_t v)
{
    g_sink_u32 = v;
}

static void sink_f32(float v)
{
    g_sink_f32 = v;
}

/* ---- inputs ------------------------------------------------------------ */

typedef struct {
    float x[BENCH_N];   /* angle-like, [-pi, pi) */
    float y[BENCH_N];   /* [-10, 10) */
    float z[BENCH_N];   /* [-10, 10) */
    float big[BENCH_N]; /* [0, 1000) */
    float va[BENCH_N];  /* [-150, 150) V */
    float vb[BENCH_N];
    q31_t qa[BENCH_N];
    q31_t qb[BENCH_N];
    q31_t qc[BENCH_N];
    mc_pi2d_f32_in_t pi2d_in[BENCH_N];
    float e2[BENCH_N]; /* CSMC position error [rad] */
    float e1[BENCH_N]; /* CSMC d-current error [A] */
} bench_inputs_t;

static bench_inputs_t g_in;
/* The FOC inputs in an array of their own, so that a case reaches a
 * sample's fields with one load each (inside the struct above they sat
 * beyond the 1 KB reach of VLDR, which cost an extra add per field). */
static mc_foc_f32_in_t g_foc_in[BENCH_N];
static uint32_t g_lcg = 12345u;

static uint32_t lcg(void)
{
    g_lcg = g_lcg * 1664525u + 1013904223u;
    return g_lcg;
}

static float uni(float lo, float hi)
{
    const float u = (float)(lcg() >> 8) * (1.0f / 16777216.0f);
    return lo + (hi - lo) * u;
}

/* ---- kernels under test, with their state ------------------------------ */

static mc_pi_f32_t g_pi;
static mc_pi_q31_t g_qpi;
static mc_foc_f32_t g_foc;
static mc_foc_f32_cfg_t g_foc_cfg;
static mc_foc_f32_t g_foc_sls;
static mc_fluxobs_f32_t g_obs;
/* Hall + observer with the hand-over on (mc_drive_hallobs.h): its step is
 * what the drive's fast step adds then; off, one pointer test. */
static mc_drive_hallobs_t g_hallobs;
static mc_spdpll_f32_t g_pll;
static mc_pi2d_f32_t g_pi2d;
static mc_pi2d_f32_out_t g_pi2d_out; /* the step's only output (last call's) */
static mc_hgo_f32_t g_hgo;
static mc_csmc_hgo_f32_t g_csmc_hgo;

/* ---- drive fast loop on a RAM HAL -------------------------------------- */

typedef struct {
    mc_hal_adc_sample_t adc;
    uint32_t enc_count;
    float duty[3];
    bool enabled;
} ram_board_t;

static ram_board_t g_rb;

static int rb_adc_read(void *ctx, mc_hal_adc_sample_t *s)
{
    ram_board_t *b = ctx;
    b->adc.seq++;
    *s = b->adc;
    return 0;
}
static int rb_pwm_set(void *ctx, float a, float b, float c)
{
    ram_board_t *r = ctx;
    if (!mc_hal_pwm3_duty_valid(a) || !mc_hal_pwm3_duty_valid(b) || !mc_hal_pwm3_duty_valid(c)) {
        return -EINVAL;
    }
    r->duty[0] = a;
    r->duty[1] = b;
    r->duty[2] = c;
    return 0;
}
static int rb_pwm_enable(void *ctx)
{
    ram_board_t *r = ctx;
    r->enabled = true;
    return 0;
}
static int rb_pwm_disable(void *ctx)
{
    ram_board_t *r = ctx;
    r->enabled = false;
    return 0;
}
static int rb_enc_read(void *ctx, mc_hal_encoder_sample_t *s)
{
    ram_board_t *r = ctx;
    r->enc_count = (r->enc_count + 7u) & 8191u; /* about 0.5 rev/s at 20 kHz x4 */
    s->count = r->enc_count;
    s->counts_per_rev = 8192u;
    s->flags = MC_HAL_ENCODER_FLAG_VALID | MC_HAL_ENCODER_FLAG_INDEX;
    s->timestamp_ticks = 0u;
    return 0;
}
static int rb_tick_read(void *ctx, uint32_t *t)
{
    (void)ctx;
    *t = 0u;
    return 0;
}

static const mc_hal_adc_ops_t k_rb_adc = {rb_adc_read, NULL};
static const mc_hal_pwm3_ops_t k_rb_pwm = {rb_pwm_set, rb_pwm_enable, rb_pwm_disable, NULL};
static const mc_hal_encoder_ops_t k_rb_enc = {rb_enc_read};
static const mc_hal_tick_ops_t k_rb_tick = {rb_tick_read, NULL};
static const mc_hal_adc_t g_rb_adc = {&k_rb_adc, &g_rb};
static const mc_hal_pwm3_t g_rb_pwm = {&k_rb_pwm, &g_rb};
static const mc_hal_encoder_t g_rb_enc = {&k_rb_enc, &g_rb};
static const mc_hal_tick_t g_rb_tick = {&k_rb_tick, &g_rb};
static const mc_hal_t g_rb_hal = {&g_rb_adc, &g_rb_pwm,  NULL, &g_rb_enc,
                                  NULL,      &g_rb_tick, NULL, NULL};
static mc_drive_t g_drive;

/* ---- wrappers ---------------------------------------------------------- */

#define NOINLINE __attribute__((noinline))

static NOINLINE void c_sincos_f32(uint32_t i)
{
    float s;
    float c;
    mc_sincos_f32(g_in.x[i], &s, &c);
    sink_f32(s + c);
}
static NOINLINE void c_atan2_f32(uint32_t i)
{
    sink_f32(mc_atan2_f32(g_in.y[i], g_in.z[i]));
}
static NOINLINE void c_sqrt_f32(uint32_t i)
{
    sink_f32(mc_sqrt_f32(g_in.big[i]));
}
static NOINLINE void c_wrap_pi_f32(uint32_t i)
{
    sink_f32(mc_wrap_pi_f32(g_in.big[i]));
}
static NOINLINE void c_clarke_f32(uint32_t i)
{
    float a;
    float b;
    mc_clarke_f32(g_in.y[i], g_in.z[i], &a, &b);
    sink_f32(a + b);
}
static NOINLINE void c_park_f32(uint32_t i)
{
    float d;
    float q;
    mc_park_f32(g_in.y[i], g_in.z[i], 0.6f, 0.8f, &d, &q);
    sink_f32(d + q);
}
static NOINLINE void c_inv_park_f32(uint32_t i)
{
    float a;
    float b;
    mc_inv_park_f32(g_in.y[i], g_in.z[i], 0.6f, 0.8f, &a, &b);
    sink_f32(a + b);
}
static NOINLINE void c_svpwm_circle_f32(uint32_t i)
{
    float a;
    float b;
    float c;
    bench_sink_u32(mc_svpwm_f32(g_in.va[i], g_in.vb[i], 200.0f, MC_SVPWM_LIMIT_CIRCLE, &a, &b, &c));
    sink_f32(a + b + c);
}
static NOINLINE void c_svpwm_hexagon_f32(uint32_t i)
{
    float a;
    float b;
    float c;
    bench_sink_u32(
        mc_svpwm_f32(g_in.va[i], g_in.vb[i], 200.0f, MC_SVPWM_LIMIT_HEXAGON, &a, &b, &c));
    sink_f32(a + b + c);
}
static NOINLINE void c_pi_f32(uint32_t i)
{
    float u;
    (void)mc_pi_f32_step_lim(&g_pi, g_in.y[i], 0.1f, -20.0f, 20.0f, &u);
    sink_f32(u);
}
static NOINLINE void c_foc_dq_f32(uint32_t i)
{
    float vd;
    float vq;
    bench_sink_u32(mc_foc_f32_step_dq(&g_foc, -0.5f, 2.0f, g_in.y[i] * 0.1f, g_in.z[i] * 0.2f,
                                      400.0f, 200.0f, &vd, &vq));
    sink_f32(vd + vq);
}
/* The FOC steps write their outputs to a static struct, as the drive keeps
 * them in its state (mc_drive.c: d->tm.foc); the step's return code is
 * sunk, the PWM write that reads the duties is not part of the step. */
static mc_foc_f32_out_t g_foc_out;
static mc_foc_f32_out_t g_sls_out;

static NOINLINE void c_foc_step_f32(uint32_t i)
{
    bench_sink_u32(mc_foc_f32_step(&g_foc, &g_foc_in[i], &g_foc_out));
}
static NOINLINE void c_foc_sensorless_f32(uint32_t i)
{
    const mc_foc_f32_in_t *f = &g_foc_in[i];
    float i_alpha;
    float i_beta;
    mc_clarke_f32(f->ia_a, f->ib_a, &i_alpha, &i_beta);
    /* the observer sees the voltage of the previous step, as in the plug-in */
    bench_sink_u32(
        mc_fluxobs_f32_step(&g_obs, g_sls_out.v_alpha_v, g_sls_out.v_beta_v, i_alpha, i_beta));
    float omega_hat;
    (void)mc_spdpll_f32_step(&g_pll, g_obs.theta_e_rad, &omega_hat);
    bench_sink_u32(mc_foc_f32_step_ab(&g_foc_sls, i_alpha, i_beta, g_obs.theta_e_rad, omega_hat,
                                      f->vbus_v, f->id_ref_a, f->iq_ref_a, &g_sls_out));
}
static NOINLINE void c_drive_fast_f32(uint32_t i)
{
    g_rb.adc.ia_a = g_in.y[i] * 0.2f;
    g_rb.adc.ib_a = g_in.z[i] * 0.2f;
    bench_sink_u32(mc_drive_fast_step(&g_drive) ? 1u : 0u);
}

/* The whole path of a step in which the observer carries weight: the
 * Hall angle at the observer's (no disagreement on these random inputs),
 * past the settle after its start, no fallback (three stores of the
 * harness in the count). */
static NOINLINE void c_drive_hallobs_f32(uint32_t i)
{
    g_hallobs.running = true;
    g_hallobs.settle_left = 0u;
    g_hallobs.fallback = false;
    const mc_drive_hallobs_in_t in = {
        g_in.y[i], g_in.z[i], g_in.va[i], g_in.vb[i], g_hallobs.obs.theta_e_rad, 2000.0f};
    sink_f32(mc_drive_hallobs_step(&g_hallobs, &in));
}

static NOINLINE void c_fluxobs_f32(uint32_t i)
{
    bench_sink_u32(mc_fluxobs_f32_step(&g_obs, g_in.va[i], g_in.vb[i], g_in.y[i], g_in.z[i]));
}
static NOINLINE void c_spdpll_f32(uint32_t i)
{
    float omega_hat;
    (void)mc_spdpll_f32_step(&g_pll, g_in.x[i], &omega_hat);
    sink_f32(omega_hat);
}
static NOINLINE void c_pi2d_f32(uint32_t i)
{
    bench_sink_u32(mc_pi2d_f32_step(&g_pi2d, &g_in.pi2d_in[i], &g_pi2d_out));
    sink_f32(g_pi2d_out.vd_v + g_pi2d_out.vq_v);
}
static NOINLINE void c_csmc_hgo_f32(uint32_t i)
{
    mc_csmc_f32_out_t out;
    bench_sink_u32(mc_csmc_hgo_f32_step(&g_csmc_hgo, g_in.e1[i], g_in.e2[i], NULL, &out));
    sink_f32(out.v_d_v + out.v_q_v);
}
static NOINLINE void c_hgo_f32(uint32_t i)
{
    mc_hgo_f32_est_t est;
    mc_hgo_f32_step(&g_hgo, g_in.e2[i], &est);
    sink_f32(est.z2 + est.z3);
}
static NOINLINE void c_sincos_q31(uint32_t i)
{
    q31_t s;
    q31_t c;
    mc_sincos_q31(g_in.qa[i], &s, &c);
    bench_sink_u32((uint32_t)s ^ (uint32_t)c);
}
static NOINLINE void c_atan2_q31(uint32_t i)
{
    bench_sink_u32((uint32_t)mc_atan2_q31(g_in.qa[i], g_in.qb[i]));
}
static NOINLINE void c_sqrt_q31(uint32_t i)
{
    bench_sink_u32((uint32_t)mc_sqrt_q31(g_in.qc[i]));
}
static NOINLINE void c_clarke_q31(uint32_t i)
{
    q31_t a;
    q31_t b;
    mc_clarke_q31(g_in.qa[i], g_in.qb[i], &a, &b);
    bench_sink_u32((uint32_t)a ^ (uint32_t)b);
}
static NOINLINE void c_park_q31(uint32_t i)
{
    q31_t d;
    q31_t q;
    mc_park_q31(g_in.qa[i], g_in.qb[i], 0x4CCCCCCD, 0x66666666, &d, &q);
    bench_sink_u32((uint32_t)d ^ (uint32_t)q);
}
static NOINLINE void c_inv_park_q31(uint32_t i)
{
    q31_t a;
    q31_t b;
    mc_inv_park_q31(g_in.qa[i], g_in.qb[i], 0x4CCCCCCD, 0x66666666, &a, &b);
    bench_sink_u32((uint32_t)a ^ (uint32_t)b);
}
static NOINLINE void c_svpwm_q31(uint32_t i)
{
    q31_t a;
    q31_t b;
    q31_t c;
    bench_sink_u32(mc_svpwm_q31(g_in.qa[i] >> 2, g_in.qb[i] >> 2, 0x40000000, MC_SVPWM_LIMIT_CIRCLE,
                                &a, &b, &c));
    bench_sink_u32((uint32_t)a ^ (uint32_t)b ^ (uint32_t)c);
}
static NOINLINE void c_pi_q31(uint32_t i)
{
    q31_t u;
    (void)mc_pi_q31_step(&g_qpi, g_in.qa[i] >> 4, &u);
    bench_sink_u32((uint32_t)u);
}

static const bench_case_t k_cases[] = {
    {"sincos", "f32", "kernel", c_sincos_f32, BENCH_N},
    {"atan2", "f32", "kernel", c_atan2_f32, BENCH_N},
    {"sqrt", "f32", "kernel", c_sqrt_f32, BENCH_N},
    {"wrap_pi", "f32", "kernel", c_wrap_pi_f32, BENCH_N},
    {"clarke", "f32", "kernel", c_clarke_f32, BENCH_N},
    {"park", "f32", "kernel", c_park_f32, BENCH_N},
    {"inv_park", "f32", "kernel", c_inv_park_f32, BENCH_N},
    {"svpwm_circle", "f32", "kernel", c_svpwm_circle_f32, BENCH_N},
    {"svpwm_hexagon", "f32", "kernel", c_svpwm_hexagon_f32, BENCH_N},
    {"pi_step_lim", "f32", "kernel", c_pi_f32, BENCH_N},
    {"foc_step_dq", "f32", "kernel", c_foc_dq_f32, BENCH_N},
    {"foc_step_sensored", "f32", "fast_loop", c_foc_step_f32, BENCH_N},
    {"drive_fast_step_sensored", "f32", "fast_loop", c_drive_fast_f32, BENCH_N},
    {"fluxobs_step", "f32", "kernel", c_fluxobs_f32, BENCH_N},
    {"spdpll_step", "f32", "kernel", c_spdpll_f32, BENCH_N},
    {"drive_hallobs_step", "f32", "fast_loop", c_drive_hallobs_f32, BENCH_N},
    {"foc_step_sensorless", "f32", "fast_loop", c_foc_sensorless_f32, BENCH_N},
    {"pi2d_step", "f32", "fast_loop", c_pi2d_f32, BENCH_N},
    {"hgo_step", "f32", "kernel", c_hgo_f32, BENCH_N},
    {"csmc_hgo_step", "f32", "fast_loop", c_csmc_hgo_f32, BENCH_N},
    {"sincos", "q31", "kernel", c_sincos_q31, BENCH_N},
    {"atan2", "q31", "kernel", c_atan2_q31, BENCH_N},
    {"sqrt", "q31", "kernel", c_sqrt_q31, BENCH_N},
    {"clarke", "q31", "kernel", c_clarke_q31, BENCH_N},
    {"park", "q31", "kernel", c_park_q31, BENCH_N},
    {"inv_park", "q31", "kernel", c_inv_park_q31, BENCH_N},
    {"svpwm_circle", "q31", "kernel", c_svpwm_q31, BENCH_N},
    {"pi_step", "q31", "kernel", c_pi_q31, BENCH_N},
    {NULL, NULL, NULL, NULL, 0u},
};

const bench_case_t *bench_cases(void)
{
    return k_cases;
}

int bench_check(void)
{
    /* The fast loop must have run the FOC every call, not a fault path; the
     * PI2D and CSMC cases must not have met a refused input or a limit. */
    if (g_drive.mode != MC_DRIVE_MODE_CURRENT || g_drive.faults != 0u) {
        return 1;
    }
    if (g_pi2d.flags != 0u || g_pi2d_out.iq_limited || g_pi2d_out.v_limited) {
        return 1;
    }
    return (g_csmc_hgo.law.flags != 0u || g_hgo.flags != 0u) ? 1 : 0;
}

/* ---- set-up ------------------------------------------------------------ */

static void draw_inputs(void)
{
    for (uint32_t i = 0u; i < BENCH_N; ++i) {
        g_in.x[i] = uni(-MC_PI_F32, MC_PI_F32);
        g_in.y[i] = uni(-10.0f, 10.0f);
        g_in.z[i] = uni(-10.0f, 10.0f);
        g_in.big[i] = uni(0.0f, 1000.0f);
        g_in.va[i] = uni(-150.0f, 150.0f);
        g_in.vb[i] = uni(-150.0f, 150.0f);
        g_in.qa[i] = (q31_t)lcg();
        g_in.qb[i] = (q31_t)lcg();
        g_in.qc[i] = (q31_t)(lcg() >> 1);
        mc_foc_f32_in_t *f = &g_foc_in[i];
        f->ia_a = uni(-3.0f, 3.0f);
        f->ib_a = uni(-3.0f, 3.0f);
        f->ic_a = 0.0f;
        f->three_phase = false;
        f->theta_e_rad = uni(0.0f, MC_TWO_PI_F32);
        f->omega_e_rad_s = uni(-1500.0f, 1500.0f);
        f->vbus_v = uni(190.0f, 210.0f);
        f->id_ref_a = 0.0f;
        f->iq_ref_a = uni(-3.0f, 3.0f);
    }
    /* Drawn after the others, so that their inputs stay those of the first
     * version of the benchmark (comparable counts). */
    for (uint32_t i = 0u; i < BENCH_N; ++i) {
        /* PI2D around a 100 rad/s operating point, small errors (no limit acts) */
        mc_pi2d_f32_in_t *p = &g_in.pi2d_in[i];
        p->id_a = uni(-0.1f, 0.1f);
        p->iq_a = uni(0.2f, 0.8f);
        p->theta_ref_rad = uni(-3.0f, 3.0f);
        p->theta_m_rad = p->theta_ref_rad + uni(-0.01f, 0.01f);
        p->omega_ref_rad_s = uni(90.0f, 110.0f);
        p->alpha_ref_rad_s2 = uni(-50.0f, 50.0f);
        p->jerk_ref_rad_s3 = uni(-100.0f, 100.0f);
        p->id_ref_a = 0.0f;
        p->did_ref_a_s = 0.0f;
        /* CSMC errors inside the boundary layers (the regulated regime) */
        g_in.e2[i] = uni(-1.0e-4f, 1.0e-4f);
        g_in.e1[i] = uni(-0.05f, 0.05f);
    }
}

/* The pi2d-motor law (see tests/target/kv/kv_families.c for the derivation
 * of the gains): triple pole at -30 rad/s, a = 2000/s, b = 1, 20 kHz. */
static int setup_pi2d(void)
{
    const float wn = 30.0f;
    const float ki = wn * wn * wn;
    const float kp = (3.0f * wn * wn) + (ki / 2000.0f);
    const mc_pi2d_f32_cfg_t c = {.r_ohm = 0.675f,
                                 .l_h = 1.14e-3f,
                                 .pole_pairs = 4u,
                                 .ke_v_s_rad = 0.44f,
                                 .kt_nm_a = 0.66f,
                                 .j_kgm2 = 1.0e-3f,
                                 .k1_per_s = 1256.6f,
                                 .k2_per_s = 1256.6f,
                                 .kp_per_s2 = kp,
                                 .kd_per_s2 = 3.0f * wn * 2000.0f,
                                 .ki_per_s3 = ki,
                                 .a_per_s = 2000.0f,
                                 .b = 1.0f,
                                 .eps_per_s = 2.0f * ki / kp,
                                 .dt_s = 5.0e-5f,
                                 .iq_max_a = 5.0f,
                                 .v_max_v = 200.0f,
                                 .nu_max_nm = 1.0f};
    return (mc_pi2d_f32_init(&g_pi2d, &c) == 0u) ? 0 : 1;
}

/* Paper 001, Sec. V: constant law (M = 50 V), servocompensators for
 * w0 = 2 pi rad/s, HGO alpha = (17, 80, 100), eps = 1e-4 s, 100 kHz. */
static int setup_csmc(void)
{
    mc_csmc_f32_cfg_t c;
    memset(&c, 0, sizeof c);
    c.law = MC_CSMC_LAW_CONST;
    c.sw = MC_CSMC_SW_SAT;
    c.k1_per_s2 = 7.5e4f;
    c.k2_per_s = 550.0f;
    c.mu1_a = 0.1f;
    c.mu2_rad_s2 = 50.0f;
    c.m1_v = 50.0f;
    c.m2_v = 50.0f;
    c.v_limit_v = 1.0e4f;
    c.dt_s = 1.0e-5f;
    const float w02 = (2.0f * MC_PI_F32) * (2.0f * MC_PI_F32);
    const float c1[5] = {0.0f, -4.0f * w02 * w02, 0.0f, -5.0f * w02, 0.0f};
    const float re1[5] = {-1.0f, -2.0f, -2.0f, -3.0f, -3.0f};
    const float im1[5] = {0.0f, 1.0f, -1.0f, 1.0f, -1.0f};
    const float c2[3] = {0.0f, -w02, 0.0f};
    const float re2[3] = {-1.0f, -2.0f, -2.0f};
    const float im2[3] = {0.0f, 1.0f, -1.0f};
    const mc_hgo_f32_cfg_t h = {.alpha1 = 17.0f,
                                .alpha2 = 80.0f,
                                .alpha3 = 100.0f,
                                .eps_s = 1.0e-4f,
                                .dt_s = 1.0e-5f,
                                .input_order = 2u};
    if (mc_csvc_f32_place(5u, c1, re1, im1, &c.sigma1) != 0u ||
        mc_csvc_f32_place(3u, c2, re2, im2, &c.sigma2) != 0u ||
        mc_csmc_hgo_f32_init(&g_csmc_hgo, &c, &h) != 0u || mc_hgo_f32_init(&g_hgo, &h) != 0u) {
        return 1;
    }
    /* The running loop: the observer's first two steps after init (which
     * have fewer past samples and take the general path, about 360
     * instructions) are not the per-step cost; run them here. */
    mc_csmc_f32_out_t o;
    for (uint32_t k = 0u; k < 2u; ++k) {
        if (mc_csmc_hgo_f32_step(&g_csmc_hgo, 0.0f, 0.0f, NULL, &o) != 0u) {
            return 1;
        }
    }
    return 0;
}

int bench_setup(void)
{
    draw_inputs();
    if (setup_pi2d() != 0 || setup_csmc() != 0) {
        return 1;
    }
    const mc_pi_f32_cfg_t pc = {.kp = 1.43f,
                                .ki_per_s = 848.0f,
                                .dt_s = 5.0e-5f,
                                .out_min = -100.0f,
                                .out_max = 100.0f,
                                .aw = MC_PI_AW_CLAMP,
                                .kaw_per_s = 0.0f};
    if (mc_pi_f32_init(&g_pi, &pc) != 0u) {
        return 1;
    }
    mc_pi_q31_cfg_t qc;
    if (mc_pi_q31_cfg_from_f32(&pc, 10.0f, 200.0f, &qc) != 0u ||
        mc_pi_q31_init(&g_qpi, &qc) != 0u) {
        return 1;
    }
    /* The paper-002 test motor at 20 kHz, 200 Hz current loop (FocSil). */
    g_foc_cfg = (mc_foc_f32_cfg_t){.r_ohm = 0.675f,
                                   .ld_h = 1.14e-3f,
                                   .lq_h = 1.14e-3f,
                                   .flux_wb = 0.11f,
                                   .kp_d_v_per_a = 1.4326f,
                                   .ki_d_v_per_as = 848.23f,
                                   .kp_q_v_per_a = 1.4326f,
                                   .ki_q_v_per_as = 848.23f,
                                   .dt_s = 5.0e-5f,
                                   .aw = MC_PI_AW_CLAMP,
                                   .kaw_per_s = 0.0f,
                                   .limit_mode = MC_SVPWM_LIMIT_CIRCLE,
                                   .v_limit_ratio = 0.95f,
                                   .v_abs_max_v = 200.0f,
                                   .decouple = true};
    if (mc_foc_f32_init(&g_foc, &g_foc_cfg) != 0u) {
        return 1;
    }
    if (mc_foc_f32_init(&g_foc_sls, &g_foc_cfg) != 0u) {
        return 1;
    }
    float gamma = 0.0f;
    if (mc_fluxobs_f32_gamma_for_critical_speed(50.0f, 4u, 0.11f, &gamma) != 0u) {
        return 1;
    }
    const mc_fluxobs_f32_cfg_t oc = {.r_ohm = 0.675f,
                                     .l_h = 1.14e-3f,
                                     .flux_wb = 0.11f,
                                     .gamma = gamma,
                                     .dt_s = 5.0e-5f,
                                     .resid_tol = 0.3f,
                                     .resid_time_s = 0.05f};
    const mc_spdpll_f32_cfg_t plc = {
        .bw_rad_s = 500.0f, .dt_s = 5.0e-5f, .omega_max_rad_s = 6000.0f};
    if (mc_fluxobs_f32_init(&g_obs, &oc) != 0u || mc_spdpll_f32_init(&g_pll, &plc) != 0u) {
        return 1;
    }
    {
        /* the observer above, the hand-over from 500 to 1000 rad/s el. */
        const mc_drive_hallobs_cfg_t hc = {.blend = {500.0f, 1000.0f, 0.785f},
                                           .r_ohm = oc.r_ohm,
                                           .l_h = oc.l_h,
                                           .flux_wb = oc.flux_wb,
                                           .gamma = oc.gamma,
                                           .resid_tol = oc.resid_tol,
                                           .resid_time_s = oc.resid_time_s,
                                           .pll_bw_rad_s = plc.bw_rad_s,
                                           .omega_max_e_rad_s = plc.omega_max_rad_s,
                                           .dt_s = oc.dt_s,
                                           .pwm_delay_periods = 1u};
        if (mc_drive_hallobs_init(&g_hallobs, &hc) != 0u) {
            return 1;
        }
    }
    mc_drive_cfg_t dc;
    memset(&dc, 0, sizeof dc);
    dc.foc = g_foc_cfg;
    dc.pole_pairs = 4u;
    dc.encoder_offset_rad = 0.0f;
    dc.speed_pll_bw_rad_s = 1000.0f;
    dc.slow_loop_div = 20u;
    dc.i_max_a = 10.0f;
    dc.i_trip_a = 15.0f;
    dc.vbus_min_v = 100.0f;
    dc.vbus_max_v = 300.0f;
    g_rb.adc.vbus_v = 200.0f;
    g_rb.adc.valid_mask = MC_HAL_ADC_VALID_IA | MC_HAL_ADC_VALID_IB | MC_HAL_ADC_VALID_VBUS;
    if (mc_drive_init(&g_drive, &dc, &g_rb_hal) != MC_DRIVE_CFG_OK ||
        mc_drive_set_mode(&g_drive, MC_DRIVE_MODE_CURRENT) != 0 ||
        mc_drive_set_current_ref(&g_drive, -0.5f, 2.0f) != 0) {
        return 1;
    }
    return 0;
}
