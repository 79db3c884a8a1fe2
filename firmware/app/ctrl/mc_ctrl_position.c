/**
 * @file mc_ctrl_position.c
 * @brief Position cascade plugged into the drive (see mc_ctrl_position.h).
 */
#include "mc_ctrl_position.h"

#include <stddef.h>

#include "math/mc_math.h"

static float clampf(float x, float lim)
{
    if (x > lim) {
        return lim;
    }
    if (x < -lim) {
        return -lim;
    }
    return x;
}

/* Measured position in the trajectory's frame [rad]: the turn difference
 * is a small integer (exact in float), the count a fraction of a turn. */
static float meas_rel(const mc_ctrl_pos_t *c, uint32_t count, uint32_t cpr)
{
    return ((float)(c->turns - c->base_turns) * MC_TWO_PI_F32) +
           ((float)count * (MC_TWO_PI_F32 / (float)cpr));
}

/* Move the frame to the whole turn at or below the present reference. */
static void rebase(mc_ctrl_pos_t *c)
{
    const float x = c->traj.out.x_rad;
    const float n_f = x / MC_TWO_PI_F32;
    int32_t n = (int32_t)n_f;
    if ((float)n > n_f) {
        n--; /* floor */
    }
    if (n != 0) {
        c->base_turns += n;
        mc_traj_f32_shift(&c->traj, (float)n * MC_TWO_PI_F32);
    }
}

static uint32_t ctrl_reset(void *ctx)
{
    mc_ctrl_pos_t *c = (mc_ctrl_pos_t *)ctx;
    if (c == NULL) {
        return MC_CTRL_POS_ERR_NULL;
    }
    c->have_prev = false;
    c->turns = 0;
    c->base_turns = 0;
    (void)mc_pi_f32_reset(&c->vel_pi, 0.0f);
    (void)mc_traj_f32_reset(&c->traj, 0.0f);
    c->ack_seq = c->req_seq; /* a target latched while stopped is dropped */
    return MC_CTRL_POS_ERR_NONE;
}

/* Take the latched setpoints (one writer, published by the sequence number). */
static uint32_t take_requests(mc_ctrl_pos_t *c)
{
    uint32_t err = MC_CTRL_POS_ERR_NONE;
    if (c->lim_ack != c->lim_seq) {
        c->lim_ack = c->lim_seq;
        if (mc_traj_f32_set_limits(&c->traj, c->req_v, c->req_a, c->req_d) != 0u) {
            err |= MC_CTRL_POS_ERR_TRAJ;
        }
    }
    if (c->mode_ack != c->mode_seq) {
        c->mode_ack = c->mode_seq;
        if (mc_traj_f32_set_mode(&c->traj, c->req_mode) != 0u) {
            err |= MC_CTRL_POS_ERR_TRAJ;
        }
    }
    if (c->ack_seq != c->req_seq) {
        c->ack_seq = c->req_seq;
        rebase(c);
        /* (turns - base) is small for any reachable target: exact in float */
        const float xf = ((float)(c->req_turns - c->base_turns) * MC_TWO_PI_F32) + c->req_rad;
        const uint32_t e = (c->traj.mode == MC_TRAJ_MODE_FILTER)
                               ? mc_traj_f32_set_input(&c->traj, xf)
                               : mc_traj_f32_set_target(&c->traj, xf);
        if (e != 0u) {
            err |= MC_CTRL_POS_ERR_TRAJ;
        }
    }
    return err;
}

