/**
 * @file mc_comm_cog.c
 * @brief Commissioning's anticogging calibration (see mc_comm_cog.h).
 */
#include "commission/mc_comm_cog.h"

#include <stddef.h>

#include "math/mc_math.h"

#define BIN_RAD (MC_TWO_PI_F32 / (float)MC_COG_N)

static bool cfg_valid(const mc_comm_cog_cfg_t *g)
{
    return mc_isfinite_f32(g->dt_s) && (g->dt_s > 0.0f) && mc_isfinite_f32(g->w_rad_s) &&
           (g->w_rad_s > 0.0f) && (g->w_rad_s * g->dt_s <= BIN_RAD) &&
           mc_isfinite_f32(g->t_ramp_s) && (g->t_ramp_s > 0.0f) && mc_isfinite_f32(g->t_settle_s) &&
           (g->t_settle_s >= 0.0f) && mc_isfinite_f32(g->i_bound_a) && (g->i_bound_a > 0.0f) &&
           mc_isfinite_f32(g->agree_frac) && (g->agree_frac > 0.0f) && (g->agree_frac <= 1.0f) &&
           mc_isfinite_f32(g->i_floor_a) && (g->i_floor_a >= 0.0f);
}

uint32_t mc_comm_cog_start(mc_comm_cog_t *c, const mc_comm_cog_cfg_t *cfg)
{
    if (c == NULL || cfg == NULL || !cfg_valid(cfg)) {
        return MC_COMM_COG_ERR_CFG;
    }
    c->cfg = *cfg;
    c->t_s = 0.0f;
    c->w_ref = 0.0f;
    c->travel = 0.0f;
    c->theta_prev = 0.0f;
    c->rms_cog_a = 0.0f;
    c->rms_dis_a = 0.0f;
    for (uint32_t k = 0u; k < MC_COG_N; k++) {
        c->sum[0][k] = 0.0f;
        c->sum[1][k] = 0.0f;
        c->cnt[0][k] = 0u;
        c->cnt[1][k] = 0u;
    }
    c->err = cfg->offset_known ? MC_COMM_COG_ERR_NONE : MC_COMM_COG_ERR_NO_OFFSET;
    c->phase = (c->err == 0u) ? MC_COMM_COG_RAMP_FWD : MC_COMM_COG_FAILED;
    return c->err;
}

void mc_comm_cog_abort(mc_comm_cog_t *c)
{
    c->err |= MC_COMM_COG_ERR_ABORTED;
    c->phase = MC_COMM_COG_FAILED;
    c->w_ref = 0.0f;
}

const float *mc_comm_cog_currents(const mc_comm_cog_t *c)
{
    return (c->phase == MC_COMM_COG_DONE) ? c->sum[0] : NULL;
}

/* Both directions' means per bin; the average with its mean removed into
 * sum[0]; the checks of the header. */
static uint32_t finish(mc_comm_cog_t *c)
{
    float mean[2] = {0.0f, 0.0f};
    for (uint32_t k = 0u; k < MC_COG_N; k++) {
        for (uint32_t s = 0u; s < 2u; s++) {
            if (c->cnt[s][k] == 0u) {
                return MC_COMM_COG_ERR_MEAS;
            }
            c->sum[s][k] /= (float)c->cnt[s][k];
            mean[s] += c->sum[s][k];
        }
    }
    mean[0] /= (float)MC_COG_N;
    mean[1] /= (float)MC_COG_N;
    float ss_cog = 0.0f;
    float ss_dis = 0.0f;
    for (uint32_t k = 0u; k < MC_COG_N; k++) {
        const float f = c->sum[0][k] - mean[0];
        const float r = c->sum[1][k] - mean[1];
        const float cog = 0.5f * (f + r);
        const float dis = 0.5f * (f - r);
        c->sum[0][k] = cog;
        ss_cog += cog * cog;
        ss_dis += dis * dis;
        if (mc_abs_f32(cog) > c->cfg.i_bound_a) {
            return MC_COMM_COG_ERR_AMPLITUDE;
        }
    }
    c->rms_cog_a = mc_sqrt_nonneg_f32(ss_cog / (float)MC_COG_N);
    c->rms_dis_a = mc_sqrt_nonneg_f32(ss_dis / (float)MC_COG_N);
    if (!(c->rms_dis_a <= c->cfg.agree_frac * c->rms_cog_a + c->cfg.i_floor_a)) {
        return MC_COMM_COG_ERR_DISAGREE;
    }
    return MC_COMM_COG_ERR_NONE;
}

static int32_t floor_i(float x)
{
    const int32_t i = (int32_t)x;
    return ((float)i > x) ? (i - 1) : i;
}

/* Record direction s (0 forward): for every bin centre the angle crossed
 * since the last step, the reference interpolated linearly at the centre
 * (samples placed anywhere in a bin bias its mean by up to half a bin:
 * 13 % of an order-84 term's amplitude at two samples per bin); the angle
 * covered. A step over more than MC_COMM_COG_MAX_CROSS bins leaves them
 * empty (the finish refuses MEAS). */
