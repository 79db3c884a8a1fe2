/**
 * @file mc_traj.c
 * @brief Trapezoidal trajectory and input filter, float32 (see mc_traj.h).
 */
#include "traj/mc_traj.h"

#include <stddef.h>

#include "math/mc_math.h"

static bool pos_finite(float x)
{
    return mc_isfinite_f32(x) && (x > 0.0f);
}

/* e^-h for 0 <= h <= 1 without libm (init only): Taylor series of e^(-h/8)
 * to the (h/8)^7 term (truncation below 1e-9 relative), then squared three
 * times (float rounding: a few 1e-7 relative). */
static float exp_neg(float h)
{
    const float y = -h / 8.0f;
    float term = 1.0f;
    float sum = 1.0f;
    for (unsigned n = 1u; n < 8u; ++n) {
        term *= y / (float)n;
        sum += term;
    }
    sum *= sum;
    sum *= sum;
    sum *= sum;
    return sum;
}

static uint32_t check_limits(float v, float a, float d)
{
    return (pos_finite(v) && pos_finite(a) && pos_finite(d)) ? MC_TRAJ_ERR_NONE : MC_TRAJ_ERR_LIMIT;
}

uint32_t mc_traj_f32_init(mc_traj_f32_t *t, const mc_traj_f32_cfg_t *cfg)
{
    if ((t == NULL) || (cfg == NULL)) {
        return MC_TRAJ_ERR_NULL;
    }
    uint32_t err = check_limits(cfg->v_max_rad_s, cfg->a_max_rad_s2, cfg->d_max_rad_s2);
    if (!pos_finite(cfg->dt_s)) {
        err |= MC_TRAJ_ERR_DT;
    }
    const float w = cfg->filter_bw_rad_s;
    if (!mc_isfinite_f32(w) || (w < 0.0f) ||
        ((err & MC_TRAJ_ERR_DT) == 0u && (w * cfg->dt_s > 1.0f))) {
        err |= MC_TRAJ_ERR_FILTER;
    }
    if (err != MC_TRAJ_ERR_NONE) {
        return err;
    }
    t->cfg = *cfg;
    /* Exact transition of e = x - r, v over one period (double root -w):
     * e(T) = E ((1 + h) e + T v), v(T) = E (-w^2 T e + (1 - h) v),
     * h = w T, E = e^-h. */
    const float dt = cfg->dt_s;
    const float h = w * dt;
    const float e = exp_neg(h);
    t->f11 = e * (1.0f + h);
    t->f12 = e * dt;
    t->f21 = -e * w * w * dt;
    t->f22 = e * (1.0f - h);
    t->mode = MC_TRAJ_MODE_TRAP;
    return mc_traj_f32_reset(t, 0.0f);
}

uint32_t mc_traj_f32_reset(mc_traj_f32_t *t, float x_rad)
{
    if (t == NULL) {
        return MC_TRAJ_ERR_NULL;
    }
    if (!mc_isfinite_f32(x_rad)) {
        return MC_TRAJ_ERR_INPUT;
    }
    for (unsigned i = 0u; i < MC_TRAJ_SEGMENTS; ++i) {
        t->t_s[i] = 0.0f;
        t->x_s[i] = x_rad;
        t->v_s[i] = 0.0f;
        t->a_s[i] = 0.0f;
    }
    t->t_s[MC_TRAJ_SEGMENTS] = 0.0f;
    t->x_target_rad = x_rad;
    t->k = 0u;
    t->fx_rad = x_rad;
    t->fv_rad_s = 0.0f;
    t->fr_rad = x_rad;
    t->out.x_rad = x_rad;
    t->out.v_rad_s = 0.0f;
    t->out.a_rad_s2 = 0.0f;
    t->out.done = true;
    return MC_TRAJ_ERR_NONE;
}

uint32_t mc_traj_f32_set_limits(mc_traj_f32_t *t, float v_max_rad_s, float a_max_rad_s2,
                                float d_max_rad_s2)
{
    if (t == NULL) {
        return MC_TRAJ_ERR_NULL;
    }
    const uint32_t err = check_limits(v_max_rad_s, a_max_rad_s2, d_max_rad_s2);
    if (err == MC_TRAJ_ERR_NONE) {
        t->cfg.v_max_rad_s = v_max_rad_s;
        t->cfg.a_max_rad_s2 = a_max_rad_s2;
        t->cfg.d_max_rad_s2 = d_max_rad_s2;
    }
    return err;
}

/* The plan (mc_traj.h): direction s from the stopping point, an optional
 * brake segment, then ramp / cruise / stop from v_s = s v >= 0. */
