/**
 * @file mc_foc.c
 * @brief dq current controller (float32). Equations and limits: mc_foc.h.
 */
#include "foc/mc_foc.h"

#include <stddef.h>

#include "math/mc_math.h"
#include "pi/mc_pi_core.h"
#include "transforms/mc_transforms.h"

/* Map PI init errors of one axis to the FOC flags. */
static uint32_t foc_pi_err(uint32_t pi_err, uint32_t gain_flag)
{
    uint32_t err = MC_FOC_ERR_NONE;

    if ((pi_err & (MC_PI_ERR_KP | MC_PI_ERR_KI)) != 0u) {
        err |= gain_flag;
    }
    if ((pi_err & (MC_PI_ERR_AW_MODE | MC_PI_ERR_KAW)) != 0u) {
        err |= MC_FOC_ERR_AW;
    }
    if ((pi_err & MC_PI_ERR_DT) != 0u) {
        err |= MC_FOC_ERR_DT;
    }
    if ((pi_err & MC_PI_ERR_LIMITS) != 0u) {
        err |= MC_FOC_ERR_V_LIMIT;
    }
    return err;
}

static bool foc_pos_f32(float x)
{
    return (x > 0.0f) && mc_isfinite_f32(x);
}

static bool foc_nonneg_f32(float x)
{
    return (x >= 0.0f) && mc_isfinite_f32(x);
}

uint32_t mc_foc_f32_gains_from_bandwidth(float r_ohm, float l_h, float bw_rad_s, float *p_kp,
                                         float *p_ki)
{
    uint32_t err = MC_FOC_ERR_NONE;

    if ((p_kp == NULL) || (p_ki == NULL)) {
        return MC_FOC_ERR_NULL;
    }
    if (!foc_nonneg_f32(r_ohm) || !foc_pos_f32(l_h)) {
        err |= MC_FOC_ERR_MOTOR;
    }
    if (!foc_pos_f32(bw_rad_s)) {
        err |= MC_FOC_ERR_BW;
    }
    if (err != MC_FOC_ERR_NONE) {
        return err;
    }
    *p_kp = l_h * bw_rad_s;
    *p_ki = r_ohm * bw_rad_s;
    return MC_FOC_ERR_NONE;
}

uint32_t mc_foc_f32_init(mc_foc_f32_t *st, const mc_foc_f32_cfg_t *cfg)
{
    uint32_t err = MC_FOC_ERR_NONE;
    mc_pi_f32_cfg_t pcfg;
    mc_pi_f32_t pi_d;
    mc_pi_f32_t pi_q;
    bool vabs_ok;

    if ((st == NULL) || (cfg == NULL)) {
        return MC_FOC_ERR_NULL;
    }
    if (!foc_nonneg_f32(cfg->r_ohm) || !foc_pos_f32(cfg->ld_h) || !foc_pos_f32(cfg->lq_h) ||
        !foc_nonneg_f32(cfg->flux_wb)) {
        err |= MC_FOC_ERR_MOTOR;
    }
    if ((cfg->limit_mode != MC_SVPWM_LIMIT_CIRCLE) && (cfg->limit_mode != MC_SVPWM_LIMIT_HEXAGON)) {
        err |= MC_FOC_ERR_LIMIT_MODE;
    }
    vabs_ok = foc_pos_f32(cfg->v_abs_max_v);
    if (!foc_pos_f32(cfg->v_limit_ratio) || !(cfg->v_limit_ratio <= 1.0f) || !vabs_ok) {
        err |= MC_FOC_ERR_V_LIMIT;
    }

    /* The PIs validate gains, dt and the anti-windup settings; a bad
     * v_abs_max_v is replaced by 1 here so that it is reported once, as
     * MC_FOC_ERR_V_LIMIT, and not also as a PI limit error. */
    pcfg.kp = cfg->kp_d_v_per_a;
    pcfg.ki_per_s = cfg->ki_d_v_per_as;
    pcfg.dt_s = cfg->dt_s;
    pcfg.out_max = vabs_ok ? cfg->v_abs_max_v : 1.0f;
    pcfg.out_min = -pcfg.out_max;
    pcfg.aw = cfg->aw;
    pcfg.kaw_per_s = cfg->kaw_per_s;
    err |= foc_pi_err(mc_pi_f32_init(&pi_d, &pcfg), MC_FOC_ERR_GAIN_D);
    pcfg.kp = cfg->kp_q_v_per_a;
    pcfg.ki_per_s = cfg->ki_q_v_per_as;
    err |= foc_pi_err(mc_pi_f32_init(&pi_q, &pcfg), MC_FOC_ERR_GAIN_Q);
    if (err != MC_FOC_ERR_NONE) {
        return err;
    }

    st->pi_d = pi_d;
    st->pi_q = pi_q;
    st->ld_h = cfg->ld_h;
    st->lq_h = cfg->lq_h;
    st->flux_wb = cfg->flux_wb;
    st->limit_mode = cfg->limit_mode;
    st->v_limit_ratio = cfg->v_limit_ratio;
    st->decouple = cfg->decouple;
    st->vd_v = 0.0f;
    st->vq_v = 0.0f;
    st->flags = MC_FOC_ERR_NONE;
    return MC_FOC_ERR_NONE;
}

