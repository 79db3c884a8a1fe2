/**
 * @file mc_as5047p.c
 * @brief AS5047P frames and the checked fast-loop read (mc_as5047p.h).
 */
#include "mc_as5047p.h"

#include <errno.h>
#include <stddef.h>

static uint16_t with_parity(uint32_t w15)
{
    const uint32_t w = w15 & 0x7FFFu;
    return (uint16_t)(mc_spienc_even_parity(w, 15u) ? w : (w | MC_AS5047P_PAR));
}

uint16_t mc_as5047p_cmd_read(uint16_t address)
{
    return with_parity(MC_AS5047P_READ | ((uint32_t)address & MC_AS5047P_DATA_MASK));
}

uint16_t mc_as5047p_cmd_write(uint16_t address)
{
    return with_parity((uint32_t)address & MC_AS5047P_DATA_MASK);
}

uint16_t mc_as5047p_data_write(uint16_t data)
{
    return with_parity((uint32_t)data & MC_AS5047P_DATA_MASK);
}

uint32_t mc_as5047p_frame_check(uint16_t rx, uint16_t *p_data)
{
    if (!mc_spienc_even_parity(rx, 16u)) {
        return MC_SPIENC_ERR_PARITY;
    }
    if (p_data != NULL) {
        *p_data = (uint16_t)(rx & MC_AS5047P_DATA_MASK);
    }
    return ((rx & MC_AS5047P_EF) != 0u) ? MC_SPIENC_ERR_CHIP : MC_SPIENC_ERR_NONE;
}

uint32_t mc_as5047p_errfl_errs(uint16_t errfl)
{
    uint32_t e = 0u;

    if ((errfl & MC_AS5047P_ERRFL_FRERR) != 0u) {
        e |= MC_SPIENC_ERR_CHIP_FRERR;
    }
    if ((errfl & MC_AS5047P_ERRFL_INVCOMM) != 0u) {
        e |= MC_SPIENC_ERR_CHIP_INVCOMM;
    }
    if ((errfl & MC_AS5047P_ERRFL_PARERR) != 0u) {
        e |= MC_SPIENC_ERR_CHIP_PARERR;
    }
    return e;
}

uint32_t mc_as5047p_diaagc_errs(uint16_t diaagc)
{
    uint32_t e = 0u;

    if ((diaagc & (MC_AS5047P_DIAAGC_MAGL | MC_AS5047P_DIAAGC_MAGH)) != 0u) {
        e |= MC_SPIENC_ERR_MAGNET;
    }
    if ((diaagc & MC_AS5047P_DIAAGC_COF) != 0u) {
        e |= MC_SPIENC_ERR_CORDIC;
    }
    if ((diaagc & MC_AS5047P_DIAAGC_LF) == 0u) {
        e |= MC_SPIENC_ERR_DIAG;
    }
    return e;
}

/* The next command: ERRFL after an EF (until it is read every answer
 * carries EF, so it goes first; once, not again while its answer is on the
 * way), DIAAGC while a field error is latched or when due, else the angle. */
static mc_as5047p_pending_t next_command(mc_as5047p_t *p)
{
    if (p->need_errfl && (p->pending != MC_AS5047P_PENDING_ERRFL)) {
        return MC_AS5047P_PENDING_ERRFL;
    }
    if ((p->diag_latched != MC_SPIENC_ERR_NONE) ||
        ((p->cfg.diag_period != 0u) && (p->since_diag + 1u >= p->cfg.diag_period))) {
        p->since_diag = 0u;
        return MC_AS5047P_PENDING_DIAAGC;
    }
    p->since_diag++;
    return MC_AS5047P_PENDING_ANGLE;
}

static uint16_t command_of(const mc_as5047p_t *p, mc_as5047p_pending_t what)
{
    switch (what) {
    case MC_AS5047P_PENDING_ERRFL:
        return mc_as5047p_cmd_read(MC_AS5047P_REG_ERRFL);
    case MC_AS5047P_PENDING_DIAAGC:
        return mc_as5047p_cmd_read(MC_AS5047P_REG_DIAAGC);
    default:
        return mc_as5047p_cmd_read(p->cfg.daec ? MC_AS5047P_REG_ANGLECOM : MC_AS5047P_REG_ANGLEUNC);
    }
}

/* A response to `pending`: its errors; *p_angle when it carried one. */
static uint32_t decode(mc_as5047p_t *p, uint16_t rx, mc_as5047p_pending_t pending,
                       bool *p_have_angle, uint32_t *p_angle)
{
    uint16_t data = 0u;
    uint32_t err = mc_as5047p_frame_check(rx, &data);

    *p_have_angle = false;
    if (err == MC_SPIENC_ERR_PARITY) {
        return err;
    }
    if (pending == MC_AS5047P_PENDING_ERRFL) {
        /* ERRFL's own answer carries EF (set when it was latched) */
        p->errfl = data;
        p->need_errfl = false;
        p->hold.err_seen |= mc_as5047p_errfl_errs(data);
        return MC_SPIENC_ERR_NONE;
    }
    if (err != MC_SPIENC_ERR_NONE) {
        p->need_errfl = true; /* EF: read ERRFL to clear it and learn why */
        return err;
    }
    if (pending == MC_AS5047P_PENDING_DIAAGC) {
        const uint32_t d = mc_as5047p_diaagc_errs(data);
        p->diaagc = data;
        p->diag_latched = d;
        return d;
    }
    if (pending == MC_AS5047P_PENDING_ANGLE) {
        *p_have_angle = true;
        *p_angle = data;
    }
    return MC_SPIENC_ERR_NONE;
}

