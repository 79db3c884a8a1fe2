/* See kv.h. One function per kernel family: input record -> kernel calls ->
 * output record. Stateful kernels (PI, FOC, observers, filters, PI2D, CSMC)
 * keep their state across the records of a file, as in a control loop; a
 * "cmd" word in the record of the stateful families from issue 8's second
 * part asks for their reset functions first (so those are compared too). */
#include "kv.h"

#include <stdbool.h>
#include <string.h>

#include "csmc/mc_csmc.h"
#include "csmc/mc_csvc.h"
#include "observer/mc_hgo.h"
#include "filters/mc_ddiff.h"
#include "foc/mc_foc.h"
#include "math/mc_math.h"
#include "math/mc_q31.h"
#include "observer/mc_fluxobs.h"
#include "observer/mc_iiobs.h"
#include "observer/mc_spdpll.h"
#include "pi/mc_pi.h"
#include "pi/mc_pi_q31.h"
#include "pi2d/mc_pi2d.h"
#include "transforms/mc_svpwm.h"
#include "transforms/mc_svpwm_q31.h"
#include "transforms/mc_transforms.h"

#define KV_MAX_WORDS 48u

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
    mc_fluxobs_f32_t fluxobs;
    mc_spdpll_f32_t pll;
    mc_iiobs_f32_t iiobs;
    mc_ddiff_f32_t dd_paper;
    mc_ddiff_f32_t dd_motor;
    mc_pi2d_f32_t pi2d_paper;
    mc_pi2d_f32_t pi2d_motor;
    mc_pi2d_f32_cfg_t pi2d_motor_cfg;
    mc_hgo_f32_t hgo;
    mc_csmc_f32_t csmc_servo; /* LAW_CONST, sat, servocompensators, HGO inputs */
    mc_csmc_f32_t csmc_model; /* LAW_MODEL, sat, conditional integrators */
    mc_csmc_f32_t csmc_ideal; /* LAW_MODEL, sgn, no sigma (ideal SMC) */
    mc_csmc_f32_model_t csmc_plant;
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
    float u_clamp = 0.0f;
    float u_back_calc = 0.0f;
    q31_t u_q = 0;
    (void)mc_pi_f32_step_lim(&st->clamp, e, ff, lo, hi, &u_clamp);
    out_f32(out, u_clamp);
    (void)mc_pi_f32_step_lim(&st->back_calc, e, ff, lo, hi, &u_back_calc);
    out_f32(out, u_back_calc);
    (void)mc_pi_q31_step_ff(&st->q, in_q31(in, 4), in_q31(in, 5), &u_q);
    out_q31(out, u_q);
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

/* in: v_alpha, v_beta, i_alpha, i_beta, theta_m, tau (f32), cmd (u32),
 * theta_e_guess, omega_e_guess (f32). cmd != 0: reset the three observers
 * first (flux observer at theta_e_guess and the record's current, PLL at
 * (theta_e_guess, omega_e_guess), I&I at (theta_m, omega_e_guess / 4, tau)).
 * Then the flux observer steps on (v, i), the PLL on its angle, and the
 * I&I observer on (theta_m, tau). out: reset bits; flux observer (bits,
 * theta, x_alpha, x_beta, resid, flags); PLL (omega, theta, omega_i,
 * flags); I&I (bits, omega, tau_load, r, h_hat, xi, flags). */