static void plan_core(mc_traj_f32_t *t, float x0, float v0, float xf, float a, float d, float vmax)
{
    const float stop = v0 * mc_abs_f32(v0) / (2.0f * d);
    const float diff = xf - (x0 + stop);
    const float s = ((diff > 0.0f) || ((diff == 0.0f) && (v0 >= 0.0f))) ? 1.0f : -1.0f;
    float x = x0;
    float v = v0;
    float time = 0.0f;
    /* 0: brake when the velocity points away from the target */
    t->t_s[0] = 0.0f;
    t->x_s[0] = x;
    t->v_s[0] = v;
    if (s * v < 0.0f) {
        const float dur = -s * v / d;
        t->a_s[0] = s * d;
        x += dur * (v + 0.5f * s * d * dur);
        v = 0.0f;
        time = dur;
    } else {
        t->a_s[0] = 0.0f;
    }
    const float vs = s * v;
    float dist = s * (xf - x);
    if (dist < 0.0f) {
        dist = 0.0f; /* rounding of the brake segment */
    }
    float vc;
    float a1;
    float cruise;
    if (vs <= vmax) {
        const float vp2 = (2.0f * a * d * dist + d * vs * vs) / (a + d);
        if (vp2 <= vmax * vmax) {
            vc = mc_sqrt_nonneg_f32(vp2);
            if (vc < vs) {
                vc = vs; /* rounding: a triangle never falls below v_s */
            }
            cruise = 0.0f;
        } else {
            vc = vmax;
            cruise = dist - ((vmax * vmax - vs * vs) / (2.0f * a)) - (vmax * vmax / (2.0f * d));
        }
        a1 = a;
    } else {
        vc = vmax;
        a1 = -d;
        cruise = dist - (vs * vs / (2.0f * d));
    }
    if (cruise < 0.0f) {
        cruise = 0.0f;
    }
    const float t1 = (vc - vs) / a1;
    const float t2 = (vc > 0.0f) ? cruise / vc : 0.0f;
    const float t3 = vc / d;
    /* 1: ramp */
    t->t_s[1] = time;
    t->x_s[1] = x;
    t->v_s[1] = v;
    t->a_s[1] = s * a1;
    x += t1 * (v + 0.5f * s * a1 * t1);
    v = s * vc;
    time += t1;
    /* 2: cruise */
    t->t_s[2] = time;
    t->x_s[2] = x;
    t->v_s[2] = v;
    t->a_s[2] = 0.0f;
    x += v * t2;
    time += t2;
    /* 3: stop */
    t->t_s[3] = time;
    t->x_s[3] = x;
    t->v_s[3] = v;
    t->a_s[3] = -s * d;
    time += t3;
    t->t_s[4] = time;
    t->x_target_rad = xf;
    t->k = 0u;
}

void mc_traj_f32_eval(const mc_traj_f32_t *t, float t_s, mc_traj_f32_out_t *out)
{
    if ((t == NULL) || (out == NULL)) {
        return;
    }
    if (!(t_s < t->t_s[MC_TRAJ_SEGMENTS])) {
        out->x_rad = t->x_target_rad;
        out->v_rad_s = 0.0f;
        out->a_rad_s2 = 0.0f;
        out->done = true;
        return;
    }
    unsigned k = MC_TRAJ_SEGMENTS - 1u;
    while ((k > 0u) && (t_s < t->t_s[k])) {
        k--;
    }
    const float tau = t_s - t->t_s[k];
    out->x_rad = t->x_s[k] + tau * (t->v_s[k] + 0.5f * t->a_s[k] * tau);
    out->v_rad_s = t->v_s[k] + t->a_s[k] * tau;
    out->a_rad_s2 = t->a_s[k];
    out->done = false;
}

/* The state the generator outputs at the present step. */
static void present(const mc_traj_f32_t *t, mc_traj_f32_out_t *o)
{
    if (t->mode == MC_TRAJ_MODE_FILTER) {
        o->x_rad = t->fx_rad;
        o->v_rad_s = t->fv_rad_s;
        o->a_rad_s2 = 0.0f;
        o->done = false;
    } else {
        mc_traj_f32_eval(t, (float)t->k * t->cfg.dt_s, o);
    }
}

uint32_t mc_traj_f32_plan(mc_traj_f32_t *t, float x0_rad, float v0_rad_s, float x_target_rad)
{
    if (t == NULL) {
        return MC_TRAJ_ERR_NULL;
    }
    if (!mc_isfinite_f32(x0_rad) || !mc_isfinite_f32(v0_rad_s) || !mc_isfinite_f32(x_target_rad)) {
        return MC_TRAJ_ERR_INPUT;
    }
    t->mode = MC_TRAJ_MODE_TRAP;
    plan_core(t, x0_rad, v0_rad_s, x_target_rad, t->cfg.a_max_rad_s2, t->cfg.d_max_rad_s2,
              t->cfg.v_max_rad_s);
    return MC_TRAJ_ERR_NONE;
}