void mc_foc_f32_reset(mc_foc_f32_t *st)
{
    if (st == NULL) {
        return;
    }
    (void)mc_pi_f32_reset(&st->pi_d, 0.0f);
    (void)mc_pi_f32_reset(&st->pi_q, 0.0f);
    st->vd_v = 0.0f;
    st->vq_v = 0.0f;
    st->flags = MC_FOC_ERR_NONE;
}

/* Input checks shared by both steps: returns the flags to raise. */
static uint32_t foc_check_inputs(float id_ref_a, float iq_ref_a, float id_a, float iq_a,
                                 float omega_e_rad_s, float vbus_v)
{
    if (!mc_isfinite_f32(id_ref_a) || !mc_isfinite_f32(iq_ref_a) || !mc_isfinite_f32(id_a) ||
        !mc_isfinite_f32(iq_a) || !mc_isfinite_f32(omega_e_rad_s) || !mc_isfinite_f32(vbus_v)) {
        return MC_FOC_ERR_NAN_INPUT;
    }
    if (!(vbus_v > 0.0f)) {
        return MC_FOC_ERR_VBUS;
    }
    return MC_FOC_ERR_NONE;
}

/* The dq step proper, inputs already checked. */
static uint32_t foc_dq_core(mc_foc_f32_t *st, float id_ref_a, float iq_ref_a, float id_a,
                            float iq_a, float omega_e_rad_s, float vbus_v, float *p_vd_v,
                            float *p_vq_v)
{
    float v_max = st->v_limit_ratio * mc_svpwm_max_voltage_f32(vbus_v, st->limit_mode);
    float ff_d = 0.0f;
    float ff_q = 0.0f;
    float vd;
    float vq;
    float vq_room_sq;
    float vq_max;
    mc_pi_f32_t pi_d_saved = st->pi_d;
    mc_pi_f32_t pi_q_saved = st->pi_q;

    if (st->decouple) {
        ff_d = -(omega_e_rad_s * st->lq_h * iq_a);
        ff_q = (omega_e_rad_s * st->ld_h * id_a) + (omega_e_rad_s * st->flux_wb);
    }

    /* The FOC owns both PIs and keeps its own sticky flags: clear theirs so
     * that a refusal in this step shows. */
    st->pi_d.flags = MC_PI_ERR_NONE;
    st->pi_q.flags = MC_PI_ERR_NONE;
    vd = mc_pi_f32_step_lim(&st->pi_d, id_ref_a - id_a, ff_d, -v_max, v_max);
    vq_room_sq = (v_max * v_max) - (vd * vd);
    vq_max = (vq_room_sq > 0.0f) ? mc_sqrt_f32(vq_room_sq) : 0.0f;
    vq = mc_pi_f32_step_lim(&st->pi_q, iq_ref_a - iq_a, ff_q, -vq_max, vq_max);

    if ((st->pi_d.flags | st->pi_q.flags) != MC_PI_ERR_NONE) {
        /* A PI refused its step (an error, feed-forward or limit overflowed
         * to infinity): both integrators stay as they were, zero voltage. */
        st->pi_d = pi_d_saved;
        st->pi_q = pi_q_saved;
        *p_vd_v = 0.0f;
        *p_vq_v = 0.0f;
        return MC_FOC_ERR_PI;
    }
    *p_vd_v = vd;
    *p_vq_v = vq;
    return MC_FOC_ERR_NONE;
}