static void fam_observer(kv_state_t *st, const rec_t *in, rec_t *out)
{
    const float va = in_f32(in, 0);
    const float vb = in_f32(in, 1);
    const float ia = in_f32(in, 2);
    const float ib = in_f32(in, 3);
    const float th_m = in_f32(in, 4);
    const float tau = in_f32(in, 5);
    uint32_t rst = 0u;
    if (in->w[6] != 0u) {
        const float th_g = in_f32(in, 7);
        const float om_g = in_f32(in, 8);
        rst |= mc_fluxobs_f32_reset(&st->fluxobs, th_g, ia, ib);
        rst |= mc_spdpll_f32_reset(&st->pll, th_g, om_g) << 8;
        rst |= mc_iiobs_f32_reset(&st->iiobs, th_m, om_g * 0.25f, tau) << 16;
    }
    out_u32(out, rst);
    out_u32(out, mc_fluxobs_f32_step(&st->fluxobs, va, vb, ia, ib));
    out_f32(out, st->fluxobs.theta_e_rad);
    out_f32(out, st->fluxobs.x_alpha_wb);
    out_f32(out, st->fluxobs.x_beta_wb);
    out_f32(out, st->fluxobs.resid);
    out_u32(out, st->fluxobs.flags);
    float omega_hat = 0.0f;
    (void)mc_spdpll_f32_step(&st->pll, st->fluxobs.theta_e_rad, &omega_hat);
    out_f32(out, omega_hat);
    out_f32(out, st->pll.theta_rad);
    out_f32(out, st->pll.omega_i_rad_s);
    out_u32(out, st->pll.flags);
    out_u32(out, mc_iiobs_f32_step(&st->iiobs, th_m, tau));
    out_f32(out, mc_iiobs_f32_get_omega_m_rad_s(&st->iiobs));
    out_f32(out, mc_iiobs_f32_get_tau_load_nm(&st->iiobs));
    out_f32(out, st->iiobs.r);
    out_f32(out, st->iiobs.hh1);
    out_f32(out, st->iiobs.hh2);
    out_f32(out, st->iiobs.xi1);
    out_f32(out, st->iiobs.xi2);
    out_u32(out, st->iiobs.flags);
}

/* in: y (f32), cmd (u32), q0 (f32). cmd != 0: both filters reset to q0
 * first. out: reset bits; per filter (paper's a = b = 50 at 10 kHz; a motor
 * speed filter, a = 2000/s, b = 1 at 20 kHz): theta_f, q, flags. */
static void fam_filters(kv_state_t *st, const rec_t *in, rec_t *out)
{
    const float y = in_f32(in, 0);
    uint32_t rst = 0u;
    if (in->w[1] != 0u) {
        rst |= mc_ddiff_f32_reset(&st->dd_paper, in_f32(in, 2));
        rst |= mc_ddiff_f32_reset(&st->dd_motor, in_f32(in, 2)) << 8;
    }
    out_u32(out, rst);
    float th = 0.0f;
    (void)mc_ddiff_f32_step(&st->dd_paper, y, &th);
    out_f32(out, th);
    out_f32(out, mc_ddiff_f32_get_q(&st->dd_paper));
    out_u32(out, st->dd_paper.flags);
    (void)mc_ddiff_f32_step(&st->dd_motor, y, &th);
    out_f32(out, th);
    out_f32(out, mc_ddiff_f32_get_q(&st->dd_motor));
    out_u32(out, st->dd_motor.flags);
}

static void out_pi2d(rec_t *out, uint32_t ret, const mc_pi2d_f32_t *c, const mc_pi2d_f32_out_t *o)
{
    out_u32(out, ret);
    out_f32(out, o->vd_v);
    out_f32(out, o->vq_v);
    out_f32(out, o->id_ref_a);
    out_f32(out, o->iq_ref_a);
    out_f32(out, o->e4_rad);
    out_f32(out, o->theta_f_rad);
    out_f32(out, o->nu_nm);
    out_f32(out, o->dnu_nm_s);
    out_f32(out, o->rho_a_s);
    out_f32(out, o->v2_a_s);
    out_u32(out, (o->iq_limited ? 1u : 0u) | (o->v_limited ? 2u : 0u));
    out_u32(out, c->flags);
}

/* in: mc_pi2d_f32_in_t (id, iq, theta_m, theta_ref, omega_ref, alpha_ref,
 * jerk_ref, id_ref, did_ref), cmd (u32), qc0, nu0 (f32). cmd != 0: both
 * laws reset to (qc0, nu0) first. out: reset bits; per law (the paper's
 * normalised gains at 10 kHz; a physical-units motor law at 20 kHz whose
 * iq and voltage limits act on part of the records): step bits and
 * mc_pi2d_f32_out_t; then the motor law's certificate over the envelope
 * |id| <= |id_a|, |iq| <= |iq_a| of the record (bits, margins of c34 and
 * c38, k2_min, max |Delta + sigma|, holds). */
