/**
 * @file mc_ctrl_align.c
 * @brief Power-up alignment and index search (see mc_ctrl_align.h).
 */
#include "mc_ctrl_align.h"

#include <stddef.h>

#include "math/mc_math.h"

#define T_MIN_S           1.0e-3f
#define T_MAX_S           5.0f
#define T_TIMEOUT_MAX_S   60.0f
#define SWEEP_SPEED_MAX   1000.0f /* rad/s el. */
#define SEARCH_SPEED_MAX  2000.0f /* rad/s el. */
#define FOLLOW_LAG_E_RAD  (1.5f * MC_PI_F32)
#define TRAVEL_MARGIN     1.25f
#define ALIGN_TRAVEL_MAX  (4.0f * MC_PI_F32)
#define SEARCH_TRAVEL_MAX (20.0f * MC_PI_F32)

/* ---- the vector and the rotor's travel (both laws) ---------------------- */

static bool finite_in(float x, float lo, float hi)
{
    return mc_isfinite_f32(x) && (x >= lo) && (x <= hi);
}

static uint32_t periods(float t_s, float dt_s)
{
    return (uint32_t)((t_s / dt_s) + 0.5f);
}

static void vec_reset(mc_ctrl_align_vec_t *v)
{
    (void)mc_foc_f32_reset(&v->foc);
    v->theta_cmd_e_rad = 0.0f;
    v->cmd_travel_e_rad = 0.0f;
    v->i_cmd_a = 0.0f;
    v->iq_cmd_a = 0.0f;
    v->have_pos = false;
    v->theta_m_prev_rad = 0.0f;
    v->theta_m0_rad = 0.0f;
    v->travel_m_rad = 0.0f;
    v->foc_err = 0u;
}

/* The measurement checked and the rotor's travel unwrapped (the drive
 * reads far faster than half a turn per period). */
static uint32_t vec_measure(mc_ctrl_align_vec_t *v, const mc_drive_meas_t *m)
{
    if (!m->have_encoder || !(m->vbus_v > 0.0f) || !mc_isfinite_f32(m->theta_m_rad) ||
        !mc_isfinite_f32(m->omega_m_rad_s)) {
        return MC_CTRL_ALIGN_ERR_MEAS;
    }
    if (!v->have_pos) {
        v->have_pos = true;
        v->theta_m0_rad = m->theta_m_rad;
    } else {
        v->travel_m_rad += mc_wrap_pi_f32(m->theta_m_rad - v->theta_m_prev_rad);
    }
    v->theta_m_prev_rad = m->theta_m_rad;
    return MC_CTRL_ALIGN_ERR_NONE;
}

/* Turn the vector by d [rad el.]. */
static void vec_turn(mc_ctrl_align_vec_t *v, float d_e_rad)
{
    v->cmd_travel_e_rad += d_e_rad;
    v->theta_cmd_e_rad = mc_wrap_2pi_f32(v->theta_cmd_e_rad + d_e_rad);
}

/* The current loop at the vector's angle: id = i_cmd, iq = 0. */
static uint32_t vec_output(mc_ctrl_align_vec_t *v, const mc_drive_meas_t *m, mc_drive_out_t *out)
{
    mc_foc_f32_in_t in;
    mc_foc_f32_out_t fo;
    uint32_t ferr;

    in.ia_a = m->ia_a;
    in.ib_a = m->ib_a;
    in.ic_a = m->ic_a;
    in.three_phase = false;
    in.theta_e_rad = v->theta_cmd_e_rad;
    in.omega_e_rad_s = 0.0f;
    in.vbus_v = m->vbus_v;
    in.id_ref_a = v->i_cmd_a;
    in.iq_ref_a = v->iq_cmd_a;
    ferr = mc_foc_f32_step(&v->foc, &in, &fo);
    out->duty_a = fo.duty_a;
    out->duty_b = fo.duty_b;
    out->duty_c = fo.duty_c;
    out->duty2_a = 0.0f;
    out->duty2_b = 0.0f;
    if (ferr != MC_FOC_ERR_NONE) {
        v->foc_err = ferr;
        return MC_CTRL_ALIGN_ERR_FOC;
    }
    return MC_CTRL_ALIGN_ERR_NONE;
}

