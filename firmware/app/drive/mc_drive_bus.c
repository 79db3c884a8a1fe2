/**
 * @file mc_drive_bus.c
 * @brief DC-bus current and power limits: see mc_drive_bus.h.
 */
#include "mc_drive_bus.h"

#include "math/mc_math.h"

#define BUS_NONE 3.0e38f /* no bound */

uint32_t mc_drive_bus_check(const mc_drive_bus_cfg_t *cfg)
{
    const float v[4] = {cfg->i_bus_max_a, cfg->i_bus_regen_max_a, cfg->p_bus_max_w,
                        cfg->p_bus_regen_max_w};
    uint32_t bad = 0u;
    for (unsigned k = 0u; k < 4u; ++k) {
        if (!mc_isfinite_f32(v[k]) || v[k] < 0.0f) {
            bad |= 1u << k;
        }
    }
    return bad;
}

float mc_drive_bus_estimate_a(float vd_v, float vq_v, float id_a, float iq_a, float vbus_v)
{
    const float i = 1.5f * ((vd_v * id_a) + (vq_v * iq_a)) / vbus_v;
    return (vbus_v > 0.0f && mc_isfinite_f32(i)) ? i : 0.0f;
}

bool mc_drive_bus_any(const mc_drive_bus_cfg_t *cfg)
{
    return cfg->i_bus_max_a != 0.0f || cfg->i_bus_regen_max_a != 0.0f || cfg->p_bus_max_w != 0.0f ||
           cfg->p_bus_regen_max_w != 0.0f;
}

void mc_drive_bus_off(mc_drive_bus_t *s)
{
    s->have_last = false;
    s->limiting = false;
    s->i_mot_lim_a = 0.0f;
    s->i_regen_lim_a = 0.0f;
}

void mc_drive_bus_init(mc_drive_bus_t *s, const mc_foc_f32_cfg_t *foc)
{
    const float t_loop = (foc->kp_q_v_per_a > 0.0f) ? (foc->lq_h / foc->kp_q_v_per_a) : foc->dt_s;
    const float tau = MC_DRIVE_BUS_CORR_TAU_LOOPS * t_loop;
    const mc_drive_bus_t z = {0};
    *s = z;
    s->corr_alpha = foc->dt_s / (tau + foc->dt_s);
    s->corr_fast_alpha = foc->dt_s / ((MC_DRIVE_BUS_CORR_FAST_LOOPS * t_loop) + foc->dt_s);
}

/* The two roots of a x^2 + b x + c = 0 (a > 0, disc = b^2 - 4ac >= 0),
 * in order, without cancellation. */
static void roots(float a, float b, float c, float disc, float *p_lo, float *p_hi)
{
    const float sq = mc_sqrt_f32(disc);
    const float q = -0.5f * (b + ((b < 0.0f) ? -sq : sq));
    float r1 = q / a;
    float r2 = (q != 0.0f) ? (c / q) : 0.0f;
    if (r1 > r2) {
        const float t = r1;
        r1 = r2;
        r2 = t;
    }
    *p_lo = r1;
    *p_hi = r2;
}

bool mc_drive_bus_motor_range(float a, float b, float c0, float p_max_w, float *p_lo, float *p_hi)
{
    const float c = c0 - p_max_w;
    *p_lo = -BUS_NONE;
    *p_hi = BUS_NONE;
    if (a > 0.0f) {
        const float disc = (b * b) - (4.0f * a * c);
        if (disc < 0.0f) {
            return false;
        }
        roots(a, b, c, disc, p_lo, p_hi);
        return true;
    }
    if (b > 0.0f) {
        *p_hi = -c / b;
    } else if (b < 0.0f) {
        *p_lo = -c / b;
    } else {
        return c <= 0.0f;
    }
    return true;
}

float mc_drive_bus_regen_clamp(float a, float b, float c0, float p_regen_w, float iq_a)
{
    const float c = c0 + p_regen_w;
    float r1;
    float r2;
    if (!(a > 0.0f)) {
        if (b > 0.0f) {
            r1 = -c / b;
            return (iq_a < r1) ? r1 : iq_a;
        }
        if (b < 0.0f) {
            r2 = -c / b;
            return (iq_a > r2) ? r2 : iq_a;
        }
        return iq_a;
    }
    {
        const float disc = (b * b) - (4.0f * a * c);
        if (!(disc > 0.0f)) {
            return iq_a;
        }
        roots(a, b, c, disc, &r1, &r2);
    }
    /* the band (r1, r2) brakes harder than P_r; past its far edge lies
     * plugging, which the current limit would bring back into the band */
    if (r1 >= 0.0f) {
        return (iq_a > r1) ? r1 : iq_a;
    }
    if (r2 <= 0.0f) {
        return (iq_a < r2) ? r2 : iq_a;
    }
    if (iq_a > r1 && iq_a < r2) {
        return ((iq_a - r1) < (r2 - iq_a)) ? r1 : r2;
    }
    return iq_a;
}