static void fam_pi2d(kv_state_t *st, const rec_t *in, rec_t *out)
{
    mc_pi2d_f32_in_t pin;
    pin.id_a = in_f32(in, 0);
    pin.iq_a = in_f32(in, 1);
    pin.theta_m_rad = in_f32(in, 2);
    pin.theta_ref_rad = in_f32(in, 3);
    pin.omega_ref_rad_s = in_f32(in, 4);
    pin.alpha_ref_rad_s2 = in_f32(in, 5);
    pin.jerk_ref_rad_s3 = in_f32(in, 6);
    pin.id_ref_a = in_f32(in, 7);
    pin.did_ref_a_s = in_f32(in, 8);
    uint32_t rst = 0u;
    if (in->w[9] != 0u) {
        rst |= mc_pi2d_f32_reset(&st->pi2d_paper, in_f32(in, 10), in_f32(in, 11));
        rst |= mc_pi2d_f32_reset(&st->pi2d_motor, in_f32(in, 10), in_f32(in, 11)) << 16;
    }
    out_u32(out, rst);
    mc_pi2d_f32_out_t o;
    uint32_t ret = mc_pi2d_f32_step(&st->pi2d_paper, &pin, &o);
    out_pi2d(out, ret, &st->pi2d_paper, &o);
    ret = mc_pi2d_f32_step(&st->pi2d_motor, &pin, &o);
    out_pi2d(out, ret, &st->pi2d_motor, &o);

    const float aid = mc_abs_f32(pin.id_a);
    const mc_pi2d_envelope_t env = {
        .id_min_a = -aid, .id_max_a = aid, .iq_abs_max_a = mc_abs_f32(pin.iq_a)};
    mc_pi2d_cert_t cert;
    memset(&cert, 0, sizeof cert);
    out_u32(out, mc_pi2d_f32_certify(&st->pi2d_motor_cfg, &env, &cert));
    out_f32(out, cert.c34_margin);
    out_f32(out, cert.c38_margin);
    out_f32(out, cert.c38_k2_min_per_s);
    out_f32(out, cert.delta_sigma_max);
    out_u32(out, cert.holds ? 1u : 0u);
}

static void out_csmc(rec_t *out, const mc_csmc_f32_t *c, const mc_csmc_f32_out_t *o)
{
    out_f32(out, o->v_d_v);
    out_f32(out, o->v_q_v);
    out_f32(out, o->s1_a);
    out_f32(out, o->s2_rad_s2);
    out_u32(out, c->flags);
}

/* in: e1, e2, de2, dde2, i_d, i_q, omega_m, di_dd, dddphi_d (f32), cmd
 * (u32). cmd != 0: the three laws reset, the HGO reset to (e2, de2, dde2).
 * Then: the HGO on e2 feeding the constant law with the servocompensators
 * (paper 001, Sec. V: output feedback); the model law with conditional
 * integrators and the ideal SMC on the record's state errors; the error
 * vector from the state (theta = e2, I_dd = 0.1 A, phi_d = 0, phi_d' = 0,
 * phi_d'' = dde2). out: reset bits; HGO (z1, z2, z3, flags); per law
 * (u1, u2, s1, s2, flags); first servocompensator states; err_from_state
 * (bits, e1, e2, e2', e2''). */
