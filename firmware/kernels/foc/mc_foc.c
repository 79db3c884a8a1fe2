/**
 * @file mc_foc.c
 * @brief dq current controller (float32). Equations and limits: mc_foc.h.
 */
#include "foc/mc_foc.h"

#include <stddef.h>

#include "math/mc_math.h"
#include "pi/mc_pi_core.h"
#include "transforms/mc_svpwm_core.h"
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

/* The bits of a positive float and back (positive floats order like their
 * bit patterns). */
static uint32_t foc_bits_of(float x)
{
    union {
        float f;
        uint32_t u;
    } b;
    b.f = x;
    return b.u;
}

static float foc_float_of(uint32_t u)
{
    union {
        float f;
        uint32_t u;
    } b;
    b.u = u;
    return b.f;
}

/* Largest bus voltage of the fast path, as its bits (0x5D000000 = 2^59 at
 * most, which keeps v_max^2 finite): the largest vbus with
 * fl(v_max_per_vbus * vbus) <= out_max, so that the PIs' dynamic limit is
 * inside their static one there. The product is monotonic in vbus, so the
 * bound is found from the quotient by a few ulp steps. */
static uint32_t foc_vbus_fast_bound(float v_max_per_vbus, float out_max)
{
    const uint32_t cap = 0x5D000000u;
    const float x = out_max / v_max_per_vbus;
    uint32_t b;

    if (!(x < foc_float_of(cap))) {
        b = cap;
    } else {
        b = foc_bits_of(x);
    }
    while ((b > 0u) && !((v_max_per_vbus * foc_float_of(b)) <= out_max)) {
        --b;
    }
    while ((b < cap) && ((v_max_per_vbus * foc_float_of(b + 1u)) <= out_max)) {
        ++b;
    }
    return b;
}

/* The delay compensation's derived values for a valid periods (mc_foc.h). */
static void foc_set_delay(mc_foc_f32_t *st, float periods)
{
    st->delay_comp_periods = periods;
    st->adv_s = periods * st->dt_s;
    st->pred_d = mc_foc_f32_eval_pred_weight(periods, st->dt_s, st->pi_d.kp, st->ld_h);
    st->pred_q = mc_foc_f32_eval_pred_weight(periods, st->dt_s, st->pi_q.kp, st->lq_h);
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
    st->v_max_per_vbus = cfg->v_limit_ratio * mc_svpwm_max_voltage_f32(1.0f, cfg->limit_mode);
    st->decouple = cfg->decouple;
    st->ff_ld_h = cfg->decouple ? cfg->ld_h : 0.0f;
    st->ff_lq_h = cfg->decouple ? cfg->lq_h : 0.0f;
    st->ff_nlq_h = -st->ff_lq_h;
    st->ff_flux_wb = cfg->decouple ? cfg->flux_wb : 0.0f;
    /* the fast path runs the clamping anti-windup only (mc_pi_f32_core_in):
     * with the other schemes every step takes the checked code */
    st->vbus_fast_bound =
        (cfg->aw == MC_PI_AW_CLAMP) ? foc_vbus_fast_bound(st->v_max_per_vbus, pcfg.out_max) : 0u;
    st->vbus_fast_bits = st->vbus_fast_bound;
    st->svpwm_linear =
        (cfg->limit_mode == MC_SVPWM_LIMIT_CIRCLE) && (cfg->v_limit_ratio <= MC_FOC_LINEAR_RATIO);
    st->dt_s = cfg->dt_s;
    st->ki_d_cfg = cfg->ki_d_v_per_as;
    st->ki_q_cfg = cfg->ki_q_v_per_as;
    st->r_scale = 1.0f;
    foc_set_delay(st, MC_FOC_DELAY_COMP_PERIODS);
    st->flags = MC_FOC_ERR_NONE;
    return MC_FOC_ERR_NONE;
}

uint32_t mc_foc_f32_set_r_scale(mc_foc_f32_t *st, float scale)
{
    if (st == NULL) {
        return MC_FOC_ERR_NULL;
    }
    if (!mc_r_scale_f32_ok(scale)) {
        return MC_FOC_ERR_MOTOR;
    }
    /* ki_cfg >= 0 finite (init) times a scale in [0.25, 3]: both accepted */
    (void)mc_pi_f32_set_gains(&st->pi_d, st->pi_d.kp, st->ki_d_cfg * scale);
    (void)mc_pi_f32_set_gains(&st->pi_q, st->pi_q.kp, st->ki_q_cfg * scale);
    st->r_scale = scale;
    return MC_FOC_ERR_NONE;
}