/* The limits in force at vbus as powers [W] (BUS_NONE: off) and in A. */
static void limits_w(mc_drive_bus_t *s, const mc_drive_bus_cfg_t *cfg, float vbus_v, float *p_m,
                     float *p_r)
{
    float m = (cfg->i_bus_max_a > 0.0f) ? (cfg->i_bus_max_a * vbus_v) : BUS_NONE;
    float r = (cfg->i_bus_regen_max_a > 0.0f) ? (cfg->i_bus_regen_max_a * vbus_v) : BUS_NONE;
    if (cfg->p_bus_max_w > 0.0f && cfg->p_bus_max_w < m) {
        m = cfg->p_bus_max_w;
    }
    if (cfg->p_bus_regen_max_w > 0.0f && cfg->p_bus_regen_max_w < r) {
        r = cfg->p_bus_regen_max_w;
    }
    s->i_mot_lim_a = (m < BUS_NONE) ? (m / vbus_v) : 0.0f;
    s->i_regen_lim_a = (r < BUS_NONE) ? (r / vbus_v) : 0.0f;
    *p_m = m;
    *p_r = r;
}

/* The correction c towards the estimate of the last step (its power
 * recorded by mc_drive_bus_limit). */
static void correct(mc_drive_bus_t *s, const mc_foc_f32_cfg_t *foc, const mc_drive_bus_in_t *in,
                    bool fresh)
{
    if (!fresh) {
        s->corr_w = 0.0f; /* the loop did not run last step: nothing to compare */
        s->corr_r_w = 0.0f;
        return;
    }
    {
        const float i2 = (in->id_a * in->id_a) + (in->iq_a * in->iq_a);
        float model = 1.5f * foc->r_ohm * i2;
        if (in->rotor_frame) {
            const float psi = foc->flux_wb + ((foc->ld_h - foc->lq_h) * in->id_a);
            model += 1.5f * in->omega_e_rad_s * psi * in->iq_a;
        }
        const float em = s->p_bus_est_w - model - s->corr_w;
        const float er = s->p_bus_est_w - model - s->corr_r_w;
        s->corr_w += ((em > 0.0f) ? s->corr_fast_alpha : s->corr_alpha) * em;
        s->corr_r_w += ((er < 0.0f) ? s->corr_fast_alpha : s->corr_alpha) * er;
        if (!mc_isfinite_f32(s->corr_w) || !mc_isfinite_f32(s->corr_r_w)) {
            s->corr_w = 0.0f;
            s->corr_r_w = 0.0f;
        }
    }
}

/* Outside the rotor's frame: both references scaled to the copper-loss
 * model's motoring limit. */
static void limit_copper(mc_drive_bus_t *s, const mc_foc_f32_cfg_t *foc, float p_m, float *p_id_a,
                         float *p_iq_a)
{
    const float q = 1.5f * foc->r_ohm * ((*p_id_a * *p_id_a) + (*p_iq_a * *p_iq_a));
    if (p_m < BUS_NONE && q > 0.0f && (q + s->corr_w) > p_m) {
        const float room = p_m - s->corr_w;
        const float k = (room > 0.0f) ? mc_sqrt_f32(room / q) : 0.0f;
        *p_id_a *= k;
        *p_iq_a *= k;
        s->limiting = true;
    }
}

/* Whether the transient bound's reference r may replace the reference
 * asked, q: where it slows the step from the current this step samples
 * (ik), or asks less current of the same sign (less loss, less of the
 * winding's energy); never more current than asked nor the other sign
 * (the steady-state clamps own those). */
static bool slew_accept(float q, float ik, float r)
{
    const bool between = ((r - q) * (r - ik)) <= 0.0f;
    const bool less = (mc_fabs_f32(r) <= mc_fabs_f32(q)) && ((r * q) >= 0.0f);
    return between || less;
}