/* The damping current for a speed error (0 with no vector). */
static void vec_damp(mc_ctrl_align_vec_t *v, float omega_err_m_rad_s)
{
    const float i2 = (v->i_max_a * v->i_max_a) - (v->i_cmd_a * v->i_cmd_a);
    const float lim = (i2 > 0.0f) ? mc_sqrt_f32(i2) : 0.0f;
    const float iq = (v->i_cmd_a > 0.0f) ? (-v->damping_a_s_rad * omega_err_m_rad_s) : 0.0f;
    v->iq_max_a = lim;
    v->iq_cmd_a = mc_sat_f32(iq, -lim, lim);
}

/* The vector's part of init. */
static void vec_setup(mc_ctrl_align_vec_t *v, const mc_foc_f32_t *foc, float damping_a_s_rad,
                      float i_max_a)
{
    v->foc = *foc;
    v->damping_a_s_rad = damping_a_s_rad;
    v->i_max_a = i_max_a;
}

/* A failed law: no current, its failure returned every period. */
static uint32_t vec_off(mc_ctrl_align_vec_t *v, const mc_drive_meas_t *m, mc_drive_out_t *out,
                        uint32_t fail)
{
    v->i_cmd_a = 0.0f;
    v->iq_cmd_a = 0.0f;
    (void)vec_output(v, m, out);
    return fail;
}

/* The drive's table of a law (3-phase bridge, encoder needed). */
static mc_drive_ctrl_t
plugin_ops(uint32_t (*reset)(void *ctx),
           uint32_t (*fast)(void *ctx, const mc_drive_meas_t *m, mc_drive_out_t *out), void *ctx)
{
    return (mc_drive_ctrl_t){.outputs = MC_DRIVE_OUT_PWM3,
                             .needs_encoder = true,
                             .finds_angle = true,
                             .reset = reset,
                             .fast = fast,
                             .slow = NULL,
                             .ctx = ctx,
                             .stop = NULL};
}

/* A linear ramp of the magnitude from i0 to i1 over n periods; true at its end. */
static bool vec_ramp(mc_ctrl_align_vec_t *v, float i0, float i1, uint32_t k, uint32_t n)
{
    const float f = (k >= n) ? 1.0f : ((float)k / (float)n);
    v->i_cmd_a = i0 + ((i1 - i0) * f);
    return k >= n;
}

/* ---- power-up alignment -------------------------------------------------- */

enum {
    AL_RAMP = 0,
    AL_SETTLE_0,
    AL_SWEEP_A,
    AL_SETTLE_A,
    AL_SWEEP_B,
    AL_SETTLE_B,
    AL_SWEEP_C_OUT,
    AL_SWEEP_C_BACK,
    AL_SETTLE_C,
    AL_HALVE,
    AL_SETTLE_D,
    AL_RELEASE,
    AL_DONE,
    AL_FAILED
};

static void al_next(mc_ctrl_align_t *c, uint32_t phase)
{
    c->phase = phase;
    c->n_phase = 0u;
    c->n_still = 0u;
    c->win_lo_m_rad = 0.0f;
    c->win_hi_m_rad = 0.0f;
}

static uint32_t al_fail(mc_ctrl_align_t *c, uint32_t why)
{
    c->res.status = MC_CTRL_ALIGN_FAILED;
    c->res.fail = why;
    c->v.i_cmd_a = 0.0f;
    c->v.iq_cmd_a = 0.0f;
    al_next(c, AL_FAILED);
    return why;
}

/* At rest long enough (the angle inside still_band for n_settle periods):
 * true; too long without: the failure. */