/* ------------------------------------------------------------------------
 * Fast path. The checked code above tests every value where it is used (the
 * step, each PI, the modulator twice). The fast path computes the same
 * operations on the same values, in the same order, so it gives the same
 * bits, but screens for non-finite values a few at a time (foc_screen),
 * commits nothing until the whole step is known to be good, and
 * skips what the config validated at init already guarantees (the PI's
 * dynamic limits are ordered: -v_max <= 0 <= v_max). When anything is off
 * (a non-finite input or intermediate, vbus <= 0) it returns false with the
 * state untouched, and the checked code runs the step instead: errors,
 * flags and refusals are exactly the checked code's. tests/unit/foc
 * (test_foc_fast.cpp) compares the two paths bit for bit.
 * ------------------------------------------------------------------------ */

/* 0 * (sum of the values): +-0 when every value is finite (and their sum
 * does not overflow), NaN when one is NaN or +-inf (or the sum overflows:
 * a false alarm, which only sends the step to the checked path). One add
 * per value and one compare instead of a test per value. */
static float foc_screen(float sum)
{
    return 0.0f * sum;
}

/* The square root of a positive finite float: mc_sqrt_f32 puts its checks
 * (0, negative, NaN, inf) in front of this same instruction. */
static float foc_sqrt_pos(float x)
{
#if defined(__ARM_FP) || defined(__SSE_MATH__)
    return __builtin_sqrtf(x);
#else
    return mc_sqrt_f32(x);
#endif
}

/* The dq step of foc_dq_core, or false (nothing written) where the checked
 * path would refuse or might differ. */
static bool foc_dq_fast(mc_foc_f32_t *st, float id_ref_a, float iq_ref_a, float id_a, float iq_a,
                        float omega_e_rad_s, float vbus_v, float *p_vd_v, float *p_vq_v)
{
    float ff_d = 0.0f;
    float ff_q = 0.0f;
    float v_max;
    float e_d;
    float e_q;
    float hi;
    float vd;
    float vq;
    float integ_d;
    float integ_q;
    float vq_room_sq;
    float vq_max;
    float screen =
        foc_screen(id_ref_a + iq_ref_a + id_a + iq_a + omega_e_rad_s + vbus_v);

    if ((screen != 0.0f) || !(vbus_v > 0.0f)) {
        return false;
    }
    /* = st->v_limit_ratio * mc_svpwm_max_voltage_f32(vbus_v, st->limit_mode)
     * for the two modes init accepts; finite, as vbus is. */
    v_max = st->v_limit_ratio * ((st->limit_mode == MC_SVPWM_LIMIT_CIRCLE)
                                     ? (vbus_v * MC_INV_SQRT3_F32)
                                     : (vbus_v * (2.0f / 3.0f)));
    if (st->decouple) {
        ff_d = -(omega_e_rad_s * st->lq_h * iq_a);
        ff_q = (omega_e_rad_s * st->ld_h * id_a) + (omega_e_rad_s * st->flux_wb);
    }
    e_d = id_ref_a - id_a;
    e_q = iq_ref_a - iq_a;

    /* d axis: mc_pi_f32_step_lim(&st->pi_d, e_d, ff_d, -v_max, v_max). Its
     * limits are max(-v_max, out_min) and min(v_max, out_max); init made
     * out_min = -out_max (> 0), so the lower one is exactly minus the upper
     * one, and they are ordered since v_max >= 0. */
    hi = (v_max < st->pi_d.out_max) ? v_max : st->pi_d.out_max;
    vd = mc_pi_f32_core(&st->pi_d, e_d, ff_d, -hi, hi, &integ_d);

    vq_room_sq = (v_max * v_max) - (vd * vd);
    vq_max = (vq_room_sq > 0.0f) ? foc_sqrt_pos(vq_room_sq) : 0.0f;

    /* q axis: mc_pi_f32_step_lim(&st->pi_q, e_q, ff_q, -vq_max, vq_max), the
     * same way (vq_max >= 0, or NaN: caught below) */
    hi = (vq_max < st->pi_q.out_max) ? vq_max : st->pi_q.out_max;
    vq = mc_pi_f32_core(&st->pi_q, e_q, ff_q, -hi, hi, &integ_q);

    /* Everything the PIs check: their inputs (e, ff, the limits: v_max is
     * finite, a NaN vd makes vq_max NaN) and their results. The results
     * are clamped to finite limits, so they are finite or NaN: their plain
     * sum is NaN iff one of them is. */
    screen = foc_screen(e_d + ff_d + e_q + ff_q + vq_max) + (integ_d + vd + integ_q + vq);
    if (screen != screen) {
        return false;
    }
    /* The FOC keeps its own sticky flags and clears the PIs' every step. */
    st->pi_d.flags = MC_PI_ERR_NONE;
    st->pi_q.flags = MC_PI_ERR_NONE;
    mc_pi_f32_commit(&st->pi_d, e_d, ff_d, integ_d, vd);
    mc_pi_f32_commit(&st->pi_q, e_q, ff_q, integ_q, vq);
    *p_vd_v = vd;
    *p_vq_v = vq;
    return true;
}

