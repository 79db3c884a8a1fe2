/**
 * @file mc_hall_q31.c
 * @brief Hall-sensor rotor angle, q31 (see mc_hall_q31.h).
 */
#include "hall/mc_hall_q31.h"

#include <stddef.h>

#include "math/mc_math.h"

#define TURN_U32_F   4294967296.0f /* 2^32 */
#define STEP_MAX_U32 0x80000000u   /* half a turn per sample */

/* Radians (a width or a band, [0, 2 pi)) to 2^-32 turn, rounded. */
static uint32_t turn_u32(float rad)
{
    const float t = rad / MC_TWO_PI_F32 * TURN_U32_F;
    if (!(t > 0.0f)) {
        return 0u;
    }
    if (t >= TURN_U32_F) {
        return 0xFFFFFFFFu;
    }
    return (uint32_t)(t + 0.5f);
}

uint32_t mc_hall_q31_init(mc_hall_q31_t *st, const mc_hall_q31_cfg_t *cfg)
{
    uint8_t map[8];
    float w[MC_HALL_SECTORS];
    mc_q46_gain_t g;
    float step_min_f;
    uint32_t k;
    uint32_t err;

    if ((st == NULL) || (cfg == NULL)) {
        return MC_HALL_ERR_NULL;
    }
    err = mc_hall_f32_validate(&cfg->f, map, w);
    if (err != MC_HALL_ERR_NONE) {
        return err;
    }
    step_min_f = cfg->f.omega_min_e_rad_s * cfg->f.dt_s / MC_TWO_PI_F32 * TURN_U32_F;
    if (!mc_isfinite_f32(cfg->omega_base_rad_s) || !(cfg->omega_base_rad_s > 0.0f) ||
        !(step_min_f >= 1.0f) || !(step_min_f < (float)STEP_MAX_U32) ||
        !mc_q46_gain_from_f32(2.0f * MC_PI_F32 / (cfg->f.dt_s * cfg->omega_base_rad_s), &g)) {
        return MC_HALL_ERR_SCALE;
    }
    st->cfg = *cfg;
    for (k = 0u; k < 8u; k++) {
        st->sector_of_code[k] = map[k];
    }
    for (k = 0u; k < MC_HALL_SECTORS; k++) {
        st->start[k] = mc_q31_angle_from_rad_f32(cfg->f.edge_e_rad[k]);
    }
    /* widths from the q31 starts: they add up to one turn exactly */
    for (k = 0u; k < MC_HALL_SECTORS; k++) {
        st->width[k] = (uint32_t)st->start[(k + 1u) % MC_HALL_SECTORS] - (uint32_t)st->start[k];
    }
    st->h2 = turn_u32(0.5f * cfg->f.hysteresis_e_rad);
    st->step_min = (uint32_t)step_min_f;
    st->omega_gain = g;
    return mc_hall_q31_reset(st);
}

uint32_t mc_hall_q31_reset(mc_hall_q31_t *st)
{
    if (st == NULL) {
        return MC_HALL_ERR_NULL;
    }
    st->seq.sector = 0u;
    st->seq.have_sector = false;
    st->seq.dir = 0;
    st->seq.have_interval = false;
    st->seq.n_since = 0u;
    st->seq.n_interval = 0u;
    st->theta_edge = 0;
    st->step_edge = 0u;
    st->theta = 0;
    st->have_theta = false;
    st->flags = MC_HALL_ERR_NONE;
    return MC_HALL_ERR_NONE;
}

/* q31 angle plus a signed distance in 2^-32 turn (wraps exactly). */
static q31_t angle_plus(q31_t a, uint32_t dist, int32_t dir)
{
    const uint32_t u = (dir > 0) ? ((uint32_t)a + dist) : ((uint32_t)a - dist);
    return (q31_t)(int32_t)u; /* two's complement (GCC: modular) */
}

static void on_edge(mc_hall_q31_t *st, int32_t dir)
{
    const uint32_t k = st->seq.sector;

    st->theta_edge = (dir > 0) ? angle_plus(st->start[k], st->h2, 1)
                               : angle_plus(st->start[(k + 1u) % MC_HALL_SECTORS], st->h2, -1);
    st->step_edge = 0u;
    if (st->seq.have_interval && (st->seq.n_interval != 0u)) {
        const uint32_t crossed = (dir > 0) ? ((k + MC_HALL_SECTORS - 1u) % MC_HALL_SECTORS)
                                           : ((k + 1u) % MC_HALL_SECTORS);
        st->step_edge = st->width[crossed] / st->seq.n_interval;
    }
}

static q31_t omega_q31(const mc_hall_q31_t *st, uint32_t step, int32_t dir)
{
    const q31_t w = mc_q46_to_q31(mc_q46_mul_q31(st->omega_gain, (q31_t)(step >> 1)));
    return (dir > 0) ? w : mc_q31_neg_sat(w);
}

uint32_t mc_hall_q31_step(mc_hall_q31_t *st, uint32_t code, mc_hall_q31_out_t *out)
{
    int32_t edge = 0;
    uint32_t err;
    uint32_t k;
    uint32_t step = 0u;
    bool interp = false;

    if ((st == NULL) || (out == NULL)) {
        return MC_HALL_ERR_NULL;
    }
    err = mc_hall_f32_step_sector(&st->seq, st->sector_of_code, code, &edge);
    st->flags |= err;
    k = st->seq.sector;
    out->sector = (uint8_t)k;
    out->edge = false;
    out->interpolating = false;
    out->omega_e = 0;
    if ((err & MC_HALL_ERR_ILLEGAL) != 0u) {
        out->theta_e = st->theta; /* held */
        return err;
    }
    if ((err & MC_HALL_ERR_SEQUENCE) != 0u) {
        st->step_edge = 0u;
        st->have_theta = false;
    }
    if (edge != 0) {
        on_edge(st, edge);
        st->have_theta = true;
    }
    if (st->step_edge != 0u) {
        const uint64_t n = st->seq.n_since;
        const uint64_t w = st->width[k];
        uint64_t travel = ((uint64_t)st->step_edge * n) + ((uint64_t)st->step_edge >> 1);
        step = st->step_edge;
        if (travel > w) {
            /* slower than at the edge: step <= 2 w / (2 n + 1) */
            step = (uint32_t)((2u * w) / ((2u * n) + 1u));
            travel = w;
        }
        interp = (step >= st->step_min);
        if (interp) {
            st->theta = angle_plus(st->theta_edge, (uint32_t)travel, st->seq.dir);
        }
    }
    if (!interp) {
        if (edge != 0) {
            st->theta = st->theta_edge;
        } else if (!st->have_theta) {
            st->theta = angle_plus(st->start[k], st->width[k] >> 1, 1);
        } else {
            /* a slowing rotor: the last angle, frozen */
        }
    } else {
        out->omega_e = omega_q31(st, step, st->seq.dir);
    }
    out->theta_e = st->theta;
    out->edge = (edge != 0);
    out->interpolating = interp;
    return err;
}
