/**
 * @file mc_ma732.c
 * @brief MA732 frames and the checked fast-loop read (mc_ma732.h).
 */
#include "mc_ma732.h"

#include <errno.h>
#include <stddef.h>

#define ADDRESS_MASK 0x1Fu
#define PARITY_BIT   (1u << 15) /* of a 32-clock frame: the 17th clock */

uint16_t mc_ma732_cmd_read(uint32_t address)
{
    return (uint16_t)(MC_MA732_CMD_READ | ((address & ADDRESS_MASK) << 8));
}

uint32_t mc_ma732_parity_bit(uint16_t word)
{
    return mc_spienc_even_parity(word, 16u) ? 0u : 1u;
}

uint32_t mc_ma732_frame32_check(uint32_t rx, uint16_t *p_word)
{
    const uint16_t word = (uint16_t)(rx >> 16);
    const uint32_t par = ((rx & PARITY_BIT) != 0u) ? 1u : 0u;

    if (par != mc_ma732_parity_bit(word)) {
        return MC_SPIENC_ERR_PARITY;
    }
    *p_word = word;
    return MC_SPIENC_ERR_NONE;
}

uint32_t mc_ma732_status_errs(uint32_t status)
{
    const uint32_t both = MC_MA732_STATUS_MGH | MC_MA732_STATUS_MGL;

    if ((status & both) == both) {
        return MC_SPIENC_ERR_DIAG; /* too strong and too weak at once */
    }
    return ((status & both) != 0u) ? MC_SPIENC_ERR_MAGNET : MC_SPIENC_ERR_NONE;
}

/* One frame: its 16-bit word, or the error (SPI, parity). */
static uint32_t frame(const mc_ma732_t *p, uint16_t mosi, uint16_t *p_word)
{
    if (p->cfg.parity) {
        uint32_t rx = 0u;
        if (mc_hal_spi_transfer32(p->cfg.p_spi, (uint32_t)mosi << 16, &rx) != 0) {
            return MC_SPIENC_ERR_SPI;
        }
        return mc_ma732_frame32_check(rx, p_word);
    }
    return (mc_hal_spi_transfer16(p->cfg.p_spi, mosi, p_word) == 0) ? MC_SPIENC_ERR_NONE
                                                                    : MC_SPIENC_ERR_SPI;
}

static int ma732_read(void *ctx, mc_hal_encoder_sample_t *p_sample)
{
    mc_ma732_t *p = ctx;
    uint16_t word = 0u;
    uint32_t err;
    bool read_reg;
    bool have_angle = false;

    if ((p == NULL) || (p_sample == NULL)) {
        return -EINVAL;
    }
    read_reg = (p->diag_latched != MC_SPIENC_ERR_NONE) ||
               ((p->cfg.diag_period != 0u) && (p->since_diag + 1u >= p->cfg.diag_period));
    p->since_diag = read_reg ? 0u : (p->since_diag + 1u);
    err = frame(p, read_reg ? mc_ma732_cmd_read(MC_MA732_REG_STATUS) : 0u, &word);
    if (err == MC_SPIENC_ERR_NONE) {
        if (p->reg_pending) {
            const uint32_t e = mc_ma732_status_errs((uint32_t)word >> 8);
            p->status = (uint8_t)(word >> 8);
            p->diag_latched = e;
            err = e;
        } else {
            have_angle = true;
        }
    }
    /* After a failed frame the chip may or may not have taken the
     * command: assume it did (the next word is then checked as a
     * register; a wrong guess costs one held read). */
    p->reg_pending = read_reg;
    if ((p->diag_latched != MC_SPIENC_ERR_NONE) && (err == MC_SPIENC_ERR_NONE)) {
        err = p->diag_latched; /* no angle is good until 0x1B is */
    }
    if (p->diag_latched != MC_SPIENC_ERR_NONE) {
        have_angle = false;
    }
    mc_spienc_hold_apply(&p->hold, err, have_angle, word, mc_spienc_ticks(p->cfg.p_tick), p_sample);
    return 0;
}

static const mc_hal_encoder_ops_t ma732_ops = {
    .read = ma732_read,
};

int mc_ma732_init(mc_ma732_t *p_drv, const mc_ma732_config_t *p_cfg)
{
    if ((p_drv == NULL) || (p_cfg == NULL) ||
        !mc_spienc_cfg_ok(p_cfg->p_spi, p_cfg->bad_reads_max, p_cfg->diag_period)) {
        return -EINVAL;
    }
    p_drv->cfg = *p_cfg;
    mc_spienc_hold_init(&p_drv->hold, p_cfg->bad_reads_max, MC_MA732_CPR);
    p_drv->reg_pending = false;
    p_drv->since_diag = 0u;
    p_drv->diag_latched = MC_SPIENC_ERR_NONE;
    p_drv->status = 0u;
    p_drv->dev.ops = &ma732_ops;
    p_drv->dev.ctx = p_drv;
    return 0;
}

int mc_ma732_probe(mc_ma732_t *p_drv)
{
    uint16_t word = 0u;
    uint32_t e;

    if (p_drv == NULL) {
        return -EINVAL;
    }
    if (p_drv->cfg.parity &&
        ((p_drv->cfg.p_spi->ops == NULL) || (p_drv->cfg.p_spi->ops->transfer32 == NULL))) {
        return -ENODEV;
    }
    p_drv->reg_pending = false;
    e = frame(p_drv, mc_ma732_cmd_read(MC_MA732_REG_STATUS), &word);
    if (e == MC_SPIENC_ERR_NONE) {
        e = frame(p_drv, 0u, &word); /* the register, then angles again */
    }
    if (e == MC_SPIENC_ERR_SPI) {
        return -EIO;
    }
    if (e != MC_SPIENC_ERR_NONE) {
        return -EPROTO;
    }
    p_drv->status = (uint8_t)(word >> 8);
    e = mc_ma732_status_errs((uint32_t)word >> 8);
    if (e == MC_SPIENC_ERR_DIAG) {
        return -EPROTO;
    }
    return (e != MC_SPIENC_ERR_NONE) ? -ERANGE : 0;
}
