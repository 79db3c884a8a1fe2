/* mc_drive_hall.c: Hall sensors as the drive's position source (mc_drive_hall.h). */
#include "mc_drive_hall.h"

#include <errno.h>
#include <stddef.h>

#include "math/mc_math.h"

#define QUARTER (MC_DRIVE_HALL_COUNTS_E / 4u)

/* The electrical angle [0, 2 pi) as a count in the electrical turn. */
static uint32_t frac_of(float theta_e_rad)
{
    const float c = theta_e_rad * ((float)MC_DRIVE_HALL_COUNTS_E / MC_TWO_PI_F32);
    uint32_t f = (c > 0.0f) ? (uint32_t)c : 0u;
    return (f < MC_DRIVE_HALL_COUNTS_E) ? f : (MC_DRIVE_HALL_COUNTS_E - 1u);
}

/* Count the electrical turns: a wrap of the angle through 0 either way
 * (the angle moves less than a sector per sample). */
static void count_turns(mc_drive_hall_t *h, uint32_t frac)
{
    if (h->have_frac) {
        if ((h->frac_prev >= 3u * QUARTER) && (frac < QUARTER)) {
            h->e_turn = (h->e_turn + 1u < h->pole_pairs) ? h->e_turn + 1u : 0u;
        } else if ((h->frac_prev < QUARTER) && (frac >= 3u * QUARTER)) {
            h->e_turn = (h->e_turn > 0u) ? h->e_turn - 1u : h->pole_pairs - 1u;
        } else {
            /* within the turn */
        }
    }
    h->frac_prev = frac;
    h->have_frac = true;
}

static int hall_read(void *ctx, mc_hal_encoder_sample_t *p_sample)
{
    mc_drive_hall_t *h = (mc_drive_hall_t *)ctx;
    uint32_t code = 0u;
    uint32_t ticks = 0u;
    mc_hall_f32_out_t out;
    if (mc_hal_hall_read(h->hall, &code) != 0) {
        return -EIO;
    }
    (void)mc_hal_tick_read(h->tick, &ticks);
    h->code = code;
    const uint32_t err = mc_hall_f32_step(&h->k, code, &out);
    const uint32_t bad = err & (MC_HALL_ERR_ILLEGAL | MC_HALL_ERR_SEQUENCE);
    h->error |= bad;
    /* below omega_min: the middle of the sector (within 30 degrees el.
     * either way, whichever way the rotor came) */
    const float theta =
        out.interpolating
            ? out.theta_e_rad
            : mc_wrap_2pi_f32(h->k.start_rad[out.sector] + (0.5f * h->k.width_rad[out.sector]));
    const uint32_t frac = frac_of(theta);
    if (bad == 0u) {
        count_turns(h, frac);
    }
    p_sample->count = (h->e_turn * MC_DRIVE_HALL_COUNTS_E) + h->frac_prev;
    p_sample->counts_per_rev = h->pole_pairs * MC_DRIVE_HALL_COUNTS_E;
    p_sample->flags = (bad == 0u) ? MC_HAL_ENCODER_FLAG_ALL : 0u;
    p_sample->timestamp_ticks = ticks;
    return 0;
}

uint32_t mc_drive_hall_init(mc_drive_hall_t *h, const mc_drive_hall_cfg_t *cfg,
                            const mc_hal_hall_t *hall, const mc_hal_tick_t *tick)
{
    mc_hall_f32_t k;
    if ((h == NULL) || (cfg == NULL) || (hall == NULL)) {
        return MC_DRIVE_HALL_ERR_NULL;
    }
    if ((cfg->pole_pairs == 0u) || (cfg->pole_pairs > 65535u)) {
        return MC_DRIVE_HALL_ERR_POLES;
    }
    if (mc_hall_f32_init(&k, &cfg->table) != MC_HALL_ERR_NONE) {
        return MC_DRIVE_HALL_ERR_CFG;
    }
    h->k = k;
    h->hall = hall;
    h->tick = tick;
    h->ops.read = hall_read;
    h->dev.ops = &h->ops;
    h->dev.ctx = h;
    h->pole_pairs = cfg->pole_pairs;
    h->e_turn = 0u;
    h->frac_prev = 0u;
    h->error = 0u;
    h->code = 0u;
    h->have_frac = false;
    return MC_DRIVE_HALL_ERR_NONE;
}

const mc_hal_encoder_t *mc_drive_hall_encoder(mc_drive_hall_t *h)
{
    return (h != NULL) ? &h->dev : NULL;
}
