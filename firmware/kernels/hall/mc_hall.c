/**
 * @file mc_hall.c
 * @brief Hall-sensor rotor angle, float32 (see mc_hall.h).
 */
#include "hall/mc_hall.h"

#include <stddef.h>

#include "math/mc_math.h"

#define SECTOR_MIN_RAD 0.17453293f /* 10 degrees */
#define SECTOR_MAX_RAD 1.9198622f  /* 110 degrees */
#define TURN_TOL_RAD   1.0e-4f     /* the widths' sum against 2 pi (float rounding) */
#define N_SAT          0xFFFFFFFFu

static uint32_t ones3(uint32_t x)
{
    return (x & 1u) + ((x >> 1) & 1u) + ((x >> 2) & 1u);
}

static bool codes_ok(const uint8_t code[MC_HALL_SECTORS], uint8_t p_sector_of_code[8])
{
    uint32_t k;

    for (k = 0u; k < 8u; k++) {
        p_sector_of_code[k] = MC_HALL_NO_SECTOR;
    }
    for (k = 0u; k < MC_HALL_SECTORS; k++) {
        const uint32_t c = code[k];
        const uint32_t next = code[(k + 1u) % MC_HALL_SECTORS];
        if ((c > 7u) || (p_sector_of_code[c] != MC_HALL_NO_SECTOR) || (next > 7u) ||
            (ones3(c ^ next) != 1u)) {
            return false;
        }
        p_sector_of_code[c] = (uint8_t)k;
    }
    return true;
}

uint32_t mc_hall_f32_validate(const mc_hall_f32_cfg_t *cfg, uint8_t p_sector_of_code[8],
                              float *p_width_rad)
{
    uint8_t map[8];
    float w[MC_HALL_SECTORS];
    float sum = 0.0f;
    float w_min = MC_TWO_PI_F32;
    uint32_t k;

    if (cfg == NULL) {
        return MC_HALL_ERR_NULL;
    }
    if (!codes_ok(cfg->code_of_sector, map) || !mc_isfinite_f32(cfg->dt_s) || !(cfg->dt_s > 0.0f) ||
        !mc_isfinite_f32(cfg->omega_min_e_rad_s) || !(cfg->omega_min_e_rad_s > 0.0f) ||
        !mc_isfinite_f32(cfg->hysteresis_e_rad) || !(cfg->hysteresis_e_rad >= 0.0f)) {
        return MC_HALL_ERR_CFG;
    }
    for (k = 0u; k < MC_HALL_SECTORS; k++) {
        const float a = cfg->edge_e_rad[k];
        const float b = cfg->edge_e_rad[(k + 1u) % MC_HALL_SECTORS];
        if (!mc_isfinite_f32(a) || !mc_isfinite_f32(b)) {
            return MC_HALL_ERR_CFG;
        }
        w[k] = mc_wrap_2pi_f32(b - a);
        if (!(w[k] >= SECTOR_MIN_RAD) || !(w[k] <= SECTOR_MAX_RAD)) {
            return MC_HALL_ERR_CFG;
        }
        w_min = (w[k] < w_min) ? w[k] : w_min;
        sum += w[k];
    }
    /* In order round one turn: the wrapped widths add up to one turn (out
     * of order they add up to two or more). */
    if (!(mc_fabs_f32(sum - MC_TWO_PI_F32) < TURN_TOL_RAD) ||
        !(cfg->hysteresis_e_rad < 0.5f * w_min)) {
        return MC_HALL_ERR_CFG;
    }
    for (k = 0u; k < 8u; k++) {
        p_sector_of_code[k] = map[k];
    }
    if (p_width_rad != NULL) {
        for (k = 0u; k < MC_HALL_SECTORS; k++) {
            p_width_rad[k] = w[k];
        }
    }
    return MC_HALL_ERR_NONE;
}

static void seq_reset(mc_hall_seq_t *seq)
{
    seq->sector = 0u;
    seq->have_sector = false;
    seq->dir = 0;
    seq->have_interval = false;
    seq->n_since = 0u;
    seq->n_interval = 0u;
}

uint32_t mc_hall_f32_init(mc_hall_f32_t *st, const mc_hall_f32_cfg_t *cfg)
{
    uint8_t map[8];
    float w[MC_HALL_SECTORS];
    uint32_t k;
    uint32_t err;

    if (st == NULL) {
        return MC_HALL_ERR_NULL;
    }
    err = mc_hall_f32_validate(cfg, map, w);
    if (err != MC_HALL_ERR_NONE) {
        return err;
    }
    st->cfg = *cfg;
    for (k = 0u; k < 8u; k++) {
        st->sector_of_code[k] = map[k];
    }
    for (k = 0u; k < MC_HALL_SECTORS; k++) {
        st->width_rad[k] = w[k];
        st->start_rad[k] = mc_wrap_2pi_f32(cfg->edge_e_rad[k]);
    }
    return mc_hall_f32_reset(st);
}

uint32_t mc_hall_f32_reset(mc_hall_f32_t *st)
{
    if (st == NULL) {
        return MC_HALL_ERR_NULL;
    }
    seq_reset(&st->seq);
    st->theta_edge_rad = 0.0f;
    st->omega_edge = 0.0f;
    st->theta_rad = 0.0f;
    st->have_theta = false;
    st->flags = MC_HALL_ERR_NONE;
    return MC_HALL_ERR_NONE;
}

