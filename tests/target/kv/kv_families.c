/* See kv.h. One function per kernel family: input record -> kernel calls ->
 * output record. Stateful kernels (PI, FOC) keep their state across the
 * records of a file, as in a control loop. */
#include "kv.h"

#include <stdbool.h>
#include <string.h>

#include "foc/mc_foc.h"
#include "math/mc_math.h"
#include "math/mc_q31.h"
#include "pi/mc_pi.h"
#include "transforms/mc_svpwm.h"
#include "transforms/mc_transforms.h"

#define KV_MAX_WORDS 32u

typedef struct {
    uint32_t w[KV_MAX_WORDS];
    uint32_t n;
} rec_t;

static float in_f32(const rec_t *r, uint32_t k)
{
    float v;
    memcpy(&v, &r->w[k], sizeof v);
    return v;
}

static q31_t in_q31(const rec_t *r, uint32_t k)
{
    q31_t v;
    memcpy(&v, &r->w[k], sizeof v);
    return v;
}

static void out_u32(rec_t *r, uint32_t v)
{
    r->w[r->n++] = v;
}

static void out_f32(rec_t *r, float v)
{
    uint32_t b;
    if (v != v) {
        b = 0x7FC00000u; /* canonical NaN: the sign/payload of a NaN is not promised */
    } else {
        memcpy(&b, &v, sizeof b);
    }
    out_u32(r, b);
}

static void out_q31(rec_t *r, q31_t v)
{
    uint32_t b;
    memcpy(&b, &v, sizeof b);
    out_u32(r, b);
}

/* ---- families ---------------------------------------------------------- */

/* in: x, y (f32). out: sin x, cos x, atan2(y, x), sqrt(|y|), wrap_pi(x),
 * wrap_2pi(x). */
static void fam_math_f32(const rec_t *in, rec_t *out)
{
    const float x = in_f32(in, 0);
    const float y = in_f32(in, 1);
    float s;
    float c;
    mc_sincos_f32(x, &s, &c);
    out_f32(out, s);
    out_f32(out, c);
    out_f32(out, mc_atan2_f32(y, x));
    out_f32(out, mc_sqrt_f32(mc_abs_f32(y)));
    out_f32(out, mc_wrap_pi_f32(x));
    out_f32(out, mc_wrap_2pi_f32(x));
}

/* in: a, b (q31), x (f32). out: sin a, cos a, atan2(a, b), sqrt(|a|),
 * a*b, a+b, a-b (saturating), angle a+b (wrapping), q31 from x. */
static void fam_math_q31(const rec_t *in, rec_t *out)
{
    const q31_t a = in_q31(in, 0);
    const q31_t b = in_q31(in, 1);
    q31_t s;
    q31_t c;
    mc_sincos_q31(a, &s, &c);
    out_q31(out, s);
    out_q31(out, c);
    out_q31(out, mc_atan2_q31(a, b));
    out_q31(out, mc_sqrt_q31(mc_q31_abs_sat(a)));
    out_q31(out, mc_q31_mul(a, b));
    out_q31(out, mc_q31_add_sat(a, b));
    out_q31(out, mc_q31_sub_sat(a, b));
    out_q31(out, mc_q31_angle_add(a, b));
    out_q31(out, mc_q31_from_f32(in_f32(in, 2)));
}

/* in: ia, ib, ic, theta (f32), qa, qb, qc, qtheta (q31). out: Clarke (2 and
 * 3 currents), Park, inverse Park, inverse Clarke, f32 then q31. */
static void fam_transforms(const rec_t *in, rec_t *out)
{
    float al;
    float be;
    float al3;
    float be3;
    float d;
    float q;
    float s;
    float c;
    float al2;
    float be2;
    float pa;
    float pb;
    float pc;
    mc_clarke_f32(in_f32(in, 0), in_f32(in, 1), &al, &be);
    mc_clarke3_f32(in_f32(in, 0), in_f32(in, 1), in_f32(in, 2), &al3, &be3);
    mc_sincos_f32(in_f32(in, 3), &s, &c);
    mc_park_f32(al, be, s, c, &d, &q);
    mc_inv_park_f32(d, q, s, c, &al2, &be2);
    mc_inv_clarke_f32(al2, be2, &pa, &pb, &pc);
    out_f32(out, al);
    out_f32(out, be);
    out_f32(out, al3);
    out_f32(out, be3);
    out_f32(out, d);
    out_f32(out, q);
    out_f32(out, al2);
    out_f32(out, be2);
    out_f32(out, pa);
    out_f32(out, pb);
    out_f32(out, pc);

    q31_t qal;
    q31_t qbe;
    q31_t qal3;
    q31_t qbe3;
    q31_t qd;
    q31_t qq;
    q31_t qs;
    q31_t qc;
    q31_t qal2;
    q31_t qbe2;
    q31_t qpa;
    q31_t qpb;
    q31_t qpc;
    mc_clarke_q31(in_q31(in, 4), in_q31(in, 5), &qal, &qbe);
    mc_clarke3_q31(in_q31(in, 4), in_q31(in, 5), in_q31(in, 6), &qal3, &qbe3);
    mc_sincos_q31(in_q31(in, 7), &qs, &qc);
    mc_park_q31(qal, qbe, qs, qc, &qd, &qq);
    mc_inv_park_q31(qd, qq, qs, qc, &qal2, &qbe2);
    mc_inv_clarke_q31(qal2, qbe2, &qpa, &qpb, &qpc);
    out_q31(out, qal);
    out_q31(out, qbe);
    out_q31(out, qal3);
    out_q31(out, qbe3);
    out_q31(out, qd);
    out_q31(out, qq);
    out_q31(out, qal2);
    out_q31(out, qbe2);
    out_q31(out, qpa);
    out_q31(out, qpb);
    out_q31(out, qpc);
}