static void fam_csmc(kv_state_t *st, const rec_t *in, rec_t *out)
{
    mc_csmc_f32_in_t cin;
    cin.e1_a = in_f32(in, 0);
    cin.e2_rad = in_f32(in, 1);
    cin.de2_rad_s = in_f32(in, 2);
    cin.dde2_rad_s2 = in_f32(in, 3);
    cin.i_d_a = in_f32(in, 4);
    cin.i_q_a = in_f32(in, 5);
    cin.omega_m_rad_s = in_f32(in, 6);
    cin.di_dd_a_s = in_f32(in, 7);
    cin.dddphi_d_rad_s3 = in_f32(in, 8);
    uint32_t rst = 0u;
    if (in->w[9] != 0u) {
        mc_csmc_f32_reset(&st->csmc_servo);
        mc_csmc_f32_reset(&st->csmc_model);
        mc_csmc_f32_reset(&st->csmc_ideal);
        rst = mc_hgo_f32_reset(&st->hgo, cin.e2_rad, cin.de2_rad_s, cin.dde2_rad_s2);
    }
    out_u32(out, rst);

    mc_hgo_f32_est_t est;
    mc_hgo_f32_step(&st->hgo, cin.e2_rad, &est);
    out_f32(out, est.z1);
    out_f32(out, est.z2);
    out_f32(out, est.z3);
    out_u32(out, st->hgo.flags);
    mc_csmc_f32_in_t hin = cin;
    hin.de2_rad_s = est.z2;
    hin.dde2_rad_s2 = est.z3;
    mc_csmc_f32_out_t o;
    mc_csmc_f32_step(&st->csmc_servo, &hin, &o);
    out_csmc(out, &st->csmc_servo, &o);
    mc_csmc_f32_step(&st->csmc_model, &cin, &o);
    out_csmc(out, &st->csmc_model, &o);
    mc_csmc_f32_step(&st->csmc_ideal, &cin, &o);
    out_csmc(out, &st->csmc_ideal, &o);
    float sg[MC_CSVC_MAX_ORDER];
    mc_csvc_f32_sigma(&st->csmc_servo.sigma1, sg);
    out_f32(out, sg[0]);
    out_f32(out, sg[4]);
    mc_csvc_f32_sigma(&st->csmc_servo.sigma2, sg);
    out_f32(out, sg[2]);
    mc_csvc_f32_sigma(&st->csmc_model.sigma2, sg);
    out_f32(out, sg[0]);

    mc_csmc_f32_in_t e;
    memset(&e, 0, sizeof e);
    out_u32(out,
            mc_csmc_f32_err_from_state(&st->csmc_plant, cin.i_d_a, cin.i_q_a, cin.omega_m_rad_s,
                                       cin.e2_rad, 0.1f, 0.0f, 0.0f, cin.dde2_rad_s2, &e));
    out_f32(out, e.e1_a);
    out_f32(out, e.e2_rad);
    out_f32(out, e.de2_rad_s);
    out_f32(out, e.dde2_rad_s2);
}

/* ---- configurations ---------------------------------------------------- */

/* The paper-002 test motor (R 0.675 ohm, L 1.14 mH, flux 0.11 Wb, 4 pole
 * pairs) at 20 kHz: flux observer with a 50 rad/s critical speed, PLL at
 * 500 rad/s, I&I observer with a1 = 6, a2 = 8.5 (k1 = 2.29) and a 100 rad/s
 * estimation pole (as the observer-compare scenario). */
static int setup_observer(kv_state_t *st)
{
    float gamma = 0.0f;
    if (mc_fluxobs_f32_gamma_for_critical_speed(50.0f, 4u, 0.11f, &gamma) != 0u) {
        return 2;
    }
    const mc_fluxobs_f32_cfg_t oc = {.r_ohm = 0.675f,
                                     .l_h = 1.14e-3f,
                                     .flux_wb = 0.11f,
                                     .gamma = gamma,
                                     .dt_s = 5.0e-5f,
                                     .resid_tol = 0.3f,
                                     .resid_time_s = 0.05f};
    const mc_spdpll_f32_cfg_t pc = {
        .bw_rad_s = 500.0f, .dt_s = 5.0e-5f, .omega_max_rad_s = 6000.0f};
    const mc_iiobs_f32_cfg_t ic = {.j_kgm2 = 2.5e-4f,
                                   .f_nms_rad = 1.0e-4f,
                                   .a1 = 6.0f,
                                   .a2 = 8.5f,
                                   .k4 = 1.0f,
                                   .t_unit_s = 2.2929f / 100.0f,
                                   .dt_s = 5.0e-5f,
                                   .r_max = 1000.0f};
    if (mc_fluxobs_f32_init(&st->fluxobs, &oc) != 0u || mc_spdpll_f32_init(&st->pll, &pc) != 0u ||
        mc_iiobs_f32_init(&st->iiobs, &ic) != 0u) {
        return 2;
    }
    return 0;
}

/* The paper-000 dirty derivative (a = b = 50, 10 kHz) and a motor speed
 * filter (a = 2000/s, b = 1, 20 kHz). */
static int setup_filters(kv_state_t *st)
{
    const mc_ddiff_f32_cfg_t p = {.a_per_s = 50.0f, .b = 50.0f, .dt_s = 1.0e-4f};
    const mc_ddiff_f32_cfg_t m = {.a_per_s = 2000.0f, .b = 1.0f, .dt_s = 5.0e-5f};
    if (mc_ddiff_f32_init(&st->dd_paper, &p) != 0u || mc_ddiff_f32_init(&st->dd_motor, &m) != 0u) {
        return 2;
    }
    return 0;
}