static uint32_t al_settle(mc_ctrl_align_t *c, bool *p_done)
{
    const float pos = c->v.travel_m_rad;
    if (c->n_still == 0u) {
        c->win_lo_m_rad = pos;
        c->win_hi_m_rad = pos;
    }
    c->win_lo_m_rad = (pos < c->win_lo_m_rad) ? pos : c->win_lo_m_rad;
    c->win_hi_m_rad = (pos > c->win_hi_m_rad) ? pos : c->win_hi_m_rad;
    if ((c->win_hi_m_rad - c->win_lo_m_rad) > c->cfg.still_band_m_rad) {
        c->n_still = 0u; /* moved: a new window from here */
    } else {
        c->n_still++;
    }
    *p_done = (c->n_still >= c->n_settle);
    if (!*p_done && (c->n_phase > c->n_timeout)) {
        return MC_CTRL_ALIGN_ERR_NOT_SETTLED;
    }
    return MC_CTRL_ALIGN_ERR_NONE;
}

/* The vector turned towards target (commanded travel) at the sweep speed;
 * true once there. */
static bool al_sweep(mc_ctrl_align_t *c)
{
    const float step = c->cfg.omega_sweep_e_rad_s * c->cfg.foc.dt_s;
    const float rest = c->target_e_rad - c->v.cmd_travel_e_rad;
    if (mc_fabs_f32(rest) <= step) {
        vec_turn(&c->v, rest);
        return true;
    }
    vec_turn(&c->v, (rest > 0.0f) ? step : -step);
    return false;
}

static float al_pos_e(const mc_ctrl_align_t *c)
{
    return (float)c->cfg.pole_pairs * c->v.travel_m_rad;
}

/* The rotor left the vector (MC_CTRL_ALIGN_ERR_SLIP), or moved against
 * its turn (MC_CTRL_ALIGN_ERR_DIRECTION: the encoder counts the other way);
 * 0 while it follows. */
static uint32_t al_following(const mc_ctrl_align_t *c)
{
    const float pos = al_pos_e(c);
    float turned;
    float moved;

    if ((c->phase == AL_RAMP) || (c->phase == AL_SETTLE_0)) {
        return (mc_fabs_f32(pos) > (1.5f * MC_PI_F32)) ? MC_CTRL_ALIGN_ERR_SLIP
                                                       : MC_CTRL_ALIGN_ERR_NONE;
    }
    turned = c->v.cmd_travel_e_rad - c->cmd_0;
    moved = pos - c->p_0;
    if (mc_fabs_f32(moved - turned) <= (0.5f * MC_PI_F32)) {
        return MC_CTRL_ALIGN_ERR_NONE;
    }
    return ((moved * turned) < 0.0f) ? MC_CTRL_ALIGN_ERR_DIRECTION : MC_CTRL_ALIGN_ERR_SLIP;
}

/* The offset from the two approaches of a0 + s. */
static void al_result(mc_ctrl_align_t *c)
{
    const float pp = (float)c->cfg.pole_pairs;
    const float rotor_e = (pp * c->v.theta_m0_rad) + (0.5f * (c->p_b + c->p_c));
    c->res.offset_e_rad = mc_wrap_2pi_f32(c->cfg.sweep_e_rad - rotor_e);
}