uint32_t mc_foc_f32_step_dq(mc_foc_f32_t *st, float id_ref_a, float iq_ref_a, float id_a,
                            float iq_a, float omega_e_rad_s, float vbus_v, float *p_vd_v,
                            float *p_vq_v)
{
    uint32_t err;
    float vd = 0.0f;
    float vq = 0.0f;

    if ((st == NULL) || (p_vd_v == NULL) || (p_vq_v == NULL)) {
        return MC_FOC_ERR_NULL;
    }
    if (foc_dq_fast(st, id_ref_a, iq_ref_a, id_a, iq_a, omega_e_rad_s, vbus_v, &vd, &vq)) {
        st->vd_v = vd;
        st->vq_v = vq;
        *p_vd_v = vd;
        *p_vq_v = vq;
        return MC_FOC_ERR_NONE;
    }
    err = foc_check_inputs(id_ref_a, iq_ref_a, id_a, iq_a, omega_e_rad_s, vbus_v);
    if (err == MC_FOC_ERR_NONE) {
        err = foc_dq_core(st, id_ref_a, iq_ref_a, id_a, iq_a, omega_e_rad_s, vbus_v, &vd, &vq);
    }
    st->flags |= err;
    st->vd_v = vd;
    st->vq_v = vq;
    *p_vd_v = vd;
    *p_vq_v = vq;
    return err;
}

static void foc_out_zero(mc_foc_f32_out_t *out)
{
    out->duty_a = 0.5f;
    out->duty_b = 0.5f;
    out->duty_c = 0.5f;
    out->vd_v = 0.0f;
    out->vq_v = 0.0f;
    out->v_alpha_v = 0.0f;
    out->v_beta_v = 0.0f;
}

/* The whole step on the fast path (see above), or false with st untouched
 * (out may be partly written; the checked step rewrites all of it). */
static bool foc_step_fast(mc_foc_f32_t *st, const mc_foc_f32_in_t *in, mc_foc_f32_out_t *out)
{
    float i_alpha;
    float i_beta;
    float sin_th;
    float cos_th;
    float id;
    float iq;
    float vd;
    float vq;
    float v_alpha;
    float v_beta;
    float va_lim;
    float vb_lim;
    uint32_t svf;
    float sum = in->ia_a + in->ib_a + in->theta_e_rad;

    if (in->three_phase) {
        sum += in->ic_a;
    }
    if (foc_screen(sum) != 0.0f) {
        return false;
    }
    if (in->three_phase) {
        mc_clarke3_f32(in->ia_a, in->ib_a, in->ic_a, &i_alpha, &i_beta);
    } else {
        mc_clarke_f32(in->ia_a, in->ib_a, &i_alpha, &i_beta);
    }
    mc_sincos_f32(in->theta_e_rad, &sin_th, &cos_th);
    mc_park_f32(i_alpha, i_beta, sin_th, cos_th, &id, &iq);
    if (!foc_dq_fast(st, in->id_ref_a, in->iq_ref_a, id, iq, in->omega_e_rad_s, in->vbus_v, &vd,
                     &vq)) {
        return false;
    }

    /* From here on nothing can fail: vd, vq, sin, cos and vbus > 0 are
     * finite. Modulator limit and duties as mc_svpwm_limit_f32 followed by
     * mc_svpwm_f32 on the limited vector (one solution when not limited). */
    mc_inv_park_f32(vd, vq, sin_th, cos_th, &v_alpha, &v_beta);
    va_lim = v_alpha;
    vb_lim = v_beta;
    svf = mc_svpwm_limit_duty_f32(&va_lim, &vb_lim, in->vbus_v, st->limit_mode, &out->duty_a,
                                  &out->duty_b, &out->duty_c);
    if ((svf & MC_SVPWM_FLAG_LIMITED) != 0u) {
        v_alpha = va_lim;
        v_beta = vb_lim;
        mc_park_f32(v_alpha, v_beta, sin_th, cos_th, &vd, &vq);
        (void)mc_pi_f32_track(&st->pi_d, vd);
        (void)mc_pi_f32_track(&st->pi_q, vq);
    }
    st->vd_v = vd;
    st->vq_v = vq;
    out->svpwm_flags = svf;
    out->id_a = id;
    out->iq_a = iq;
    out->vd_v = vd;
    out->vq_v = vq;
    out->v_alpha_v = v_alpha;
    out->v_beta_v = v_beta;
    out->flags = st->flags;
    return true;
}