/* in: va, vb, vbus (f32), qva, qvb, qvbus (q31). out: SVPWM with the circle
 * and the hexagon limit (flags, 3 duties each), the limiter alone (flags,
 * va, vb), the largest voltage per limit; q31 SVPWM with both limits. */
static void fam_svpwm(const rec_t *in, rec_t *out)
{
    const float va = in_f32(in, 0);
    const float vb = in_f32(in, 1);
    const float vbus = in_f32(in, 2);
    for (int lim = 0; lim < 2; ++lim) {
        const mc_svpwm_limit_t l = (lim == 0) ? MC_SVPWM_LIMIT_CIRCLE : MC_SVPWM_LIMIT_HEXAGON;
        float da;
        float db;
        float dc;
        out_u32(out, mc_svpwm_f32(va, vb, vbus, l, &da, &db, &dc));
        out_f32(out, da);
        out_f32(out, db);
        out_f32(out, dc);
    }
    float la = va;
    float lb = vb;
    out_u32(out, mc_svpwm_limit_f32(&la, &lb, vbus, MC_SVPWM_LIMIT_HEXAGON));
    out_f32(out, la);
    out_f32(out, lb);
    out_f32(out, mc_svpwm_max_voltage_f32(vbus, MC_SVPWM_LIMIT_CIRCLE));
    out_f32(out, mc_svpwm_max_voltage_f32(vbus, MC_SVPWM_LIMIT_HEXAGON));
    for (int lim = 0; lim < 2; ++lim) {
        const mc_svpwm_limit_t l = (lim == 0) ? MC_SVPWM_LIMIT_CIRCLE : MC_SVPWM_LIMIT_HEXAGON;
        q31_t da;
        q31_t db;
        q31_t dc;
        out_u32(out, mc_svpwm_q31(in_q31(in, 3), in_q31(in, 4), in_q31(in, 5), l, &da, &db, &dc));
        out_q31(out, da);
        out_q31(out, db);
        out_q31(out, dc);
    }
}

typedef struct {
    mc_pi_f32_t clamp;
    mc_pi_f32_t back_calc;
    mc_pi_q31_t q;
    mc_foc_f32_t foc;
} kv_state_t;

/* in: e, ff, lo, hi (f32), qe, qff (q31). out: f32 PI with clamping and with
 * back-calculation (step with dynamic limits), q31 PI (step with
 * feed-forward), and the f32 integrators. */
static void fam_pi(kv_state_t *st, const rec_t *in, rec_t *out)
{
    const float e = in_f32(in, 0);
    const float ff = in_f32(in, 1);
    const float lo = in_f32(in, 2);
    const float hi = in_f32(in, 3);
    out_f32(out, mc_pi_f32_step_lim(&st->clamp, e, ff, lo, hi));
    out_f32(out, mc_pi_f32_step_lim(&st->back_calc, e, ff, lo, hi));
    out_q31(out, mc_pi_q31_step_ff(&st->q, in_q31(in, 4), in_q31(in, 5)));
    out_f32(out, st->clamp.integ);
    out_f32(out, st->back_calc.integ);
    out_u32(out, st->clamp.flags | (st->back_calc.flags << 16));
}

/* in: mc_foc_f32_in_t (ia, ib, ic, three_phase, theta_e, omega_e, vbus,
 * id_ref, iq_ref). out: return bits and mc_foc_f32_out_t. */
static void fam_foc(kv_state_t *st, const rec_t *in, rec_t *out)
{
    mc_foc_f32_in_t fi;
    fi.ia_a = in_f32(in, 0);
    fi.ib_a = in_f32(in, 1);
    fi.ic_a = in_f32(in, 2);
    fi.three_phase = in->w[3] != 0u;
    fi.theta_e_rad = in_f32(in, 4);
    fi.omega_e_rad_s = in_f32(in, 5);
    fi.vbus_v = in_f32(in, 6);
    fi.id_ref_a = in_f32(in, 7);
    fi.iq_ref_a = in_f32(in, 8);
    mc_foc_f32_out_t fo;
    out_u32(out, mc_foc_f32_step(&st->foc, &fi, &fo));
    out_f32(out, fo.duty_a);
    out_f32(out, fo.duty_b);
    out_f32(out, fo.duty_c);
    out_f32(out, fo.id_a);
    out_f32(out, fo.iq_a);
    out_f32(out, fo.vd_v);
    out_f32(out, fo.vq_v);
    out_f32(out, fo.v_alpha_v);
    out_f32(out, fo.v_beta_v);
    out_u32(out, fo.svpwm_flags);
    out_u32(out, fo.flags);
}

