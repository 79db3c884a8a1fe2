/**
 * @file mc_comm_hall.c
 * @brief Commissioning's Hall table (see mc_comm_hall.h).
 */
#include "commission/mc_comm_hall.h"

#include <stdbool.h>
#include <stddef.h>

#include "math/mc_math.h"

#define NO_CODE 0xFFu

void mc_comm_hall_record(mc_comm_hall_rec_t *rec, int32_t dir, uint32_t from, uint32_t to,
                         float theta_rad)
{
    uint32_t *n = (dir > 0) ? &rec->n_up : &rec->n_down;
    mc_comm_hall_event_t *ev = (dir > 0) ? rec->up : rec->down;
    rec->seen_mask |= (1u << (from & 7u)) | (1u << (to & 7u));
    if (*n >= MC_COMM_HALL_EVENTS_MAX) {
        rec->overflow++;
        return;
    }
    ev[*n].from = (uint8_t)(from & 7u);
    ev[*n].to = (uint8_t)(to & 7u);
    ev[*n].theta_rad = theta_rad;
    (*n)++;
}

static bool one_sensor(uint32_t a, uint32_t b)
{
    const uint32_t x = (a ^ b) & 7u;
    return (x == 1u) || (x == 2u) || (x == 4u);
}

/* The up cycle: succ[c] = the code after c going up. Every change one
 * sensor, no code with two successors, one cycle through six codes; every
 * change down the reverse of one up. */
static uint32_t cycle_of(const mc_comm_hall_rec_t *rec, uint8_t succ[8])
{
    uint32_t k;
    for (k = 0u; k < 8u; k++) {
        succ[k] = NO_CODE;
    }
    for (k = 0u; k < rec->n_up; k++) {
        const mc_comm_hall_event_t *e = &rec->up[k];
        if (!one_sensor(e->from, e->to)) {
            return MC_COMM_HALL_ERR_ORDER;
        }
        if (succ[e->from] != NO_CODE && succ[e->from] != e->to) {
            /* a swing back at an edge: to -> from going up is the reverse
             * of from -> to; anything else is a second successor */
            if (succ[e->to] != e->from) {
                return MC_COMM_HALL_ERR_ORDER;
            }
            continue;
        }
        if (succ[e->to] == e->from) {
            continue; /* the swing back of a change already seen */
        }
        succ[e->from] = e->to;
    }
    uint8_t c = rec->up[0].from;
    uint32_t seen = 0u;
    for (k = 0u; k < MC_HALL_SECTORS; k++) {
        if (c == NO_CODE || (seen & (1u << c)) != 0u) {
            return MC_COMM_HALL_ERR_ORDER;
        }
        seen |= 1u << c;
        c = succ[c];
    }
    if (c != rec->up[0].from) {
        return MC_COMM_HALL_ERR_ORDER;
    }
    for (k = 0u; k < rec->n_down; k++) {
        const mc_comm_hall_event_t *e = &rec->down[k];
        if (!one_sensor(e->from, e->to) || (succ[e->to] != e->from && succ[e->from] != e->to)) {
            return MC_COMM_HALL_ERR_ORDER;
        }
    }
    return MC_COMM_HALL_ERR_NONE;
}

/* Circular mean of the angles where code a changed to b in ev; false if
 * never. */
static bool mean_of(const mc_comm_hall_event_t *ev, uint32_t n, uint32_t a, uint32_t b, float *p)
{
    float s = 0.0f;
    float c = 0.0f;
    uint32_t m = 0u;
    for (uint32_t k = 0u; k < n; k++) {
        if (ev[k].from == a && ev[k].to == b) {
            float sk;
            float ck;
            mc_sincos_f32(ev[k].theta_rad, &sk, &ck);
            s += sk;
            c += ck;
            m++;
        }
    }
    if (m == 0u) {
        return false;
    }
    *p = mc_atan2_f32(s, c);
    return true;
}

/* Edge of the sector entered going up from code a to code b: the middle of
 * u (up) and d (down, b back to a); *p_diff = u - d. */
static bool edge_of(const mc_comm_hall_rec_t *rec, uint32_t a, uint32_t b, float *p_edge,
                    float *p_diff)
{
    float u;
    float d;
    if (!mean_of(rec->up, rec->n_up, a, b, &u) || !mean_of(rec->down, rec->n_down, b, a, &d)) {
        return false;
    }
    const float diff = mc_wrap_pi_f32(u - d);
    *p_edge = mc_wrap_2pi_f32(d + 0.5f * diff);
    *p_diff = diff;
    return true;
}

uint32_t mc_comm_hall_table_f32(const mc_comm_hall_rec_t *rec, mc_comm_hall_table_t *out)
{
    uint8_t succ[8];
    uint8_t code[MC_HALL_SECTORS];
    float edge[MC_HALL_SECTORS];
    float band = 0.0f;
    uint32_t k;
    if (rec == NULL || out == NULL) {
        return MC_COMM_HALL_ERR_NULL;
    }
    if ((rec->seen_mask & 0x81u) != 0u) {
        return MC_COMM_HALL_ERR_CODES; /* 000 or 111 */
    }
    uint32_t distinct = 0u;
    for (k = 1u; k < 7u; k++) {
        distinct += (rec->seen_mask >> k) & 1u;
    }
    if (distinct < MC_HALL_SECTORS) {
        return MC_COMM_HALL_ERR_CODES;
    }
    if (rec->n_up == 0u || rec->n_down == 0u) {
        return MC_COMM_HALL_ERR_MOTION;
    }
    if (rec->overflow != 0u) {
        return MC_COMM_HALL_ERR_ORDER;
    }
    const uint32_t e = cycle_of(rec, succ);
    if (e != MC_COMM_HALL_ERR_NONE) {
        return e;
    }
    /* The sectors in the up order from any code; then rotated so that
     * sector 0 begins at the smallest angle. */
    uint8_t c = rec->up[0].from;
    uint32_t first = 0u;
    for (k = 0u; k < MC_HALL_SECTORS; k++) {
        const uint8_t nx = succ[c];
        float diff;
        if (!edge_of(rec, c, nx, &edge[k], &diff)) {
            return MC_COMM_HALL_ERR_MOTION;
        }
        code[k] = nx;
        band += diff;
        first = (edge[k] < edge[first]) ? k : first;
        c = nx;
    }
    band /= (float)MC_HALL_SECTORS;
    if (band < 0.0f) {
        band = 0.0f; /* the up change seen before the down: a rotor ahead, noise */
    }
    float w_min = MC_TWO_PI_F32;
    for (k = 0u; k < MC_HALL_SECTORS; k++) {
        const float w = mc_wrap_2pi_f32(edge[(k + 1u) % MC_HALL_SECTORS] - edge[k]);
        if (!(w >= MC_COMM_HALL_WIDTH_MIN_RAD) || !(w <= MC_COMM_HALL_WIDTH_MAX_RAD)) {
            return MC_COMM_HALL_ERR_WIDTH;
        }
        w_min = (w < w_min) ? w : w_min;
    }
    if (!(band < 0.5f * w_min)) {
        return MC_COMM_HALL_ERR_WIDTH;
    }
    for (k = 0u; k < MC_HALL_SECTORS; k++) {
        const uint32_t j = (first + k) % MC_HALL_SECTORS;
        out->code_of_sector[k] = code[j];
        out->edge_e_rad[k] = edge[j];
    }
    out->hysteresis_e_rad = band;
    return MC_COMM_HALL_ERR_NONE;
}
