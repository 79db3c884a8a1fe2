/* mc_drive_thermal.c: derating and the winding model (mc_drive_thermal.h). */
#include "mc_drive_thermal.h"

#include <stddef.h>

#include "math/mc_math.h"

/* R(T) / R(T_a): copper's linear law referred to the ambient the drive's
 * resistance was measured at. */
static float r_factor(float t_c, float ambient_c)
{
    const float a = MC_DRIVE_THERMAL_ALPHA_CU_1_K;
    return (1.0f + a * (t_c - 20.0f)) / (1.0f + a * (ambient_c - 20.0f));
}

static bool pair_ok(float start_c, float end_c)
{
    if (!mc_isfinite_f32(start_c) || !mc_isfinite_f32(end_c) || start_c < 0.0f) {
        return false;
    }
    if (start_c == 0.0f && end_c == 0.0f) {
        return true; /* off */
    }
    return start_c > 0.0f && end_c > start_c;
}

static bool model_ok(const mc_drive_thermal_cfg_t *c)
{
    const float v[6] = {c->r_ohm, c->i_rated_a, c->rise_k, c->tau_w_s, c->tau_h_s, c->share};
    for (unsigned k = 0u; k < 6u; ++k) {
        if (!mc_isfinite_f32(v[k]) || !(v[k] > 0.0f)) {
            return false;
        }
    }
    return c->share < 1.0f && mc_isfinite_f32(c->ambient_c) && c->ambient_c >= -50.0f &&
           c->ambient_c <= 150.0f;
}

uint32_t mc_drive_thermal_init(mc_drive_thermal_t *th, const mc_drive_thermal_cfg_t *cfg)
{
    uint32_t err = MC_DRIVE_THERMAL_ERR_NONE;
    if (th == NULL || cfg == NULL) {
        return MC_DRIVE_THERMAL_ERR_NULL;
    }
    if (!pair_ok(cfg->fet_start_c, cfg->fet_end_c) ||
        !pair_ok(cfg->motor_start_c, cfg->motor_end_c)) {
        err |= MC_DRIVE_THERMAL_ERR_DERATE;
    }
    if (cfg->model_enable && !model_ok(cfg)) {
        err |= MC_DRIVE_THERMAL_ERR_MODEL;
    }
    if (err != MC_DRIVE_THERMAL_ERR_NONE) {
        return err;
    }
    th->cfg = *cfg;
    th->r_wh_k_w = 0.0f;
    th->r_ha_k_w = 0.0f;
    th->c_w_j_k = 0.0f;
    th->c_h_j_k = 0.0f;
    if (cfg->model_enable) {
        const float p_hot = 1.5f * cfg->i_rated_a * cfg->i_rated_a * cfg->r_ohm *
                            r_factor(cfg->ambient_c + cfg->rise_k, cfg->ambient_c);
        const float r_total = cfg->rise_k / p_hot;
        th->r_wh_k_w = cfg->share * r_total;
        th->r_ha_k_w = r_total - th->r_wh_k_w;
        th->c_w_j_k = cfg->tau_w_s / th->r_wh_k_w;
        th->c_h_j_k = cfg->tau_h_s / th->r_ha_k_w;
    }
    th->t_w_c = cfg->ambient_c;
    th->t_h_c = cfg->ambient_c;
    th->t_w_lo = 0.0f;
    th->t_h_lo = 0.0f;
    th->k = 1.0f;
    th->started = false;
    th->derating = false;
    return MC_DRIVE_THERMAL_ERR_NONE;
}

float mc_drive_thermal_factor(float t_c, float start_c, float end_c)
{
    if (!(end_c > 0.0f) || !mc_isfinite_f32(t_c) || t_c <= start_c) {
        return 1.0f;
    }
    if (t_c >= end_c) {
        return 0.0f;
    }
    return (end_c - t_c) / (end_c - start_c);
}

/* The estimate's start: the motor thermistor, else the larger of the
 * ambient and the power stage (mc_drive_thermal.h, after a power-up). */
static void model_start(mc_drive_thermal_t *th, const mc_drive_thermal_in_t *in)
{
    float t0 = th->cfg.ambient_c;
    if (in->motor_ok && mc_isfinite_f32(in->motor_c)) {
        t0 = in->motor_c;
    } else if (in->fet_ok && mc_isfinite_f32(in->fet_c) && in->fet_c > t0) {
        t0 = in->fet_c;
    }
    th->t_w_c = t0;
    th->t_h_c = t0;
    th->t_w_lo = 0.0f;
    th->t_h_lo = 0.0f;
    th->started = true;
}