/* ---- configurations ---------------------------------------------------- */

static int setup(kv_state_t *st)
{
    const mc_pi_f32_cfg_t pc = {.kp = 2.5f, .ki_per_s = 400.0f, .dt_s = 5.0e-5f,
                                .out_min = -12.0f, .out_max = 12.0f,
                                .aw = MC_PI_AW_CLAMP, .kaw_per_s = 0.0f};
    mc_pi_f32_cfg_t pb = pc;
    pb.aw = MC_PI_AW_BACK_CALC;
    pb.kaw_per_s = 2000.0f;
    mc_pi_q31_cfg_t qc;
    if (mc_pi_f32_init(&st->clamp, &pc) != 0u || mc_pi_f32_init(&st->back_calc, &pb) != 0u ||
        mc_pi_q31_cfg_from_f32(&pc, 10.0f, 24.0f, &qc) != 0u ||
        mc_pi_q31_init(&st->q, &qc) != 0u) {
        return 2;
    }
    /* FocSil's current loop (paper-002 test motor, 20 kHz, 200 Hz
     * bandwidth), the set-up the FOC vectors were recorded in. */
    float kp = 0.0f;
    float ki = 0.0f;
    if (mc_foc_f32_gains_from_bandwidth(0.675f, 1.14e-3f, 2.0f * MC_PI_F32 * 200.0f, &kp, &ki) !=
        0u) {
        return 2;
    }
    const mc_foc_f32_cfg_t fc = {
        .r_ohm = 0.675f, .ld_h = 1.14e-3f, .lq_h = 1.14e-3f, .flux_wb = 0.11f,
        .kp_d_v_per_a = kp, .ki_d_v_per_as = ki, .kp_q_v_per_a = kp, .ki_q_v_per_as = ki,
        .dt_s = 5.0e-5f, .aw = MC_PI_AW_CLAMP, .kaw_per_s = 0.0f,
        .limit_mode = MC_SVPWM_LIMIT_CIRCLE, .v_limit_ratio = 0.95f, .v_abs_max_v = 200.0f,
        .decouple = true};
    if (mc_foc_f32_init(&st->foc, &fc) != 0u) {
        return 2;
    }
    return 0;
}

/* ---- driver ------------------------------------------------------------ */

static const kv_family_t k_families[] = {
    {"math_f32", 2u, 6u},
    {"math_q31", 3u, 9u},
    {"transforms", 8u, 22u},
    {"svpwm", 6u, 21u},
    {"pi", 6u, 6u},
    {"foc", 9u, 12u},
    {NULL, 0u, 0u},
};

const kv_family_t *kv_families(void)
{
    return k_families;
}

const kv_family_t *kv_find(const char *name)
{
    for (const kv_family_t *f = k_families; f->name != NULL; ++f) {
        if (strcmp(f->name, name) == 0) {
            return f;
        }
    }
    return NULL;
}

static void run_one(const char *name, kv_state_t *st, const rec_t *in, rec_t *out)
{
    if (strcmp(name, "math_f32") == 0) {
        fam_math_f32(in, out);
    } else if (strcmp(name, "math_q31") == 0) {
        fam_math_q31(in, out);
    } else if (strcmp(name, "transforms") == 0) {
        fam_transforms(in, out);
    } else if (strcmp(name, "svpwm") == 0) {
        fam_svpwm(in, out);
    } else if (strcmp(name, "pi") == 0) {
        fam_pi(st, in, out);
    } else {
        fam_foc(st, in, out);
    }
}

int kv_run(const char *family, const kv_io_t *io)
{
    static kv_state_t st; /* large for a target stack; one run per process */
    const kv_family_t *f = kv_find(family);
    if (f == NULL) {
        return 1;
    }
    if (setup(&st) != 0) {
        return 2;
    }
    uint32_t records = 0u;
    for (;;) {
        rec_t in;
        rec_t out;
        in.n = f->in_words;
        out.n = 0u;
        const size_t want = 4u * (size_t)f->in_words;
        const size_t got = io->read(io->ctx, in.w, want);
        if (got == 0u) {
            break;
        }
        if (got != want) {
            return 3;
        }
        run_one(f->name, &st, &in, &out);
        if (out.n != f->out_words || io->write(io->ctx, out.w, 4u * (size_t)out.n) != 0) {
            return 4;
        }
        ++records;
    }
    return (records == 0u) ? 5 : 0;
}