/* The settle phases: each records its position and moves on. */
static uint32_t al_step_settle(mc_ctrl_align_t *c)
{
    bool done = false;
    const uint32_t e = al_settle(c, &done);
    const float pos = al_pos_e(c);

    if (e != MC_CTRL_ALIGN_ERR_NONE) {
        return al_fail(c, e);
    }
    if (!done) {
        return MC_CTRL_ALIGN_ERR_NONE;
    }
    if (c->phase == AL_SETTLE_0) {
        c->p_0 = pos;
        c->cmd_0 = c->v.cmd_travel_e_rad;
        c->target_e_rad = 0.0f;
        al_next(c, AL_SWEEP_A);
    } else if (c->phase == AL_SETTLE_A) {
        c->p_a = pos;
        c->target_e_rad = c->cfg.sweep_e_rad;
        al_next(c, AL_SWEEP_B);
    } else if (c->phase == AL_SETTLE_B) {
        c->p_b = pos;
        c->res.sweep_e_rad = c->p_b - c->p_a;
        if (mc_fabs_f32(c->res.sweep_e_rad - c->cfg.sweep_e_rad) > c->cfg.sweep_tol_e_rad) {
            return al_fail(c, MC_CTRL_ALIGN_ERR_DIRECTION);
        }
        c->target_e_rad = 2.0f * c->cfg.sweep_e_rad;
        al_next(c, AL_SWEEP_C_OUT);
    } else if (c->phase == AL_SETTLE_C) {
        c->p_c = pos;
        c->res.hysteresis_e_rad = 0.5f * (c->p_c - c->p_b);
        al_next(c, AL_HALVE);
    } else { /* AL_SETTLE_D */
        c->p_d = pos;
        c->res.load_shift_e_rad = c->p_d - c->p_c;
        if (mc_fabs_f32(c->res.load_shift_e_rad) > c->cfg.load_tol_e_rad) {
            return al_fail(c, MC_CTRL_ALIGN_ERR_LOAD);
        }
        al_result(c);
        c->i_from_a = c->v.i_cmd_a;
        al_next(c, AL_RELEASE);
    }
    return MC_CTRL_ALIGN_ERR_NONE;
}

/* One step of the sequence (after the measurement). */
static uint32_t al_sequence(mc_ctrl_align_t *c)
{
    c->n_phase++;
    switch (c->phase) {
    case AL_RAMP:
        if (vec_ramp(&c->v, 0.0f, c->cfg.i_align_a, c->n_phase, c->n_ramp)) {
            al_next(c, AL_SETTLE_0);
        }
        return MC_CTRL_ALIGN_ERR_NONE;
    case AL_SWEEP_A:
    case AL_SWEEP_B:
    case AL_SWEEP_C_BACK:
        if (al_sweep(c)) {
            al_next(c, (c->phase == AL_SWEEP_A)   ? AL_SETTLE_A
                       : (c->phase == AL_SWEEP_B) ? AL_SETTLE_B
                                                  : AL_SETTLE_C);
        }
        return MC_CTRL_ALIGN_ERR_NONE;
    case AL_SWEEP_C_OUT:
        if (al_sweep(c)) {
            c->target_e_rad = c->cfg.sweep_e_rad;
            al_next(c, AL_SWEEP_C_BACK);
        }
        return MC_CTRL_ALIGN_ERR_NONE;
    case AL_HALVE:
        if (vec_ramp(&c->v, c->cfg.i_align_a, 0.5f * c->cfg.i_align_a, c->n_phase, c->n_ramp)) {
            al_next(c, AL_SETTLE_D);
        }
        return MC_CTRL_ALIGN_ERR_NONE;
    case AL_RELEASE:
        if (vec_ramp(&c->v, c->i_from_a, 0.0f, c->n_phase, c->n_ramp)) {
            c->res.status = MC_CTRL_ALIGN_DONE;
            al_next(c, AL_DONE);
        }
        return MC_CTRL_ALIGN_ERR_NONE;
    case AL_DONE:
        return MC_CTRL_ALIGN_ERR_NONE;
    default:
        return al_step_settle(c);
    }
}