uint32_t mc_hall_f32_step_sector(mc_hall_seq_t *seq, const uint8_t sector_of_code[8], uint32_t code,
                                 int32_t *p_edge)
{
    uint32_t s;
    uint32_t d;

    *p_edge = 0;
    if (seq->n_since != N_SAT) {
        seq->n_since++;
    }
    s = (code < 8u) ? sector_of_code[code] : MC_HALL_NO_SECTOR;
    if (s == MC_HALL_NO_SECTOR) {
        return MC_HALL_ERR_ILLEGAL;
    }
    if (!seq->have_sector) {
        seq->sector = (uint8_t)s;
        seq->have_sector = true;
        return MC_HALL_ERR_NONE;
    }
    if (s == seq->sector) {
        return MC_HALL_ERR_NONE;
    }
    d = (s + MC_HALL_SECTORS - seq->sector) % MC_HALL_SECTORS; /* 1..5 */
    seq->sector = (uint8_t)s;
    if ((d != 1u) && (d != (MC_HALL_SECTORS - 1u))) {
        seq->dir = 0;
        seq->have_interval = false;
        seq->n_since = 0u;
        return MC_HALL_ERR_SEQUENCE;
    }
    *p_edge = (d == 1u) ? 1 : -1;
    seq->have_interval = (seq->dir == *p_edge);
    seq->n_interval = seq->n_since;
    seq->n_since = 0u;
    seq->dir = (int8_t)*p_edge;
    return MC_HALL_ERR_NONE;
}

/* The angle an edge into sector k (direction dir) is seen at. */
static float edge_seen(const mc_hall_f32_t *st, uint32_t k, int32_t dir)
{
    const float h2 = 0.5f * st->cfg.hysteresis_e_rad;
    return (dir > 0) ? (st->start_rad[k] + h2) : (st->start_rad[(k + 1u) % MC_HALL_SECTORS] - h2);
}

static void on_edge(mc_hall_f32_t *st, int32_t dir)
{
    const uint32_t k = st->seq.sector;

    st->theta_edge_rad = edge_seen(st, k, dir);
    st->omega_edge = 0.0f;
    if (st->seq.have_interval && (st->seq.n_interval != 0u)) {
        /* the sector crossed: the one before k in the direction of motion */
        const uint32_t crossed = (dir > 0) ? ((k + MC_HALL_SECTORS - 1u) % MC_HALL_SECTORS)
                                           : ((k + 1u) % MC_HALL_SECTORS);
        st->omega_edge = st->width_rad[crossed] / ((float)st->seq.n_interval * st->cfg.dt_s);
    }
}

uint32_t mc_hall_f32_step(mc_hall_f32_t *st, uint32_t code, mc_hall_f32_out_t *out)
{
    int32_t edge = 0;
    uint32_t err;
    uint32_t k;
    float omega = 0.0f;
    bool interp = false;

    if ((st == NULL) || (out == NULL)) {
        return MC_HALL_ERR_NULL;
    }
    err = mc_hall_f32_step_sector(&st->seq, st->sector_of_code, code, &edge);
    st->flags |= err;
    k = st->seq.sector;
    if ((err & MC_HALL_ERR_ILLEGAL) != 0u) {
        out->theta_e_rad = st->theta_rad; /* held */
        out->omega_e_rad_s = 0.0f;
        out->sector = (uint8_t)k;
        out->edge = false;
        out->interpolating = false;
        return err;
    }
    if ((err & MC_HALL_ERR_SEQUENCE) != 0u) {
        st->omega_edge = 0.0f;
        st->have_theta = false; /* position known to the sector only */
    }
    if (edge != 0) {
        on_edge(st, edge);
        st->have_theta = true;
    }
    if (st->omega_edge > 0.0f) {
        /* the edge was on average half a sample before it was seen */
        const float tau = ((float)st->seq.n_since + 0.5f) * st->cfg.dt_s;
        const float w = st->width_rad[k];
        omega = (st->omega_edge * tau > w) ? (w / tau) : st->omega_edge;
        interp = (omega >= st->cfg.omega_min_e_rad_s);
        if (interp) {
            const float travel = omega * tau;
            const float dir = (st->seq.dir > 0) ? 1.0f : -1.0f;
            st->theta_rad = mc_wrap_2pi_f32(st->theta_edge_rad + (dir * travel));
        }
    }
    if (!interp) {
        omega = 0.0f;
        if (edge != 0) {
            st->theta_rad = mc_wrap_2pi_f32(st->theta_edge_rad);
        } else if (!st->have_theta) {
            st->theta_rad = mc_wrap_2pi_f32(st->start_rad[k] + (0.5f * st->width_rad[k]));
        } else {
            /* a slowing rotor: the last angle, frozen */
        }
    }
    out->theta_e_rad = st->theta_rad;
    out->omega_e_rad_s = !interp ? 0.0f : ((st->seq.dir > 0) ? omega : -omega);
    out->sector = (uint8_t)k;
    out->edge = (edge != 0);
    out->interpolating = interp;
    return err;
}