uint32_t mc_foc_f32_set_delay_comp(mc_foc_f32_t *st, float periods)
{
    if (st == NULL) {
        return MC_FOC_ERR_NULL;
    }
    if (!mc_foc_f32_validate_delay_comp(periods)) {
        return MC_FOC_ERR_DELAY;
    }
    foc_set_delay(st, periods);
    return MC_FOC_ERR_NONE;
}

uint32_t mc_foc_f32_reset(mc_foc_f32_t *st)
{
    if (st == NULL) {
        return MC_FOC_ERR_NULL;
    }
    (void)mc_pi_f32_reset(&st->pi_d, 0.0f);
    (void)mc_pi_f32_reset(&st->pi_q, 0.0f);
    st->flags = MC_FOC_ERR_NONE;
    st->vbus_fast_bits = st->vbus_fast_bound;
    return MC_FOC_ERR_NONE;
}

/* Raise sticky flags (err may be 0). The fast path runs only while none is
 * set: its bus bound is 0 from then on, until reset. */
static void foc_raise(mc_foc_f32_t *st, uint32_t err)
{
    st->flags |= err;
    if (st->flags != MC_FOC_ERR_NONE) {
        st->vbus_fast_bits = 0u;
    }
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

/* The decoupling feed-forward, -omega L_q i_q and omega (L_d i_d + psi),
 * with the currents predicted for the interval the voltage acts over
 * (i + w (i_ref - i), mc_foc.h); its gains are 0 without decoupling (then
 * the terms are +-0, or NaN for a non-finite speed or current). */
static inline void foc_feed_forward(const mc_foc_f32_t *st, float id_ref_a, float iq_ref_a,
                                    float id_a, float iq_a, float omega_e_rad_s, float *p_ff_d,
                                    float *p_ff_q)
{
    id_a += st->pred_d * (id_ref_a - id_a);
    iq_a += st->pred_q * (iq_ref_a - iq_a);
    /* -(w (L_q i_q)) as w ((-L_q) i_q): the same bits (rounding is
     * symmetric, and the signs of zeros agree), no negation left to store */
    *p_ff_d = omega_e_rad_s * (st->ff_nlq_h * iq_a);
    *p_ff_q = omega_e_rad_s * ((st->ff_ld_h * id_a) + st->ff_flux_wb);
}

/* The dq step proper, inputs already checked (the checked path). */
static uint32_t foc_dq_core(mc_foc_f32_t *st, float id_ref_a, float iq_ref_a, float id_a,
                            float iq_a, float omega_e_rad_s, float vbus_v, float *p_vd_v,
                            float *p_vq_v)
{
    float v_max = st->v_max_per_vbus * vbus_v;
    float ff_d;
    float ff_q;
    float vd;
    float vq;
    float vq_room_sq;
    float vq_max;
    mc_pi_f32_t pi_d_saved = st->pi_d;
    mc_pi_f32_t pi_q_saved = st->pi_q;

    foc_feed_forward(st, id_ref_a, iq_ref_a, id_a, iq_a, omega_e_rad_s, &ff_d, &ff_q);

    /* The FOC owns both PIs and keeps its own sticky flags: clear theirs so
     * that a refusal in this step shows. */
    st->pi_d.flags = MC_PI_ERR_NONE;
    st->pi_q.flags = MC_PI_ERR_NONE;
    (void)mc_pi_f32_step_lim(&st->pi_d, id_ref_a - id_a, ff_d, -v_max, v_max, &vd);
    vq_room_sq = (v_max * v_max) - (vd * vd);
    vq_max = (vq_room_sq > 0.0f) ? mc_sqrt_f32(vq_room_sq) : 0.0f;
    (void)mc_pi_f32_step_lim(&st->pi_q, iq_ref_a - iq_a, ff_q, -vq_max, vq_max, &vq);

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
 * bits, but tests only what NaN propagation does not catch (see mc_foc.h),
 * commits nothing until the PIs are known good, and skips what init
 * validated already (the PIs' limits are symmetric: out_min = -out_max, so
 * the checked PI's dynamic limits max(-x, out_min), min(x, out_max) are
 * -hi, hi with hi = min(x, out_max)). When anything is off it returns false
 * with the state untouched, and the checked code runs the step instead:
 * errors, flags and refusals are exactly the checked code's.
 * tests/unit/foc (test_foc_fast.cpp) compares the two paths bit for bit.
 * ------------------------------------------------------------------------ */

/* The fast path is inlined into each entry point: one frame, no arguments
 * through memory. */
#if defined(__GNUC__)
#define FOC_INLINE static inline __attribute__((always_inline))
#else
#define FOC_INLINE static inline
#endif

/* The square root of a positive finite float: mc_sqrt_f32 puts its checks
 * (0, negative, NaN, inf) in front of this same instruction. */
FOC_INLINE float foc_sqrt_pos(float x)
{
#if defined(__ARM_FP) || defined(__SSE_MATH__)
    return __builtin_sqrtf(x);
#else
    return mc_sqrt_f32(x);
#endif
}

/* 0 < vbus <= the bus bound of init (foc_vbus_fast_bound; at most 2^59;
 * 0 once a sticky flag is set: then false for every vbus;
 * false for NaN): one unsigned compare, as +0 (bits 0) wraps to the top and
 * every negative float, inf and NaN lie above. */
FOC_INLINE bool foc_vbus_fast_ok(const mc_foc_f32_t *st, float vbus_v)
{
    return (foc_bits_of(vbus_v) - 1u) < st->vbus_fast_bits;
}

/* |theta| <= MC_MATH_NEAR_LIMIT_RAD (256 = bits 0x43800000; false for NaN
 * and inf) and foc_vbus_fast_ok(vbus): the angle's bits without the sign,
 * compared in one. */
FOC_INLINE bool foc_theta_fast_ok(float theta_rad)
{
    return (foc_bits_of(theta_rad) << 1) <= (0x43800000u << 1);
}

FOC_INLINE bool foc_theta_vbus_fast_ok(const mc_foc_f32_t *st, float theta_rad, float vbus_v)
{
    return foc_theta_fast_ok(theta_rad) & foc_vbus_fast_ok(st, vbus_v);
}

/* The dq step of foc_dq_core for 0 < vbus <= the bus bound (foc_vbus_fast_ok:
 * the caller tests it; then v_max <= out_max of both PIs), committed to both PIs; or false with nothing written where the
 * checked path would refuse or might differ. The PIs' own sticky flags are
 * not touched: they are 0 between steps (the checked step clears them and a
 * refused step restores the PIs as they were). */
FOC_INLINE bool foc_dq_fast(mc_foc_f32_t *st, float id_ref_a, float iq_ref_a, float id_a,
                            float iq_a, float omega_e_rad_s, float vbus_v, float *p_vd_v,
                            float *p_vq_v)
{
    float ff_d;
    float ff_q;
    float vd;
    float vq;
    float integ_d;
    float integ_q;
    float vq_room_sq;
    float vq_max;
    /* finite and at most the PIs' out_max (the bus bound) */
    const float v_max = st->v_max_per_vbus * vbus_v;

    /* a non-finite speed makes both terms non-finite (0 * inf is NaN):
     * caught by the PIs' tests */
    foc_feed_forward(st, id_ref_a, iq_ref_a, id_a, iq_a, omega_e_rad_s, &ff_d, &ff_q);
    const float e_d = id_ref_a - id_a;
    const float e_q = iq_ref_a - iq_a;

    /* d axis: mc_pi_f32_step_lim(&st->pi_d, e_d, ff_d, -v_max, v_max) */
    if (!mc_pi_f32_core_in(&st->pi_d, e_d, ff_d, v_max, &integ_d, &vd)) {
        return false;
    }
    /* |vd| <= v_max (the PI's limit), so vd^2 <= v_max^2 after rounding
     * too (rounding is monotonic) and the room is finite and >= +0 (an
     * exact difference of equal floats is +0): its square root is what the
     * checked path's (room > 0) ? sqrt(room) : 0 gives. */
    vq_room_sq = (v_max * v_max) - (vd * vd);
    vq_max = foc_sqrt_pos(vq_room_sq);

    /* q axis: mc_pi_f32_step_lim(&st->pi_q, e_q, ff_q, -vq_max, vq_max);
     * vq_max <= v_max <= out_max (rounding is monotonic: the room is at
     * most fl(v_max^2), whose square root is at most v_max) */
    if (!mc_pi_f32_core_in(&st->pi_q, e_q, ff_q, vq_max, &integ_q, &vq)) {
        return false;
    }
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
    if (foc_vbus_fast_ok(st, vbus_v) &&
        foc_dq_fast(st, id_ref_a, iq_ref_a, id_a, iq_a, omega_e_rad_s, vbus_v, &vd, &vq)) {
        *p_vd_v = vd;
        *p_vq_v = vq;
        return MC_FOC_ERR_NONE;
    }
    err = foc_check_inputs(id_ref_a, iq_ref_a, id_a, iq_a, omega_e_rad_s, vbus_v);
    if (err == MC_FOC_ERR_NONE) {
        err = foc_dq_core(st, id_ref_a, iq_ref_a, id_a, iq_a, omega_e_rad_s, vbus_v, &vd, &vq);
    }
    foc_raise(st, err);
    *p_vd_v = vd;
    *p_vq_v = vq;
    return err;
}

/* The modulator cut the vector (hexagon flat sides, or rounding at the
 * circle): tell both PIs what was really applied. */
static void foc_track_applied(mc_foc_f32_t *st, float v_alpha, float v_beta, float sin_th,
                              float cos_th, float *p_vd, float *p_vq)
{
    mc_park_f32(v_alpha, v_beta, sin_th, cos_th, p_vd, p_vq);
    (void)mc_pi_f32_track(&st->pi_d, *p_vd);
    (void)mc_pi_f32_track(&st->pi_q, *p_vq);
}

/* The applied voltage after the modulator: alpha-beta and dq. */
typedef struct {
    float v_alpha;
    float v_beta;
    float vd;
    float vq;
} foc_applied_t;

/* The fast path's modulator when it is not known to stay linear: limit and
 * duties (mc_svpwm_limit_duty_f32), the cut fed back to the PIs. Out of
 * line, so that the linear case needs no stack frame; writes the duties
 * and out->svpwm_flags, returns the applied voltage. */
static foc_applied_t foc_modulate_general(mc_foc_f32_t *st, foc_applied_t v, float vbus,
                                          float sin_th, float cos_th, mc_foc_f32_out_t *out)
{
    float va_lim = v.v_alpha;
    float vb_lim = v.v_beta;
    const uint32_t svf = mc_svpwm_limit_duty_f32(&va_lim, &vb_lim, vbus, st->limit_mode,
                                                 &out->duty_a, &out->duty_b, &out->duty_c);
    if ((svf & MC_SVPWM_FLAG_LIMITED) != 0u) {
        v.v_alpha = va_lim;
        v.v_beta = vb_lim;
        foc_track_applied(st, v.v_alpha, v.v_beta, sin_th, cos_th, &v.vd, &v.vq);
    }
    out->svpwm_flags = svf;
    return v;
}

/* The whole step from alpha-beta currents on the fast path (see above), or
 * false with st untouched (out may be partly written; the checked step
 * rewrites all of it). */
FOC_INLINE bool foc_step_fast(mc_foc_f32_t *st, float i_alpha, float i_beta, float theta,
                              float omega, float vbus, float id_ref, float iq_ref,
                              mc_foc_f32_out_t *out)
{
    float sin_th;
    float cos_th;
    float sin_v;
    float cos_v;
    float id;
    float iq;
    foc_applied_t v;
    /* the voltage angle: non-finite for a non-finite speed (0 * inf is
     * NaN), which sends the step to the checked path before anything is
     * committed */
    const float theta_v = mc_foc_f32_eval_voltage_angle(st, theta, omega);

    /* NaN fails both; a non-finite current shows in the PIs */
    if (!foc_theta_vbus_fast_ok(st, theta, vbus) || !foc_theta_fast_ok(theta_v)) {
        return false;
    }
    mc_sincos_near_f32(theta, &sin_th, &cos_th); /* = mc_sincos_f32 here */
    mc_park_f32(i_alpha, i_beta, sin_th, cos_th, &id, &iq);
    if (!foc_dq_fast(st, id_ref, iq_ref, id, iq, omega, vbus, &v.vd, &v.vq)) {
        return false;
    }
    if (st->adv_s > 0.0f) {
        mc_sincos_near_f32(theta_v, &sin_v, &cos_v);
    } else {
        sin_v = sin_th;
        cos_v = cos_th;
    }

    /* From here on nothing can fail: vd, vq, sin, cos are finite and
     * 0 < vbus <= 2^59. Modulator limit and duties as mc_svpwm_limit_f32
     * followed by mc_svpwm_f32 on the limited vector. */
    mc_inv_park_f32(v.vd, v.vq, sin_v, cos_v, &v.v_alpha, &v.v_beta);
    if (MC_PI_LIKELY(st->svpwm_linear)) {
        /* mc_svpwm_f32's linear case: its first test |v_alpha|, |v_beta|
         * <= vbus holds (|v| <= v_max (1 + 1e-6) < 0.58 vbus), and so does
         * its second (MC_FOC_LINEAR_RATIO), so the duties are these and the
         * modulator limits nothing. */
        mc_svpwm_circle_duties_f32(v.v_alpha / vbus, v.v_beta / vbus, &out->duty_a, &out->duty_b,
                                   &out->duty_c);
        out->svpwm_flags = MC_SVPWM_FLAG_NONE;
    } else {
        v = foc_modulate_general(st, v, vbus, sin_v, cos_v, out);
    }
    out->id_a = id;
    out->iq_a = iq;
    out->vd_v = v.vd;
    out->vq_v = v.vq;
    out->v_alpha_v = v.v_alpha;
    out->v_beta_v = v.v_beta;
    out->flags = MC_FOC_ERR_NONE; /* the fast path runs with no sticky flag set */
    return true;
}

/* An error of the whole step: zero voltage, duties 0.5, sticky flag. */
static uint32_t foc_step_fail(mc_foc_f32_t *st, mc_foc_f32_out_t *out, uint32_t err)
{
    foc_raise(st, err);
    out->duty_a = 0.5f;
    out->duty_b = 0.5f;
    out->duty_c = 0.5f;
    out->vd_v = 0.0f;
    out->vq_v = 0.0f;
    out->v_alpha_v = 0.0f;
    out->v_beta_v = 0.0f;
    out->flags = st->flags;
    return err;
}

/* sin and cos of the voltage angle for a finite theta and omega (the sampled
 * angle's when the compensation is off); MC_FOC_ERR_NAN_INPUT when the
 * advanced angle overflows. */
static uint32_t foc_voltage_sincos(const mc_foc_f32_t *st, float theta, float omega, float sin_th,
                                   float cos_th, float *p_sin_v, float *p_cos_v)
{
    const float theta_v = mc_foc_f32_eval_voltage_angle(st, theta, omega);

    if (!(st->adv_s > 0.0f)) {
        *p_sin_v = sin_th;
        *p_cos_v = cos_th;
        return MC_FOC_ERR_NONE;
    }
    if (!mc_isfinite_f32(theta_v)) {
        return MC_FOC_ERR_NAN_INPUT;
    }
    mc_sincos_f32(theta_v, p_sin_v, p_cos_v);
    return MC_FOC_ERR_NONE;
}

/* The checked whole step from alpha-beta currents: errors, refusals, and
 * what the fast path left. */
static uint32_t foc_step_checked(mc_foc_f32_t *st, float i_alpha, float i_beta, float theta,
                                 float omega, float vbus, float id_ref, float iq_ref,
                                 mc_foc_f32_out_t *out)
{
    uint32_t err;
    float sin_th = 0.0f;
    float cos_th = 1.0f;
    float sin_v = 0.0f;
    float cos_v = 1.0f;
    float id = 0.0f;
    float iq = 0.0f;
    float vd = 0.0f;
    float vq = 0.0f;
    float v_alpha = 0.0f;
    float v_beta = 0.0f;
    float va_lim;
    float vb_lim;

    out->svpwm_flags = MC_SVPWM_FLAG_NONE;
    out->id_a = 0.0f;
    out->iq_a = 0.0f;
    /* Raw inputs first: a NaN angle or current never reaches the transforms. */
    if (!mc_isfinite_f32(i_alpha) || !mc_isfinite_f32(i_beta) || !mc_isfinite_f32(theta)) {
        return foc_step_fail(st, out, MC_FOC_ERR_NAN_INPUT);
    }
    mc_sincos_f32(theta, &sin_th, &cos_th);
    mc_park_f32(i_alpha, i_beta, sin_th, cos_th, &id, &iq);
    out->id_a = id;
    out->iq_a = iq;
    err = foc_check_inputs(id_ref, iq_ref, id, iq, omega, vbus);
    if (err == MC_FOC_ERR_NONE) {
        err = foc_voltage_sincos(st, theta, omega, sin_th, cos_th, &sin_v, &cos_v);
    }
    if (err == MC_FOC_ERR_NONE) {
        err = foc_dq_core(st, id_ref, iq_ref, id, iq, omega, vbus, &vd, &vq);
    }
    if (err != MC_FOC_ERR_NONE) {
        return foc_step_fail(st, out, err);
    }

    mc_inv_park_f32(vd, vq, sin_v, cos_v, &v_alpha, &v_beta);
    va_lim = v_alpha;
    vb_lim = v_beta;
    out->svpwm_flags = mc_svpwm_limit_f32(&va_lim, &vb_lim, vbus, st->limit_mode);
    if ((out->svpwm_flags & MC_SVPWM_FLAG_LIMITED) != 0u) {
        v_alpha = va_lim;
        v_beta = vb_lim;
        foc_track_applied(st, v_alpha, v_beta, sin_v, cos_v, &vd, &vq);
    }
    out->svpwm_flags |= mc_svpwm_f32(v_alpha, v_beta, vbus, st->limit_mode, &out->duty_a,
                                     &out->duty_b, &out->duty_c);
    out->vd_v = vd;
    out->vq_v = vq;
    out->v_alpha_v = v_alpha;
    out->v_beta_v = v_beta;
    out->flags = st->flags;
    return MC_FOC_ERR_NONE;
}

uint32_t mc_foc_f32_step_ab(mc_foc_f32_t *st, float i_alpha_a, float i_beta_a, float theta_e_rad,
                            float omega_e_rad_s, float vbus_v, float id_ref_a, float iq_ref_a,
                            mc_foc_f32_out_t *out)
{
    if ((st == NULL) || (out == NULL)) {
        return MC_FOC_ERR_NULL;
    }
    if (foc_step_fast(st, i_alpha_a, i_beta_a, theta_e_rad, omega_e_rad_s, vbus_v, id_ref_a,
                      iq_ref_a, out)) {
        return MC_FOC_ERR_NONE;
    }
    return foc_step_checked(st, i_alpha_a, i_beta_a, theta_e_rad, omega_e_rad_s, vbus_v, id_ref_a,
                            iq_ref_a, out);
}

uint32_t mc_foc_f32_step(mc_foc_f32_t *st, const mc_foc_f32_in_t *in, mc_foc_f32_out_t *out)
{
    float i_alpha;
    float i_beta;

    /* one branch for the three pointers (| evaluates all, no short circuit) */
    if ((int)(st == NULL) | (int)(in == NULL) | (int)(out == NULL)) {
        return MC_FOC_ERR_NULL;
    }
    /* A non-finite current that is read gives a non-finite alpha or beta
     * (x + finite, x * nonzero constant): the step from alpha-beta reports
     * it as MC_FOC_ERR_NAN_INPUT. */
    if (in->three_phase) {
        mc_clarke3_f32(in->ia_a, in->ib_a, in->ic_a, &i_alpha, &i_beta);
    } else {
        mc_clarke_f32(in->ia_a, in->ib_a, &i_alpha, &i_beta);
    }
    if (foc_step_fast(st, i_alpha, i_beta, in->theta_e_rad, in->omega_e_rad_s, in->vbus_v,
                      in->id_ref_a, in->iq_ref_a, out)) {
        return MC_FOC_ERR_NONE;
    }
    return foc_step_checked(st, i_alpha, i_beta, in->theta_e_rad, in->omega_e_rad_s, in->vbus_v,
                            in->id_ref_a, in->iq_ref_a, out);
}