uint32_t mc_ctrl_align_fast(mc_ctrl_align_t *c, const mc_drive_meas_t *m, mc_drive_out_t *out)
{
    uint32_t e;

    if ((c == NULL) || (m == NULL) || (out == NULL)) {
        return MC_CTRL_ALIGN_ERR_NULL;
    }
    if (c->phase == AL_FAILED) {
        return vec_off(&c->v, m, out, c->res.fail);
    }
    e = vec_measure(&c->v, m);
    if (e != MC_CTRL_ALIGN_ERR_NONE) {
        return vec_off(&c->v, m, out, al_fail(c, e));
    }
    const float t = mc_fabs_f32(c->v.travel_m_rad);
    c->res.travel_peak_m_rad = (t > c->res.travel_peak_m_rad) ? t : c->res.travel_peak_m_rad;
    if (t > c->cfg.travel_max_m_rad) {
        e = al_fail(c, MC_CTRL_ALIGN_ERR_TRAVEL);
    } else if (al_following(c) != MC_CTRL_ALIGN_ERR_NONE) {
        e = al_fail(c, al_following(c));
    } else {
        e = al_sequence(c);
        vec_damp(&c->v, m->omega_m_rad_s);
    }
    const uint32_t ef = vec_output(&c->v, m, out);
    if ((e == MC_CTRL_ALIGN_ERR_NONE) && (ef != MC_CTRL_ALIGN_ERR_NONE)) {
        e = al_fail(c, ef);
    }
    return e;
}

uint32_t mc_ctrl_align_reset(mc_ctrl_align_t *c)
{
    const mc_ctrl_align_result_t r0 = {0};

    if (c == NULL) {
        return MC_CTRL_ALIGN_ERR_NULL;
    }
    vec_reset(&c->v);
    c->res = r0;
    c->res.status = MC_CTRL_ALIGN_RUNNING;
    c->i_from_a = 0.0f;
    c->target_e_rad = 0.0f;
    c->p_a = 0.0f;
    c->p_b = 0.0f;
    c->p_c = 0.0f;
    c->p_d = 0.0f;
    c->p_0 = 0.0f;
    c->cmd_0 = 0.0f;
    /* the first vector at a0 - s: the sweep to a0 moves any rotor off the
     * dead point opposite the vector before P_A is taken */
    vec_turn(&c->v, -c->cfg.sweep_e_rad);
    al_next(c, AL_RAMP);
    return MC_CTRL_ALIGN_ERR_NONE;
}

static uint32_t al_ops_reset(void *ctx)
{
    return mc_ctrl_align_reset((mc_ctrl_align_t *)ctx);
}

static uint32_t al_ops_fast(void *ctx, const mc_drive_meas_t *m, mc_drive_out_t *out)
{
    return mc_ctrl_align_fast((mc_ctrl_align_t *)ctx, m, out);
}

/* The limits and timing both laws share. */
static bool common_ok(const mc_foc_f32_cfg_t *foc, uint32_t pole_pairs, float i_max_a, float i_a,
                      float t_ramp_s)
{
    return (pole_pairs >= 1u) && finite_in(i_max_a, 1.0e-6f, 1.0e6f) &&
           finite_in(i_a, 1.0e-6f, i_max_a) && finite_in(t_ramp_s, T_MIN_S, T_MAX_S) &&
           finite_in(foc->dt_s, 1.0e-7f, 1.0e-2f);
}

static bool align_cfg_ok(const mc_ctrl_align_cfg_t *cfg)
{
    const float s = cfg->sweep_e_rad;
    const float pp = (float)cfg->pole_pairs;
    return common_ok(&cfg->foc, cfg->pole_pairs, cfg->i_max_a, cfg->i_align_a, cfg->t_ramp_s) &&
           finite_in(cfg->t_settle_s, T_MIN_S, T_MAX_S) &&
           finite_in(cfg->t_timeout_s, cfg->t_settle_s, T_TIMEOUT_MAX_S) &&
           finite_in(cfg->still_band_m_rad, 1.0e-7f, 0.1f) &&
           finite_in(s, 0.125f * MC_PI_F32, 0.5f * MC_PI_F32) &&
           finite_in(cfg->omega_sweep_e_rad_s, 1.0e-3f, SWEEP_SPEED_MAX) &&
           finite_in(cfg->sweep_tol_e_rad, 1.0e-6f, 0.5f * s) &&
           finite_in(cfg->load_tol_e_rad, 1.0e-6f, 0.25f * MC_PI_F32) &&
           finite_in(cfg->damping_a_s_rad, 0.0f, 1.0e3f) &&
           finite_in(cfg->travel_max_m_rad, TRAVEL_MARGIN * (MC_PI_F32 + (3.0f * s)) / pp,
                     ALIGN_TRAVEL_MAX);
}