/* PI2D: the paper's normalised gains (k1 = 4, k2 = 75, kp = 5, kd = 10,
 * ki = 0.01, a = b = 50, eps = 0.02; no limits) at 10 kHz, and the
 * physical-units law of the pi2d-motor scenario (triple pole at -30 rad/s,
 * a = 2000/s, b = 1, 200 Hz current loops) at 20 kHz with limits that act:
 * iq <= 5 A, |u| <= 13.2 V (24 V bus), |nu| <= 1 N m. */
static int setup_pi2d(kv_state_t *st)
{
    const mc_pi2d_f32_cfg_t p = {.r_ohm = 1.0f,
                                 .l_h = 1.0f,
                                 .pole_pairs = 1u,
                                 .ke_v_s_rad = 0.17f,
                                 .kt_nm_a = 0.51f,
                                 .j_kgm2 = 1.0f,
                                 .k1_per_s = 4.0f,
                                 .k2_per_s = 75.0f,
                                 .kp_per_s2 = 5.0f,
                                 .kd_per_s2 = 10.0f,
                                 .ki_per_s3 = 0.01f,
                                 .a_per_s = 50.0f,
                                 .b = 50.0f,
                                 .eps_per_s = 0.02f,
                                 .dt_s = 1.0e-4f,
                                 .iq_max_a = 1.0e6f,
                                 .v_max_v = 1.0e9f,
                                 .nu_max_nm = 1.0e6f};
    const float wn = 30.0f;
    const float ki = wn * wn * wn;
    const float kp = (3.0f * wn * wn) + (ki / 2000.0f);
    const mc_pi2d_f32_cfg_t m = {.r_ohm = 0.675f,
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
                                 .v_max_v = 13.2f,
                                 .nu_max_nm = 1.0f};
    st->pi2d_motor_cfg = m;
    if (mc_pi2d_f32_init(&st->pi2d_paper, &p) != 0u ||
        mc_pi2d_f32_init(&st->pi2d_motor, &m) != 0u) {
        return 2;
    }
    return 0;
}

/* Paper 001's stepper and gains (k1^2 = 7.5e4, k2^2 = 550, mu = 0.1 A and
 * 50 rad/s^2, M = 50 V, q_i = 2.1 k0 mu L^M) at 100 kHz: the constant law
 * with the Sec. V servocompensators for w0 = 2 pi rad/s (poles -1, -2 +- j,
 * -3 +- j and -1, -2 +- j) fed by the HGO (alpha = 17, 80, 100,
 * eps = 1e-4 s, parabolic input); the model law with conditional
 * integrators (k0 = 20, 100); the ideal SMC (model law, sgn). */
static int setup_csmc(kv_state_t *st)
{
    mc_csmc_f32_cfg_t c;
    memset(&c, 0, sizeof c);
    c.law = MC_CSMC_LAW_MODEL;
    c.sw = MC_CSMC_SW_SAT;
    c.k1_per_s2 = 7.5e4f;
    c.k2_per_s = 550.0f;
    c.mu1_a = 0.1f;
    c.mu2_rad_s2 = 50.0f;
    c.m1_v = 50.0f;
    c.m2_v = 50.0f;
    c.model = (mc_csmc_f32_model_t){.km_nm_a = 0.1349f,
                                    .j_kgm2 = 4.1295e-4f,
                                    .b_nms_rad = 0.0013f,
                                    .rotor_teeth = 50u,
                                    .tau_load_nm = 0.2f,
                                    .r_nom_ohm = 20.0f,
                                    .r_min_ohm = 19.0f,
                                    .r_max_ohm = 21.0f,
                                    .l_nom_h = 0.035f,
                                    .l_min_h = 0.030f,
                                    .l_max_h = 0.040f,
                                    .q1_v = 2.1f * 20.0f * 0.1f * 0.040f,
                                    .q2_radh_s3 = 2.1f * 100.0f * 50.0f * 0.040f};
    c.v_limit_v = 1.0e4f;
    c.dt_s = 1.0e-5f;
    st->csmc_plant = c.model;

    mc_csmc_f32_cfg_t ideal = c;
    ideal.sw = MC_CSMC_SW_SGN;
    if (mc_csmc_f32_init(&st->csmc_ideal, &ideal) != 0u) {
        return 2;
    }
    if (mc_csvc_f32_integrator(20.0f, &c.sigma1) != 0u ||
        mc_csvc_f32_integrator(100.0f, &c.sigma2) != 0u ||
        mc_csmc_f32_init(&st->csmc_model, &c) != 0u) {
        return 2;
    }

    const float w02 = (2.0f * MC_PI_F32) * (2.0f * MC_PI_F32);
    const float c1[5] = {0.0f, -4.0f * w02 * w02, 0.0f, -5.0f * w02, 0.0f};
    const float re1[5] = {-1.0f, -2.0f, -2.0f, -3.0f, -3.0f};
    const float im1[5] = {0.0f, 1.0f, -1.0f, 1.0f, -1.0f};
    const float c2[3] = {0.0f, -w02, 0.0f};
    const float re2[3] = {-1.0f, -2.0f, -2.0f};
    const float im2[3] = {0.0f, 1.0f, -1.0f};
    c.law = MC_CSMC_LAW_CONST;
    if (mc_csvc_f32_place(5u, c1, re1, im1, &c.sigma1) != 0u ||
        mc_csvc_f32_place(3u, c2, re2, im2, &c.sigma2) != 0u ||
        mc_csmc_f32_init(&st->csmc_servo, &c) != 0u) {
        return 2;
    }
    const mc_hgo_f32_cfg_t h = {.alpha1 = 17.0f,
                                .alpha2 = 80.0f,
                                .alpha3 = 100.0f,
                                .eps_s = 1.0e-4f,
                                .dt_s = 1.0e-5f,
                                .input_order = 2u};
    if (mc_hgo_f32_init(&st->hgo, &h) != 0u) {
        return 2;
    }
    return 0;
}

