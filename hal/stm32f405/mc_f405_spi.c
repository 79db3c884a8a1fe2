/**
 * @file mc_f405_spi.c
 * @brief spi capability (hal/spi.h) on SPI1..3 of the STM32F405: master,
 *        16-bit frames, software chip select on a GPIO. Register facts:
 *        RM0090 §28 (SPI). See mc_f405_hal.h.
 *
 * A transfer is polled (no interrupt, no DMA): a gate driver's register
 * set-up and status reads, a few frames at a time, and an absolute
 * encoder's one frame per PWM period. Sequence (RM0090 §28.3.5, "full
 * duplex, master"): restore this device's CR1 if another device on the
 * same SPI changed it; assert chip select; drop a stale received word;
 * per 16-bit word: wait TXE, write DR, wait RXNE, read DR; wait until BSY
 * clears (the last bit has left the shift register); release chip select
 * and keep it high for the configured gap.
 */
#include "mc_f405_hal.h"

#include <errno.h>
#include <stddef.h>

#define SPI_MODE_MAX 3u
#define SPI_BR_MAX   7u /* PCLK / 256 */

static void cs_drive(const mc_f405_pin_t *p_cs, bool asserted)
{
    const bool level = p_cs->active_low ? !asserted : asserted;
    p_cs->p_port->BSRR = level ? (1u << p_cs->pin) : (1u << (p_cs->pin + 16u));
}

static bool wait_flag(const mc_f405_spi_regs_t *r, uint32_t flag, bool set)
{
    uint32_t n;

    for (n = 0u; n < MC_F405_SPI_POLLS; n++) {
        if (((r->SR & flag) != 0u) == set) {
            return true;
        }
    }
    return false;
}

static void cs_release(const mc_f405_spi_t *p)
{
    uint32_t n;
    const uint32_t gap =
        (p->cfg.cs_gap_reads != 0u) ? p->cfg.cs_gap_reads : MC_F405_SPI_CS_GAP_READS;

    cs_drive(&p->cfg.cs, false);
    /* Chip select high time between frames (see MC_F405_SPI_CS_GAP_READS). */
    for (n = 0u; n < gap; n++) {
        (void)p->cfg.p_spi->SR;
    }
}

/* Claim the bus for this device: -EIO when the SPI is disabled (reset
 * behind our back, CS untouched); CR1 restored when another device on the
 * same SPI left its own settings; chip select asserted; a stale received
 * word dropped. */
static int frame_begin(const mc_f405_spi_t *p)
{
    mc_f405_spi_regs_t *r = p->cfg.p_spi;

    if ((r->CR1 & MC_F405_SPI_CR1_SPE) == 0u) {
        return -EIO;
    }
    if (r->CR1 != p->cr1) {
        r->CR1 = p->cr1 & ~MC_F405_SPI_CR1_SPE;
        r->CR1 = p->cr1;
    }
    cs_drive(&p->cfg.cs, true);
    if ((r->SR & MC_F405_SPI_SR_RXNE) != 0u) {
        (void)r->DR; /* a word left from before: not this frame's */
    }
    return 0;
}

/* One 16-bit word of a frame in progress. */
static bool word_xfer(mc_f405_spi_regs_t *r, uint16_t tx, uint16_t *p_rx)
{
    if (!wait_flag(r, MC_F405_SPI_SR_TXE, true)) {
        return false;
    }
    r->DR = tx;
    if (!wait_flag(r, MC_F405_SPI_SR_RXNE, true)) {
        return false;
    }
    *p_rx = (uint16_t)(r->DR & 0xFFFFu);
    return true;
}

/* The last bit has left the shift register, then the chip select is
 * released (either way). */
static bool frame_end(const mc_f405_spi_t *p, bool ok)
{
    const bool idle = ok && wait_flag(p->cfg.p_spi, MC_F405_SPI_SR_BSY, false);
    cs_release(p);
    return idle;
}