uint32_t mc_ctrl_align_init(mc_ctrl_align_t *c, const mc_ctrl_align_cfg_t *cfg)
{
    mc_foc_f32_t foc;

    if ((c == NULL) || (cfg == NULL)) {
        return MC_CTRL_ALIGN_ERR_NULL;
    }
    if (!align_cfg_ok(cfg)) {
        return MC_CTRL_ALIGN_ERR_CFG;
    }
    if (mc_foc_f32_init(&foc, &cfg->foc) != MC_FOC_ERR_NONE) {
        return MC_CTRL_ALIGN_ERR_FOC;
    }
    c->cfg = *cfg;
    vec_setup(&c->v, &foc, cfg->damping_a_s_rad, cfg->i_max_a);
    c->n_ramp = periods(cfg->t_ramp_s, cfg->foc.dt_s);
    c->n_settle = periods(cfg->t_settle_s, cfg->foc.dt_s);
    c->n_timeout = periods(cfg->t_timeout_s, cfg->foc.dt_s);
    c->ops = plugin_ops(al_ops_reset, al_ops_fast, c);
    return mc_ctrl_align_reset(c);
}

const mc_drive_ctrl_t *mc_ctrl_align_ops(mc_ctrl_align_t *c)
{
    return (c == NULL) ? NULL : &c->ops;
}

uint32_t mc_ctrl_align_get_result(const mc_ctrl_align_t *c, mc_ctrl_align_result_t *p_res)
{
    if ((c == NULL) || (p_res == NULL)) {
        return MC_CTRL_ALIGN_ERR_NULL;
    }
    *p_res = c->res;
    return MC_CTRL_ALIGN_ERR_NONE;
}

/* ---- index search -------------------------------------------------------- */

enum {
    IX_RAMP = 0,
    IX_TURN,
    IX_RELEASE,
    IX_DONE,
    IX_FAILED
};

static uint32_t ix_fail(mc_ctrl_idx_t *c, uint32_t why)
{
    c->res.status = MC_CTRL_ALIGN_FAILED;
    c->res.fail = why;
    c->v.i_cmd_a = 0.0f;
    c->v.iq_cmd_a = 0.0f;
    c->phase = IX_FAILED;
    return why;
}

static void ix_found(mc_ctrl_idx_t *c)
{
    c->res.direction = c->dir;
    c->res.travel_at_index_m_rad = c->v.travel_m_rad;
    c->i_from_a = c->v.i_cmd_a;
    c->phase = IX_RELEASE;
    c->n_phase = 0u;
}

/* A new leg the other way, from where the rotor is. */
static void ix_turn_back(mc_ctrl_idx_t *c)
{
    c->dir = -c->dir;
    c->cmd_leg0_e_rad = c->v.cmd_travel_e_rad;
    c->pos_leg0_e_rad = (float)c->cfg.pole_pairs * c->v.travel_m_rad;
}