/* t += dt with the rounding carried in *lo (Kahan): with a time constant of
 * minutes and a step of milliseconds an increment falls below half a float
 * ulp of the temperature kelvins before the steady state, and would stall
 * there (7 K short for 900 s at 1 ms). */
static void add_compensated(float *t, float *lo, float dt)
{
    const float y = dt - *lo;
    const float s = *t + y;
    *lo = (s - *t) - y;
    *t = s;
}

/* One backward-Euler step of the two-node network: the increments solve
 *   (C_w/h + g_wh) dw - g_wh dh = P - g_wh (T_w - T_h)
 *   -g_wh dw + (C_h/h + g_wh + g_ha) dh = g_wh (T_w - T_h) - g_ha (T_h - T_a)
 * with the loss from R at the step's start. */
static void model_step(mc_drive_thermal_t *th, float dt_s, float i_sq_a2)
{
    const mc_drive_thermal_cfg_t *c = &th->cfg;
    const float p_w = 1.5f * c->r_ohm * r_factor(th->t_w_c, c->ambient_c) * i_sq_a2;
    const float g_wh = 1.0f / th->r_wh_k_w;
    const float g_ha = 1.0f / th->r_ha_k_w;
    const float a11 = th->c_w_j_k / dt_s + g_wh;
    const float a22 = th->c_h_j_k / dt_s + g_wh + g_ha;
    const float q_wh = g_wh * (th->t_w_c - th->t_h_c);
    const float b1 = p_w - q_wh;
    const float b2 = q_wh - g_ha * (th->t_h_c - c->ambient_c);
    const float det = a11 * a22 - g_wh * g_wh;
    add_compensated(&th->t_w_c, &th->t_w_lo, (b1 * a22 + g_wh * b2) / det);
    add_compensated(&th->t_h_c, &th->t_h_lo, (a11 * b2 + g_wh * b1) / det);
}

float mc_drive_thermal_r_scale(const mc_drive_thermal_t *th)
{
    const mc_drive_thermal_cfg_t *c = &th->cfg;
    if (!c->model_enable || !c->r_follow || !th->started) {
        return 1.0f;
    }
    return r_factor(th->t_w_c, c->ambient_c);
}

/* The warning with hysteresis: on below k = 1, off when every temperature
 * is MC_DRIVE_THERMAL_HYST_K below its start. */
static bool below_release(float t_c, float start_c, float end_c)
{
    return !(end_c > 0.0f) || !mc_isfinite_f32(t_c) || t_c < start_c - MC_DRIVE_THERMAL_HYST_K;
}

float mc_drive_thermal_step(mc_drive_thermal_t *th, float dt_s, float i_sq_a2,
                            const mc_drive_thermal_in_t *in)
{
    const mc_drive_thermal_cfg_t *c = &th->cfg;
    float kw = 1.0f;
    bool w_cool = true;
    if (c->model_enable) {
        if (!th->started) {
            model_start(th, in);
        }
        if (dt_s > 0.0f && mc_isfinite_f32(i_sq_a2) && i_sq_a2 >= 0.0f) {
            model_step(th, dt_s, i_sq_a2);
        }
        kw = mc_drive_thermal_factor(th->t_w_c, c->motor_start_c, c->motor_end_c);
        w_cool = below_release(th->t_w_c, c->motor_start_c, c->motor_end_c);
    }
    const float kf =
        in->fet_ok ? mc_drive_thermal_factor(in->fet_c, c->fet_start_c, c->fet_end_c) : 1.0f;
    const float km = in->motor_ok
                         ? mc_drive_thermal_factor(in->motor_c, c->motor_start_c, c->motor_end_c)
                         : 1.0f;
    float k = (kf < km) ? kf : km;
    k = (kw < k) ? kw : k;
    th->k = k;
    if (k < 1.0f) {
        th->derating = true;
    } else if ((!in->fet_ok || below_release(in->fet_c, c->fet_start_c, c->fet_end_c)) &&
               (!in->motor_ok || below_release(in->motor_c, c->motor_start_c, c->motor_end_c)) &&
               w_cool) {
        th->derating = false;
    }
    return k;
}