#define MC_COMM_COG_MAX_CROSS 4
static void record(mc_comm_cog_t *c, uint32_t s, float theta, float iq)
{
    const float per_rad = (float)MC_COG_N / MC_TWO_PI_F32;
    const float dth = mc_wrap_pi_f32(theta - c->theta_prev);
    /* u0 and u1 computed from the angles alone (the same float for the same
     * angle): the end of one step is exactly the start of the next, so a
     * bin centre on it is crossed once, never lost to rounding */
    const float u0 = c->theta_prev * per_rad;
    float u1 = theta * per_rad;
    if ((dth > 0.0f) && (u1 < u0)) {
        u1 += (float)MC_COG_N;
    } else if ((dth < 0.0f) && (u1 > u0)) {
        u1 -= (float)MC_COG_N;
    }
    /* forward: the centres j in (u0, u1]; back: in [u1, u0) */
    const int32_t j0 = (u1 >= u0) ? (floor_i(u0) + 1) : -floor_i(-u1);
    const int32_t j1 = (u1 >= u0) ? floor_i(u1) : (-floor_i(-u0) - 1);
    if ((j1 - j0) < MC_COMM_COG_MAX_CROSS && (u1 != u0)) {
        for (int32_t j = j0; j <= j1; j++) {
            const float x = ((float)j - u0) / (u1 - u0);
            const uint32_t k = (uint32_t)j & (MC_COG_N - 1u);
            if (c->cnt[s][k] < UINT8_MAX) { /* the first 255 crossings */
                c->sum[s][k] += c->iq_prev + (iq - c->iq_prev) * x;
                c->cnt[s][k]++;
            }
        }
    }
    c->travel += (s == 0u) ? dth : -dth;
}

/* Ramp from w0 to w1; at the end (and the settle) the recording begins. */
static bool ramp(mc_comm_cog_t *c, float w0, float w1)
{
    const float x = c->t_s / c->cfg.t_ramp_s;
    c->w_ref = (x >= 1.0f) ? w1 : (w0 + (w1 - w0) * x);
    return c->t_s >= (c->cfg.t_ramp_s + c->cfg.t_settle_s);
}

static void next(mc_comm_cog_t *c, mc_comm_cog_phase_t p, float theta, float iq)
{
    c->iq_prev = iq;
    c->phase = p;
    c->t_s = 0.0f;
    c->travel = 0.0f;
    c->theta_prev = theta;
}

uint32_t mc_comm_cog_step(mc_comm_cog_t *c, float theta_m_rad, float iq_ref_a, float *p_w_ref)
{
    const float w = c->cfg.w_rad_s;
    const float turn = MC_TWO_PI_F32 + (float)MC_COMM_COG_MARGIN_BINS * BIN_RAD;
    const float t_max = MC_COMM_COG_TIME_FACTOR * turn / w;
    const bool rec = (c->phase == MC_COMM_COG_REC_FWD) || (c->phase == MC_COMM_COG_REC_REV);
    if (rec && (!mc_isfinite_f32(theta_m_rad) || !mc_isfinite_f32(iq_ref_a))) {
        c->err |= MC_COMM_COG_ERR_MEAS;
        c->phase = MC_COMM_COG_FAILED;
    }
    c->t_s += c->cfg.dt_s;
    switch (c->phase) {
    case MC_COMM_COG_RAMP_FWD:
        if (ramp(c, 0.0f, w)) {
            next(c, MC_COMM_COG_REC_FWD, theta_m_rad, iq_ref_a);
        }
        break;
    case MC_COMM_COG_REC_FWD:
    case MC_COMM_COG_REC_REV: {
        const uint32_t s = (c->phase == MC_COMM_COG_REC_FWD) ? 0u : 1u;
        record(c, s, theta_m_rad, iq_ref_a);
        c->theta_prev = theta_m_rad;
        c->iq_prev = iq_ref_a;
        if (c->travel >= turn) {
            next(c, (s == 0u) ? MC_COMM_COG_RAMP_REV : MC_COMM_COG_STOP, theta_m_rad, iq_ref_a);
        } else if (c->t_s > t_max) {
            c->err |= MC_COMM_COG_ERR_BLOCKED;
            c->phase = MC_COMM_COG_FAILED;
        }
        break;
    }
    case MC_COMM_COG_RAMP_REV:
        if (ramp(c, w, -w)) {
            next(c, MC_COMM_COG_REC_REV, theta_m_rad, iq_ref_a);
        }
        break;
    case MC_COMM_COG_STOP:
        if (ramp(c, -w, 0.0f)) {
            c->err |= finish(c);
            c->phase = (c->err == 0u) ? MC_COMM_COG_DONE : MC_COMM_COG_FAILED;
        }
        break;
    default:
        break;
    }
    if (c->phase == MC_COMM_COG_FAILED || c->phase == MC_COMM_COG_DONE ||
        c->phase == MC_COMM_COG_IDLE) {
        c->w_ref = 0.0f;
    }
    *p_w_ref = c->w_ref;
    return c->err;
}