/* The vector turning: leg limits and the rotor following. */
static uint32_t ix_turn(mc_ctrl_idx_t *c)
{
    const float pp = (float)c->cfg.pole_pairs;
    const float d = (float)c->dir;
    const float cmd = d * (c->v.cmd_travel_e_rad - c->cmd_leg0_e_rad);
    const float moved = d * ((pp * c->v.travel_m_rad) - c->pos_leg0_e_rad);
    const bool first = (c->dir == c->cfg.first_direction);
    const bool blocked = (cmd > MC_TWO_PI_F32) && (moved < (cmd - FOLLOW_LAG_E_RAD));
    const bool far = (d * c->v.travel_m_rad) >= c->cfg.travel_max_m_rad;

    if (far || blocked) {
        if (!first) {
            return ix_fail(c, far ? MC_CTRL_ALIGN_ERR_NOT_FOUND : MC_CTRL_ALIGN_ERR_NO_MOTION);
        }
        ix_turn_back(c);
        return MC_CTRL_ALIGN_ERR_NONE;
    }
    vec_turn(&c->v, d * c->cfg.omega_search_e_rad_s * c->cfg.foc.dt_s);
    return MC_CTRL_ALIGN_ERR_NONE;
}

static uint32_t ix_sequence(mc_ctrl_idx_t *c, bool index)
{
    c->n_phase++;
    if (index && ((c->phase == IX_RAMP) || (c->phase == IX_TURN))) {
        ix_found(c);
    }
    switch (c->phase) {
    case IX_RAMP:
        if (vec_ramp(&c->v, 0.0f, c->cfg.i_search_a, c->n_phase, c->n_ramp)) {
            c->phase = IX_TURN;
            c->n_phase = 0u;
            c->cmd_leg0_e_rad = c->v.cmd_travel_e_rad;
            c->pos_leg0_e_rad = (float)c->cfg.pole_pairs * c->v.travel_m_rad;
        }
        return MC_CTRL_ALIGN_ERR_NONE;
    case IX_TURN:
        return ix_turn(c);
    case IX_RELEASE:
        if (vec_ramp(&c->v, c->i_from_a, 0.0f, c->n_phase, c->n_ramp)) {
            c->res.status = MC_CTRL_ALIGN_DONE;
            c->phase = IX_DONE;
        }
        return MC_CTRL_ALIGN_ERR_NONE;
    default: /* IX_DONE */
        return MC_CTRL_ALIGN_ERR_NONE;
    }
}

/* The measurement and the index flag: the travel up to the index (the
 * drive's angle jumps in the step the index appears: that step's motion is
 * not added), the sequence. */
static void ix_measure(mc_ctrl_idx_t *c, const mc_drive_meas_t *m)
{
    mc_hal_encoder_sample_t s;
    const bool searching = (c->phase == IX_RAMP) || (c->phase == IX_TURN);
    bool index;
    uint32_t e;

    if (mc_hal_encoder_read(c->cfg.p_enc, &s) != 0) {
        (void)ix_fail(c, MC_CTRL_ALIGN_ERR_ENCODER);
        return;
    }
    index = (s.flags & MC_HAL_ENCODER_FLAG_INDEX) != 0u;
    if (index && searching && c->v.have_pos) {
        c->v.have_pos = false; /* re-anchored below: the jump is not travel */
    }
    {
        const float travel = c->v.travel_m_rad;
        e = vec_measure(&c->v, m);
        c->v.travel_m_rad = (index && searching) ? travel : c->v.travel_m_rad;
    }
    if (e != MC_CTRL_ALIGN_ERR_NONE) {
        (void)ix_fail(c, e);
        return;
    }
    if (searching && (mc_fabs_f32(c->v.travel_m_rad) > c->res.travel_peak_m_rad)) {
        c->res.travel_peak_m_rad = mc_fabs_f32(c->v.travel_m_rad);
    }
    (void)ix_sequence(c, index);
    {
        /* the vector's mechanical speed while it turns */
        const float w_vec =
            (c->phase == IX_TURN)
                ? ((float)c->dir * c->cfg.omega_search_e_rad_s / (float)c->cfg.pole_pairs)
                : 0.0f;
        vec_damp(&c->v, m->omega_m_rad_s - w_vec);
    }
}