static int spi_transfer16(void *ctx, uint16_t tx, uint16_t *p_rx)
{
    mc_f405_spi_t *p = ctx;
    uint16_t rx = 0u;

    if (p == NULL) {
        return -EINVAL;
    }
    if (frame_begin(p) != 0) {
        return -EIO;
    }
    if (!frame_end(p, word_xfer(p->cfg.p_spi, tx, &rx))) {
        return -EIO;
    }
    if (p_rx != NULL) {
        *p_rx = rx;
    }
    return 0;
}

static int spi_transfer32(void *ctx, uint32_t tx, uint32_t *p_rx)
{
    mc_f405_spi_t *p = ctx;
    uint16_t hi = 0u;
    uint16_t lo = 0u;
    bool ok;

    if (p == NULL) {
        return -EINVAL;
    }
    if (frame_begin(p) != 0) {
        return -EIO;
    }
    ok = word_xfer(p->cfg.p_spi, (uint16_t)(tx >> 16), &hi) &&
         word_xfer(p->cfg.p_spi, (uint16_t)(tx & 0xFFFFu), &lo);
    if (!frame_end(p, ok)) {
        return -EIO;
    }
    if (p_rx != NULL) {
        *p_rx = ((uint32_t)hi << 16) | (uint32_t)lo;
    }
    return 0;
}

static const mc_hal_spi_ops_t spi_ops = {
    .transfer16 = spi_transfer16,
    .transfer32 = spi_transfer32,
};

int mc_f405_spi_init(mc_f405_spi_t *p_drv, const mc_f405_spi_config_t *p_cfg)
{
    uint32_t br;
    uint32_t cr1;
    uint32_t shift;
    mc_f405_gpio_regs_t *port;

    if ((p_drv == NULL) || (p_cfg == NULL) || (p_cfg->p_spi == NULL) ||
        (p_cfg->cs.p_port == NULL) || (p_cfg->cs.pin > 15u) || (p_cfg->pclk_hz == 0u) ||
        (p_cfg->max_sck_hz == 0u) || (p_cfg->mode > SPI_MODE_MAX)) {
        return -EINVAL;
    }
    /* Smallest divider 2^(BR + 1) with pclk / divider <= max_sck_hz. */
    for (br = 0u; br <= SPI_BR_MAX; br++) {
        if ((p_cfg->pclk_hz >> (br + 1u)) <= p_cfg->max_sck_hz) {
            break;
        }
    }
    if (br > SPI_BR_MAX) {
        return -EINVAL;
    }

    p_drv->cfg = *p_cfg;
    p_drv->sck_hz = p_cfg->pclk_hz >> (br + 1u);
    cr1 = MC_F405_SPI_CR1_MSTR | MC_F405_SPI_CR1_SSM | MC_F405_SPI_CR1_SSI | MC_F405_SPI_CR1_DFF |
          (br << MC_F405_SPI_CR1_BR_SHIFT);
    if ((p_cfg->mode & 2u) != 0u) {
        cr1 |= MC_F405_SPI_CR1_CPOL;
    }
    if ((p_cfg->mode & 1u) != 0u) {
        cr1 |= MC_F405_SPI_CR1_CPHA;
    }
    p_drv->cr1 = cr1 | MC_F405_SPI_CR1_SPE;
    p_drv->dev.ops = &spi_ops;
    p_drv->dev.ctx = p_drv;

    /* Chip select released before the pin becomes an output. */
    cs_drive(&p_cfg->cs, false);
    port = p_cfg->cs.p_port;
    shift = 2u * (uint32_t)p_cfg->cs.pin;
    port->MODER = (port->MODER & ~(3u << shift)) | (MC_F405_GPIO_MODER_OUTPUT << shift);

    /* RM0090 §28.3.3: configure with SPE = 0, then enable. */
    p_cfg->p_spi->CR1 = cr1;
    p_cfg->p_spi->CR2 = 0u;
    p_cfg->p_spi->CR1 = p_drv->cr1;
    return 0;
}