static uint32_t ctrl_fast(void *ctx, const mc_drive_meas_t *m, mc_drive_out_t *out)
{
    mc_ctrl_pos_t *c = (mc_ctrl_pos_t *)ctx;
    if ((c == NULL) || (m == NULL) || (out == NULL)) {
        return MC_CTRL_POS_ERR_NULL;
    }
    if (!m->have_encoder || (m->enc_cpr == 0u) || !(m->vbus_v > 0.0f) ||
        !mc_isfinite_f32(m->omega_m_rad_s)) {
        return MC_CTRL_POS_ERR_MEAS;
    }
    const uint32_t cpr = m->enc_cpr;
    const uint32_t count = (m->enc_count < cpr) ? m->enc_count : (m->enc_count % cpr);
    if (!c->have_prev) {
        /* enable: turn 0, the reference at rest where the rotor is */
        c->have_prev = true;
        c->turns = 0;
        c->base_turns = 0;
        (void)mc_traj_f32_reset(&c->traj, meas_rel(c, count, cpr));
    } else if ((count < c->count_prev) && ((c->count_prev - count) > (cpr / 2u))) {
        c->turns++; /* wrapped forward */
    } else if ((count > c->count_prev) && ((count - c->count_prev) > (cpr / 2u))) {
        c->turns--; /* wrapped backward */
    } else {
        /* within the turn */
    }
    c->count_prev = count;

    uint32_t err = take_requests(c);
    /* Torque feed-forward from the trajectory's acceleration ff_lead_s
     * ahead (exact evaluation): the current loop and the PWM delay make the
     * torque lag its reference by about that long. */
    float a_ff = 0.0f;
    const bool trap = (c->traj.mode == MC_TRAJ_MODE_TRAP);
    if (trap) {
        mc_traj_f32_out_t ahead;
        mc_traj_f32_eval(&c->traj, ((float)c->traj.k * c->traj.cfg.dt_s) + c->cfg.ff_lead_s,
                         &ahead);
        a_ff = ahead.a_rad_s2;
    }
    mc_traj_f32_out_t r;
    (void)mc_traj_f32_step(&c->traj, &r);
    if (!trap) {
        a_ff = r.a_rad_s2;
    }

    const float x = meas_rel(c, count, cpr);
    const float e_pos = r.x_rad - x;
    const float w_cmd = clampf(r.v_rad_s + (c->cfg.pos_kp_per_s * e_pos), c->cfg.vel_limit_rad_s);
    const float ff = ((c->cfg.j_kgm2 * a_ff) + (c->cfg.b_nm_s_rad * r.v_rad_s)) / c->cfg.kt_nm_a;
    /* the drive's current limit in force: the output saturates there and
     * the integrator with it (a lower limit set at run time included) */
    const float lim = (m->i_max_a < c->cfg.iq_max_a) ? m->i_max_a : c->cfg.iq_max_a;
    float iq_ref = 0.0f;
    if (m->regen_scale < 1.0f) {
        (void)mc_pi_f32_track(&c->vel_pi, m->iq_applied_a); /* the regen limit cut it */
    }
    if (mc_pi_f32_step_lim(&c->vel_pi, w_cmd - m->omega_m_rad_s, ff, -lim, lim, &iq_ref) !=
        MC_PI_ERR_NONE) {
        err |= MC_CTRL_POS_ERR_MEAS;
    }
    /* the drive's current loop at the encoder's angle */
    out->id_ref_a = 0.0f;
    out->iq_ref_a = iq_ref;
    out->theta_e_rad = m->theta_e_rad;
    out->omega_e_rad_s = m->omega_m_rad_s * (float)c->cfg.pole_pairs;
    out->rotor_frame = true;
    out->reframe = false;

    c->tm.turns = c->turns;
    c->tm.count = count;
    c->tm.theta_m_rad =
        ((float)c->turns * MC_TWO_PI_F32) + ((float)count * (MC_TWO_PI_F32 / (float)cpr));
    c->tm.theta_ref_rad = ((float)c->base_turns * MC_TWO_PI_F32) + r.x_rad;
    c->tm.pos_err_rad = e_pos;
    c->tm.omega_ref_rad_s = r.v_rad_s;
    c->tm.alpha_ref_rad_s2 = r.a_rad_s2;
    c->tm.omega_cmd_rad_s = w_cmd;
    c->tm.iq_ref_a = iq_ref;
    c->tm.done = r.done;
    return err;
}