uint32_t mc_ctrl_idx_fast(mc_ctrl_idx_t *c, const mc_drive_meas_t *m, mc_drive_out_t *out)
{
    uint32_t e;

    if ((c == NULL) || (m == NULL) || (out == NULL)) {
        return MC_CTRL_ALIGN_ERR_NULL;
    }
    if (c->phase != IX_FAILED) {
        ix_measure(c, m);
    }
    if (c->phase == IX_FAILED) {
        return vec_off(&c->v, m, out, c->res.fail);
    }
    e = vec_output(&c->v, m, out);
    return (e != MC_CTRL_ALIGN_ERR_NONE) ? ix_fail(c, e) : MC_CTRL_ALIGN_ERR_NONE;
}

uint32_t mc_ctrl_idx_reset(mc_ctrl_idx_t *c)
{
    const mc_ctrl_idx_result_t r0 = {0};

    if (c == NULL) {
        return MC_CTRL_ALIGN_ERR_NULL;
    }
    vec_reset(&c->v);
    c->res = r0;
    c->res.status = MC_CTRL_ALIGN_RUNNING;
    c->phase = IX_RAMP;
    c->n_phase = 0u;
    c->dir = c->cfg.first_direction;
    c->cmd_leg0_e_rad = 0.0f;
    c->pos_leg0_e_rad = 0.0f;
    c->i_from_a = 0.0f;
    return MC_CTRL_ALIGN_ERR_NONE;
}

static uint32_t ix_ops_reset(void *ctx)
{
    return mc_ctrl_idx_reset((mc_ctrl_idx_t *)ctx);
}

static uint32_t ix_ops_fast(void *ctx, const mc_drive_meas_t *m, mc_drive_out_t *out)
{
    return mc_ctrl_idx_fast((mc_ctrl_idx_t *)ctx, m, out);
}

uint32_t mc_ctrl_idx_init(mc_ctrl_idx_t *c, const mc_ctrl_idx_cfg_t *cfg)
{
    mc_foc_f32_t foc;

    if ((c == NULL) || (cfg == NULL)) {
        return MC_CTRL_ALIGN_ERR_NULL;
    }
    if (!common_ok(&cfg->foc, cfg->pole_pairs, cfg->i_max_a, cfg->i_search_a, cfg->t_ramp_s) ||
        !finite_in(cfg->omega_search_e_rad_s, 1.0e-3f, SEARCH_SPEED_MAX) ||
        !finite_in(cfg->damping_a_s_rad, 0.0f, 1.0e3f) ||
        !finite_in(cfg->travel_max_m_rad, MC_TWO_PI_F32 / (float)cfg->pole_pairs,
                   SEARCH_TRAVEL_MAX) ||
        ((cfg->first_direction != 1) && (cfg->first_direction != -1)) || (cfg->p_enc == NULL)) {
        return MC_CTRL_ALIGN_ERR_CFG;
    }
    if (mc_foc_f32_init(&foc, &cfg->foc) != MC_FOC_ERR_NONE) {
        return MC_CTRL_ALIGN_ERR_FOC;
    }
    c->cfg = *cfg;
    vec_setup(&c->v, &foc, cfg->damping_a_s_rad, cfg->i_max_a);
    c->n_ramp = periods(cfg->t_ramp_s, cfg->foc.dt_s);
    c->ops = plugin_ops(ix_ops_reset, ix_ops_fast, c);
    return mc_ctrl_idx_reset(c);
}

const mc_drive_ctrl_t *mc_ctrl_idx_ops(mc_ctrl_idx_t *c)
{
    return (c == NULL) ? NULL : &c->ops;
}

uint32_t mc_ctrl_idx_get_result(const mc_ctrl_idx_t *c, mc_ctrl_idx_result_t *p_res)
{
    if ((c == NULL) || (p_res == NULL)) {
        return MC_CTRL_ALIGN_ERR_NULL;
    }
    *p_res = c->res;
    return MC_CTRL_ALIGN_ERR_NONE;
}