static int setup(kv_state_t *st)
{
    const mc_pi_f32_cfg_t pc = {.kp = 2.5f,
                                .ki_per_s = 400.0f,
                                .dt_s = 5.0e-5f,
                                .out_min = -12.0f,
                                .out_max = 12.0f,
                                .aw = MC_PI_AW_CLAMP,
                                .kaw_per_s = 0.0f};
    mc_pi_f32_cfg_t pb = pc;
    pb.aw = MC_PI_AW_BACK_CALC;
    pb.kaw_per_s = 2000.0f;
    mc_pi_q31_cfg_t qc;
    if (mc_pi_f32_init(&st->clamp, &pc) != 0u || mc_pi_f32_init(&st->back_calc, &pb) != 0u ||
        mc_pi_q31_cfg_from_f32(&pc, 10.0f, 24.0f, &qc) != 0u || mc_pi_q31_init(&st->q, &qc) != 0u) {
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
    const mc_foc_f32_cfg_t fc = {.r_ohm = 0.675f,
                                 .ld_h = 1.14e-3f,
                                 .lq_h = 1.14e-3f,
                                 .flux_wb = 0.11f,
                                 .kp_d_v_per_a = kp,
                                 .ki_d_v_per_as = ki,
                                 .kp_q_v_per_a = kp,
                                 .ki_q_v_per_as = ki,
                                 .dt_s = 5.0e-5f,
                                 .aw = MC_PI_AW_CLAMP,
                                 .kaw_per_s = 0.0f,
                                 .limit_mode = MC_SVPWM_LIMIT_CIRCLE,
                                 .v_limit_ratio = 0.95f,
                                 .v_abs_max_v = 200.0f,
                                 .decouple = true};
    if (mc_foc_f32_init(&st->foc, &fc) != 0u) {
        return 2;
    }
    return setup_observer(st) | setup_filters(st) | setup_pi2d(st) | setup_csmc(st);
}

/* ---- driver ------------------------------------------------------------ */

static const kv_family_t k_families[] = {
    {"math_f32", 2u, 6u}, {"math_q31", 3u, 9u}, {"transforms", 8u, 22u}, {"svpwm", 6u, 21u},
    {"pi", 6u, 6u},       {"foc", 9u, 12u},     {"observer", 9u, 20u},   {"filters", 3u, 7u},
    {"pi2d", 12u, 33u},   {"csmc", 10u, 29u},   {NULL, 0u, 0u},
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
    } else if (strcmp(name, "foc") == 0) {
        fam_foc(st, in, out);
    } else if (strcmp(name, "observer") == 0) {
        fam_observer(st, in, out);
    } else if (strcmp(name, "filters") == 0) {
        fam_filters(st, in, out);
    } else if (strcmp(name, "pi2d") == 0) {
        fam_pi2d(st, in, out);
    } else {
        fam_csmc(st, in, out);
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