static int as5047p_read(void *ctx, mc_hal_encoder_sample_t *p_sample)
{
    mc_as5047p_t *p = ctx;
    mc_as5047p_pending_t next;
    uint16_t rx = 0u;
    uint32_t err;
    uint32_t angle = 0u;
    bool have_angle = false;

    if ((p == NULL) || (p_sample == NULL)) {
        return -EINVAL;
    }
    next = next_command(p);
    if (mc_hal_spi_transfer16(p->cfg.p_spi, command_of(p, next), &rx) != 0) {
        err = MC_SPIENC_ERR_SPI;
        next = MC_AS5047P_PENDING_NONE; /* what the chip received is unknown */
    } else {
        err = decode(p, rx, p->pending, &have_angle, &angle);
    }
    p->pending = next;
    if ((p->diag_latched != MC_SPIENC_ERR_NONE) && (err == MC_SPIENC_ERR_NONE)) {
        err = p->diag_latched; /* no angle is good until DIAAGC is */
        have_angle = false;
    }
    mc_spienc_hold_apply(&p->hold, err, have_angle, angle, mc_spienc_ticks(p->cfg.p_tick),
                         p_sample);
    return 0;
}

static const mc_hal_encoder_ops_t as5047p_ops = {
    .read = as5047p_read,
};

int mc_as5047p_init(mc_as5047p_t *p_drv, const mc_as5047p_config_t *p_cfg)
{
    if ((p_drv == NULL) || (p_cfg == NULL) ||
        !mc_spienc_cfg_ok(p_cfg->p_spi, p_cfg->bad_reads_max, p_cfg->diag_period)) {
        return -EINVAL;
    }
    p_drv->cfg = *p_cfg;
    mc_spienc_hold_init(&p_drv->hold, p_cfg->bad_reads_max, MC_AS5047P_CPR);
    p_drv->pending = MC_AS5047P_PENDING_NONE;
    p_drv->since_diag = 0u;
    p_drv->need_errfl = false;
    p_drv->diag_latched = MC_SPIENC_ERR_NONE;
    p_drv->errfl = 0u;
    p_drv->diaagc = 0u;
    p_drv->dev.ops = &as5047p_ops;
    p_drv->dev.ctx = p_drv;
    return 0;
}

/* One probe frame: its response's data, -EIO or -EPROTO (parity, EF). */
static int probe_frame(const mc_as5047p_t *p, uint16_t cmd, bool check, uint16_t *p_data)
{
    uint16_t rx = 0u;

    if (mc_hal_spi_transfer16(p->cfg.p_spi, cmd, &rx) != 0) {
        return -EIO;
    }
    if (check && (mc_as5047p_frame_check(rx, p_data) != MC_SPIENC_ERR_NONE)) {
        return -EPROTO;
    }
    return 0;
}

int mc_as5047p_probe(mc_as5047p_t *p_drv)
{
    uint16_t diaagc = 0u;
    uint16_t settings1 = 0u;
    uint16_t ignored = 0u;
    int rc;

    if (p_drv == NULL) {
        return -EINVAL;
    }
    p_drv->pending = MC_AS5047P_PENDING_NONE;
    /* ERRFL read (its answer clears EF), then DIAAGC, SETTINGS1, angle:
     * each frame returns the answer to the one before. */
    rc = probe_frame(p_drv, mc_as5047p_cmd_read(MC_AS5047P_REG_ERRFL), false, &ignored);
    if (rc == 0) {
        /* ERRFL's answer is not checked: it carries EF for the errors it
         * clears, and a chip just powered may have seen a partial frame */
        rc = probe_frame(p_drv, mc_as5047p_cmd_read(MC_AS5047P_REG_DIAAGC), false, &ignored);
    }
    if (rc == 0) {
        rc = probe_frame(p_drv, mc_as5047p_cmd_read(MC_AS5047P_REG_SETTINGS1), true, &diaagc);
    }
    if (rc == 0) {
        rc = probe_frame(p_drv, command_of(p_drv, MC_AS5047P_PENDING_ANGLE), true, &settings1);
    }
    if (rc != 0) {
        return rc;
    }
    p_drv->pending = MC_AS5047P_PENDING_ANGLE;
    p_drv->diaagc = diaagc;
    if ((mc_as5047p_diaagc_errs(diaagc) & MC_SPIENC_ERR_DIAG) != 0u ||
        ((settings1 & MC_AS5047P_SETTINGS1_FACTORY) == 0u)) {
        return -EPROTO;
    }
    return (mc_as5047p_diaagc_errs(diaagc) != 0u) ? -ERANGE : 0;
}