static uint32_t ctrl_stop(void *ctx, float decel_rad_s2)
{
    mc_ctrl_pos_t *c = (mc_ctrl_pos_t *)ctx;
    if (c == NULL) {
        return MC_CTRL_POS_ERR_NULL;
    }
    c->ack_seq = c->req_seq; /* a pending target no longer applies */
    return (mc_traj_f32_stop(&c->traj, decel_rad_s2) == 0u) ? MC_CTRL_POS_ERR_NONE
                                                            : MC_CTRL_POS_ERR_REF;
}

/* A trapezoid, or the input filter when it has a bandwidth. */
static bool input_mode_ok(const mc_ctrl_pos_cfg_t *cfg, mc_traj_mode_t mode)
{
    return (mode == MC_TRAJ_MODE_TRAP) ||
           ((mode == MC_TRAJ_MODE_FILTER) && (cfg->traj.filter_bw_rad_s > 0.0f));
}

static bool nonneg_finite(float x)
{
    return mc_isfinite_f32(x) && (x >= 0.0f);
}

uint32_t mc_ctrl_pos_init(mc_ctrl_pos_t *c, const mc_ctrl_pos_cfg_t *cfg)
{
    if ((c == NULL) || (cfg == NULL)) {
        return MC_CTRL_POS_ERR_NULL;
    }
    uint32_t err = MC_CTRL_POS_ERR_NONE;
    mc_traj_f32_t traj;
    if (mc_traj_f32_init(&traj, &cfg->traj) != MC_TRAJ_ERR_NONE) {
        err |= MC_CTRL_POS_ERR_TRAJ;
    }
    if (!nonneg_finite(cfg->pos_kp_per_s) || !nonneg_finite(cfg->vel_kp_a_s_rad) ||
        !nonneg_finite(cfg->vel_ki_a_rad) || !nonneg_finite(cfg->ff_lead_s) ||
        !(cfg->ff_lead_s <= 0.1f) || !(cfg->pos_kp_per_s * cfg->dt_s <= 1.0f) ||
        !mc_isfinite_f32(cfg->dt_s) || !(cfg->dt_s > 0.0f)) {
        err |= MC_CTRL_POS_ERR_GAIN;
    }
    if (!(mc_isfinite_f32(cfg->vel_limit_rad_s) && (cfg->vel_limit_rad_s > 0.0f)) ||
        !(mc_isfinite_f32(cfg->iq_max_a) && (cfg->iq_max_a > 0.0f)) ||
        !(mc_isfinite_f32(cfg->kt_nm_a) && (cfg->kt_nm_a > 0.0f)) || !nonneg_finite(cfg->j_kgm2) ||
        !nonneg_finite(cfg->b_nm_s_rad) || (cfg->pole_pairs == 0u)) {
        err |= MC_CTRL_POS_ERR_LIMIT;
    }
    if (!input_mode_ok(cfg, cfg->input_mode)) {
        err |= MC_CTRL_POS_ERR_TRAJ;
    }
    mc_pi_f32_t pi;
    if ((err & (MC_CTRL_POS_ERR_GAIN | MC_CTRL_POS_ERR_LIMIT)) == 0u) {
        mc_pi_f32_cfg_t pc;
        pc.kp = cfg->vel_kp_a_s_rad;
        pc.ki_per_s = cfg->vel_ki_a_rad;
        pc.dt_s = cfg->dt_s;
        pc.out_min = -cfg->iq_max_a;
        pc.out_max = cfg->iq_max_a;
        pc.aw = MC_PI_AW_CLAMP;
        pc.kaw_per_s = 0.0f;
        if (mc_pi_f32_init(&pi, &pc) != MC_PI_ERR_NONE) {
            err |= MC_CTRL_POS_ERR_GAIN;
        }
    }
    if (err != MC_CTRL_POS_ERR_NONE) {
        return err;
    }
    const mc_ctrl_pos_tm_t tm0 = {0};
    c->cfg = *cfg;
    c->vel_pi = pi;
    c->traj = traj;
    c->have_prev = false;
    c->count_prev = 0u;
    c->turns = 0;
    c->base_turns = 0;
    c->req_seq = 0u;
    c->ack_seq = 0u;
    c->req_turns = 0;
    c->req_rad = 0.0f;
    c->req_mode = cfg->input_mode;
    c->req_v = cfg->traj.v_max_rad_s;
    c->req_a = cfg->traj.a_max_rad_s2;
    c->req_d = cfg->traj.d_max_rad_s2;
    c->lim_seq = 0u;
    c->lim_ack = 0u;
    c->mode_seq = (cfg->input_mode != MC_TRAJ_MODE_TRAP) ? 1u : 0u; /* taken at the first step */
    c->mode_ack = 0u;
    c->tm = tm0;
    c->ops = (mc_drive_ctrl_t){.outputs = MC_DRIVE_OUT_CURRENT,
                               .needs_encoder = true,
                               .reset = ctrl_reset,
                               .fast = ctrl_fast,
                               .stop = ctrl_stop,
                               .ctx = c,
                               .cogging_ff = true};
    return MC_CTRL_POS_ERR_NONE;
}

