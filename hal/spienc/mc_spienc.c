/**
 * @file mc_spienc.c
 * @brief The hold rule and helpers shared by the SPI encoders (mc_spienc.h).
 */
#include "mc_spienc.h"

#include <stddef.h>

#define DIAG_PERIOD_MIN 2u
#define DIAG_PERIOD_MAX 1000000u

bool mc_spienc_cfg_ok(const void *p_spi, uint32_t bad_reads_max, uint32_t diag_period)
{
    return (p_spi != NULL) && (bad_reads_max != 0u) && (bad_reads_max <= MC_SPIENC_BAD_READS_MAX) &&
           ((diag_period == 0u) ||
            ((diag_period >= DIAG_PERIOD_MIN) && (diag_period <= DIAG_PERIOD_MAX)));
}

void mc_spienc_hold_init(mc_spienc_hold_t *p_hold, uint32_t bad_reads_max, uint32_t cpr)
{
    if (p_hold == NULL) {
        return;
    }
    p_hold->bad_reads_max = (bad_reads_max == 0u) ? 1u : bad_reads_max;
    p_hold->cpr = cpr;
    p_hold->run = 0u;
    p_hold->code = 0u;
    p_hold->have_code = false;
    p_hold->err_last = MC_SPIENC_ERR_NONE;
    p_hold->err_seen = MC_SPIENC_ERR_NONE;
    p_hold->n_reads = 0u;
    p_hold->n_bad = 0u;
    p_hold->n_held = 0u;
}

void mc_spienc_hold_apply(mc_spienc_hold_t *p_hold, uint32_t err, bool have_angle, uint32_t code,
                          uint32_t ticks, mc_hal_encoder_sample_t *p_sample)
{
    bool valid;

    p_hold->n_reads++;
    p_hold->err_last = err;
    p_hold->err_seen |= err;
    if (err != MC_SPIENC_ERR_NONE) {
        p_hold->n_bad++;
        if (p_hold->run < MC_SPIENC_BAD_READS_MAX) {
            p_hold->run++;
        }
    } else if (have_angle && (code < p_hold->cpr)) {
        p_hold->code = code;
        p_hold->have_code = true;
        p_hold->run = 0u;
    } else {
        p_hold->n_held++;
    }
    valid = p_hold->have_code && (p_hold->run < p_hold->bad_reads_max);
    p_sample->count = p_hold->code;
    p_sample->counts_per_rev = p_hold->cpr;
    p_sample->flags = valid ? (MC_HAL_ENCODER_FLAG_VALID | MC_HAL_ENCODER_FLAG_INDEX) : 0u;
    p_sample->timestamp_ticks = ticks;
}

bool mc_spienc_even_parity(uint32_t w, uint32_t bits)
{
    uint32_t ones = 0u;
    uint32_t k;

    for (k = 0u; (k < bits) && (k < 32u); k++) {
        ones += (w >> k) & 1u;
    }
    return (ones & 1u) == 0u;
}

uint32_t mc_spienc_ticks(const mc_hal_tick_t *p_tick)
{
    uint32_t t = 0u;

    if (p_tick != NULL) {
        (void)mc_hal_tick_read(p_tick, &t);
    }
    return t;
}

const char *mc_spienc_err_name(uint32_t err_bit)
{
    switch (err_bit) {
    case MC_SPIENC_ERR_SPI:
        return "SPI transfer failed";
    case MC_SPIENC_ERR_PARITY:
        return "parity";
    case MC_SPIENC_ERR_CHIP:
        return "chip error flag";
    case MC_SPIENC_ERR_MAGNET:
        return "magnet field out of range";
    case MC_SPIENC_ERR_CORDIC:
        return "CORDIC overflow";
    case MC_SPIENC_ERR_DIAG:
        return "diagnostic word impossible (MISO stuck or chip absent)";
    case MC_SPIENC_ERR_CHIP_FRERR:
        return "chip: framing error";
    case MC_SPIENC_ERR_CHIP_INVCOMM:
        return "chip: invalid command";
    case MC_SPIENC_ERR_CHIP_PARERR:
        return "chip: command parity error";
    default:
        return NULL;
    }
}