/* The current loop's own transient, which the steady-state model p(iq)
 * does not carry: the winding's 3/2 Lq iq diq/dt while the current moves
 * at the loop's bandwidth. From the last step's measured current i0 and
 * commanded voltage vq, the current moves by d = T (vq - vq_ss(i0)) / Lq
 * a period (vq_ss = R iq + w psi_eff): this step samples about
 * ik = i0 + d, and the voltage it commands acts one period later (the
 * computation delay), from i1 = i0 + 2 d. That voltage is
 * vq_ss + kp u, u = iq* - ik (the loop's proportional action on this
 * step's error), which moves the current by g u (g = kp T / Lq) and
 * carries, at its mean current i1 + g u / 2,
 *   p(u) = p_ss(i1 + g u / 2) + 3/2 kp u (i1 + g u / 2) + c,
 * a quadratic in u held within [-P_r, P_m] as the steady state is
 * (c: each limit's correction). q: the reference so far; ab: the
 * model's a and b. */
static float limit_slew(const mc_foc_f32_cfg_t *foc, const mc_drive_bus_in_t *in, const float ab[2],
                        const float c[2], float p_m, float p_r, float q)
{
    const float a = ab[0];
    const float b = ab[1];
    const float kp = foc->kp_q_v_per_a;
    const float t_l = (foc->lq_h > 0.0f) ? (foc->dt_s / foc->lq_h) : 0.0f;
    const float d = t_l * (in->vq_v - ((foc->r_ohm * in->iq_a) + (b / 1.5f)));
    const float ik = in->iq_a + d;
    const float i1 = ik + d;
    const float h = 0.5f * kp * t_l;
    /* p(u) = A u^2 + B u + C with p_ss(i) = a i^2 + b i + a id^2 */
    const float qa = (a * h * h) + (1.5f * kp * h);
    const float qb = (((2.0f * a * i1) + b) * h) + (1.5f * kp * i1);
    const float c0 = (a * i1 * i1) + (b * i1) + (a * in->id_a * in->id_a);
    float u = q - ik;
    if (!mc_isfinite_f32(i1) || !(qa > 0.0f)) {
        return q;
    }
    if (p_m < BUS_NONE) {
        float lo;
        float hi;
        if (mc_drive_bus_motor_range(qa, qb, c0 + c[0], p_m, &lo, &hi)) {
            u = mc_sat_f32(u, lo, hi);
        } else {
            u = -qb / (2.0f * qa); /* the least power the model has */
        }
    }
    if (p_r < BUS_NONE) {
        u = mc_drive_bus_regen_clamp(qa, qb, c0 + c[1], p_r, u);
    }
    return slew_accept(q, ik, ik + u) ? (ik + u) : q;
}

void mc_drive_bus_limit(mc_drive_bus_t *s, const mc_drive_bus_cfg_t *cfg,
                        const mc_foc_f32_cfg_t *foc, const mc_drive_bus_in_t *in, float *p_id_a,
                        float *p_iq_a)
{
    float p_m;
    float p_r;
    const bool fresh = s->have_last && (in->fast_count == s->last_count + 1u);
    const float p = 1.5f * ((in->vd_v * in->id_a) + (in->vq_v * in->iq_a));
    s->p_bus_est_w = mc_isfinite_f32(p) ? p : 0.0f;
    s->vbus_v = in->vbus_v;
    s->limiting = false;
    if (!mc_drive_bus_any(cfg)) {
        mc_drive_bus_off(s); /* the correction restarts when a limit is set */
        return;
    }
    s->last_count = in->fast_count;
    s->have_last = true;
    correct(s, foc, in, fresh);
    if (!(in->vbus_v > 0.0f)) {
        s->i_mot_lim_a = 0.0f;
        s->i_regen_lim_a = 0.0f;
        return; /* no bus: the under-voltage trip's business */
    }
    limits_w(s, cfg, in->vbus_v, &p_m, &p_r);
    if (!in->rotor_frame) {
        limit_copper(s, foc, p_m, p_id_a, p_iq_a);
        return;
    }
    {
        const float id = *p_id_a;
        const float a = 1.5f * foc->r_ohm;
        const float b = 1.5f * in->omega_e_rad_s * (foc->flux_wb + ((foc->ld_h - foc->lq_h) * id));
        const float c0 = (a * id * id) + s->corr_w;
        float iq = *p_iq_a;
        if (p_m < BUS_NONE) {
            float lo;
            float hi;
            if (!mc_drive_bus_motor_range(a, b, c0, p_m, &lo, &hi)) {
                iq = 0.0f;
            } else {
                iq = mc_sat_f32(iq, lo, hi);
            }
        }
        if (p_r < BUS_NONE) {
            iq = mc_drive_bus_regen_clamp(a, b, c0 - s->corr_w + s->corr_r_w, p_r, iq);
        }
        {
            const float ab[2] = {a, b};
            const float c[2] = {s->corr_w, s->corr_r_w};
            iq = limit_slew(foc, in, ab, c, p_m, p_r, iq);
        }
        s->limiting = (iq != *p_iq_a);
        *p_iq_a = iq;
    }
}