const mc_drive_ctrl_t *mc_ctrl_pos_ops(mc_ctrl_pos_t *c)
{
    return (c == NULL) ? NULL : &c->ops;
}

uint32_t mc_ctrl_pos_set_target(mc_ctrl_pos_t *c, int32_t turns, float rad)
{
    if (c == NULL) {
        return MC_CTRL_POS_ERR_NULL;
    }
    if (!mc_isfinite_f32(rad)) {
        return MC_CTRL_POS_ERR_REF;
    }
    /* whole turns of rad into turns: the fraction stays in [0, 2 pi) */
    const float n_f = rad / MC_TWO_PI_F32;
    if (!(n_f < 2.0e9f) || !(n_f > -2.0e9f)) {
        return MC_CTRL_POS_ERR_REF;
    }
    int32_t n = (int32_t)n_f;
    if ((float)n > n_f) {
        n--;
    }
    c->req_turns = turns + n;
    c->req_rad = rad - ((float)n * MC_TWO_PI_F32);
    c->req_seq++;
    return MC_CTRL_POS_ERR_NONE;
}

uint32_t mc_ctrl_pos_set_target_rad(mc_ctrl_pos_t *c, float theta_rad)
{
    return mc_ctrl_pos_set_target(c, 0, theta_rad);
}

uint32_t mc_ctrl_pos_set_input_mode(mc_ctrl_pos_t *c, mc_traj_mode_t mode)
{
    if (c == NULL) {
        return MC_CTRL_POS_ERR_NULL;
    }
    if (!input_mode_ok(&c->cfg, mode)) {
        return MC_CTRL_POS_ERR_REF;
    }
    c->req_mode = mode;
    c->mode_seq++;
    return MC_CTRL_POS_ERR_NONE;
}

uint32_t mc_ctrl_pos_set_limits(mc_ctrl_pos_t *c, float v_max_rad_s, float a_max_rad_s2,
                                float d_max_rad_s2)
{
    if (c == NULL) {
        return MC_CTRL_POS_ERR_NULL;
    }
    mc_traj_f32_t probe = c->traj;
    if (mc_traj_f32_set_limits(&probe, v_max_rad_s, a_max_rad_s2, d_max_rad_s2) != 0u) {
        return MC_CTRL_POS_ERR_REF;
    }
    c->req_v = v_max_rad_s;
    c->req_a = a_max_rad_s2;
    c->req_d = d_max_rad_s2;
    c->lim_seq++;
    return MC_CTRL_POS_ERR_NONE;
}