uint32_t mc_traj_f32_set_target(mc_traj_f32_t *t, float x_target_rad)
{
    if (t == NULL) {
        return MC_TRAJ_ERR_NULL;
    }
    mc_traj_f32_out_t o;
    present(t, &o);
    return mc_traj_f32_plan(t, o.x_rad, o.v_rad_s, x_target_rad);
}

uint32_t mc_traj_f32_stop(mc_traj_f32_t *t, float d_rad_s2)
{
    if (t == NULL) {
        return MC_TRAJ_ERR_NULL;
    }
    if (!pos_finite(d_rad_s2)) {
        return MC_TRAJ_ERR_INPUT;
    }
    mc_traj_f32_out_t o;
    present(t, &o);
    const float xf = o.x_rad + (o.v_rad_s * mc_abs_f32(o.v_rad_s) / (2.0f * d_rad_s2));
    t->mode = MC_TRAJ_MODE_TRAP;
    plan_core(t, o.x_rad, o.v_rad_s, xf, t->cfg.a_max_rad_s2, d_rad_s2, t->cfg.v_max_rad_s);
    return MC_TRAJ_ERR_NONE;
}

uint32_t mc_traj_f32_set_mode(mc_traj_f32_t *t, mc_traj_mode_t mode)
{
    if (t == NULL) {
        return MC_TRAJ_ERR_NULL;
    }
    if ((mode != MC_TRAJ_MODE_TRAP) &&
        ((mode != MC_TRAJ_MODE_FILTER) || !(t->cfg.filter_bw_rad_s > 0.0f))) {
        return MC_TRAJ_ERR_MODE;
    }
    if (mode == t->mode) {
        return MC_TRAJ_ERR_NONE;
    }
    mc_traj_f32_out_t o;
    present(t, &o);
    if (mode == MC_TRAJ_MODE_FILTER) {
        t->fx_rad = o.x_rad;
        t->fv_rad_s = o.v_rad_s;
        t->fr_rad = t->x_target_rad;
        t->mode = MC_TRAJ_MODE_FILTER;
        return MC_TRAJ_ERR_NONE;
    }
    return mc_traj_f32_plan(t, o.x_rad, o.v_rad_s, t->fr_rad);
}

uint32_t mc_traj_f32_set_input(mc_traj_f32_t *t, float r_rad)
{
    if (t == NULL) {
        return MC_TRAJ_ERR_NULL;
    }
    if (!mc_isfinite_f32(r_rad)) {
        return MC_TRAJ_ERR_INPUT;
    }
    if (t->mode != MC_TRAJ_MODE_FILTER) {
        return MC_TRAJ_ERR_MODE;
    }
    t->fr_rad = r_rad;
    return MC_TRAJ_ERR_NONE;
}

uint32_t mc_traj_f32_step(mc_traj_f32_t *t, mc_traj_f32_out_t *out)
{
    if ((t == NULL) || (out == NULL)) {
        return MC_TRAJ_ERR_NULL;
    }
    if (t->mode == MC_TRAJ_MODE_FILTER) {
        const float w = t->cfg.filter_bw_rad_s;
        const float e = t->fx_rad - t->fr_rad;
        const float v = t->fv_rad_s;
        out->x_rad = t->fx_rad;
        out->v_rad_s = v;
        out->a_rad_s2 = -(w * w * e) - (2.0f * w * v);
        out->done = false;
        t->fx_rad = t->fr_rad + (t->f11 * e) + (t->f12 * v);
        t->fv_rad_s = (t->f21 * e) + (t->f22 * v);
    } else {
        mc_traj_f32_eval(t, (float)t->k * t->cfg.dt_s, out);
        if (!out->done) {
            t->k++;
        }
    }
    t->out = *out;
    return MC_TRAJ_ERR_NONE;
}

float mc_traj_f32_get_duration_s(const mc_traj_f32_t *t)
{
    return (t == NULL) ? 0.0f : t->t_s[MC_TRAJ_SEGMENTS];
}

void mc_traj_f32_shift(mc_traj_f32_t *t, float dx_rad)
{
    if (t == NULL) {
        return;
    }
    for (unsigned i = 0u; i < MC_TRAJ_SEGMENTS; ++i) {
        t->x_s[i] -= dx_rad;
    }
    t->x_target_rad -= dx_rad;
    t->fx_rad -= dx_rad;
    t->fr_rad -= dx_rad;
    t->out.x_rad -= dx_rad;
}