uint32_t mc_foc_f32_step(mc_foc_f32_t *st, const mc_foc_f32_in_t *in, mc_foc_f32_out_t *out)
{
    uint32_t err;
    float i_alpha = 0.0f;
    float i_beta = 0.0f;
    float sin_th = 0.0f;
    float cos_th = 1.0f;
    float id = 0.0f;
    float iq = 0.0f;
    float vd = 0.0f;
    float vq = 0.0f;
    float v_alpha = 0.0f;
    float v_beta = 0.0f;
    float va_lim;
    float vb_lim;

    if ((st == NULL) || (in == NULL) || (out == NULL)) {
        return MC_FOC_ERR_NULL;
    }
    if (foc_step_fast(st, in, out)) {
        return MC_FOC_ERR_NONE;
    }
    /* The checked step: errors, refusals, and what the fast path left. */
    out->svpwm_flags = MC_SVPWM_FLAG_NONE;
    out->id_a = 0.0f;
    out->iq_a = 0.0f;

    /* Raw inputs first: a NaN angle or current never reaches the transforms. */
    if (!mc_isfinite_f32(in->ia_a) || !mc_isfinite_f32(in->ib_a) ||
        (in->three_phase && !mc_isfinite_f32(in->ic_a)) || !mc_isfinite_f32(in->theta_e_rad)) {
        err = MC_FOC_ERR_NAN_INPUT;
    } else {
        if (in->three_phase) {
            mc_clarke3_f32(in->ia_a, in->ib_a, in->ic_a, &i_alpha, &i_beta);
        } else {
            mc_clarke_f32(in->ia_a, in->ib_a, &i_alpha, &i_beta);
        }
        mc_sincos_f32(in->theta_e_rad, &sin_th, &cos_th);
        mc_park_f32(i_alpha, i_beta, sin_th, cos_th, &id, &iq);
        out->id_a = id;
        out->iq_a = iq;
        err = foc_check_inputs(in->id_ref_a, in->iq_ref_a, id, iq, in->omega_e_rad_s, in->vbus_v);
        if (err == MC_FOC_ERR_NONE) {
            err = foc_dq_core(st, in->id_ref_a, in->iq_ref_a, id, iq, in->omega_e_rad_s,
                              in->vbus_v, &vd, &vq);
        }
    }
    if (err != MC_FOC_ERR_NONE) {
        st->flags |= err;
        st->vd_v = 0.0f;
        st->vq_v = 0.0f;
        foc_out_zero(out);
        out->flags = st->flags;
        return err;
    }

    mc_inv_park_f32(vd, vq, sin_th, cos_th, &v_alpha, &v_beta);
    va_lim = v_alpha;
    vb_lim = v_beta;
    out->svpwm_flags = mc_svpwm_limit_f32(&va_lim, &vb_lim, in->vbus_v, st->limit_mode);
    if ((out->svpwm_flags & MC_SVPWM_FLAG_LIMITED) != 0u) {
        /* The modulator cut the vector (hexagon flat sides, or rounding at
         * the circle): tell both PIs what was really applied. */
        v_alpha = va_lim;
        v_beta = vb_lim;
        mc_park_f32(v_alpha, v_beta, sin_th, cos_th, &vd, &vq);
        (void)mc_pi_f32_track(&st->pi_d, vd);
        (void)mc_pi_f32_track(&st->pi_q, vq);
    }
    out->svpwm_flags |= mc_svpwm_f32(v_alpha, v_beta, in->vbus_v, st->limit_mode, &out->duty_a,
                                     &out->duty_b, &out->duty_c);
    st->vd_v = vd;
    st->vq_v = vq;
    out->vd_v = vd;
    out->vq_v = vq;
    out->v_alpha_v = v_alpha;
    out->v_beta_v = v_beta;
    out->flags = st->flags;
    return MC_FOC_ERR_NONE;
}
