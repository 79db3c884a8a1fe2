/**
 * @file mc_f405_can.c
 * @brief can capability on bxCAN (CAN1) of the STM32F405. Register facts:
 *        RM0090 §32 (bxCAN): §32.7.4 filters, §32.7.7 bit timing, §32.9
 *        registers. See mc_f405_hal.h.
 */
#include "mc_f405_hal.h"

#include <errno.h>
#include <stddef.h>

#define TQ_MIN         8u  /* fewer tq per bit leave no room to place the sample */
#define TQ_MAX         25u /* 1 + 16 + 8 */
#define BS1_MAX        16u
#define BS2_MAX        8u
#define BRP_MAX        1024u
#define SJW_MAX        4u
#define N_TX_MAILBOXES 3u
#define RX_FIFO_DEPTH  3u

/* ---- bit timing -------------------------------------------------------- */

int mc_f405_can_bit_timing(uint32_t pclk_hz, uint32_t bitrate_bps, uint16_t sample_point_permille,
                           uint8_t sjw_tq, uint32_t *p_btr)
{
    uint32_t brp;
    bool found = false;
    uint32_t best_err = 0u; /* |1000 (1 + BS1) - sp N|, over best_n */
    uint32_t best_n = 1u;
    uint32_t best_btr = 0u;

    if ((p_btr == NULL) || (pclk_hz == 0u) || (bitrate_bps == 0u) ||
        (sample_point_permille < 500u) || (sample_point_permille > 950u) || (sjw_tq == 0u) ||
        (sjw_tq > SJW_MAX)) {
        return -EINVAL;
    }
    for (brp = 1u; brp <= BRP_MAX; brp++) {
        const uint64_t clocks = (uint64_t)brp * bitrate_bps;
        uint32_t n;
        uint32_t bs1;
        uint32_t bs2;
        uint32_t sp_x1000;
        uint32_t err;

        if ((pclk_hz % clocks) != 0u) {
            continue; /* only exact bit rates */
        }
        n = (uint32_t)(pclk_hz / clocks);
        if ((n < TQ_MIN) || (n > TQ_MAX)) {
            continue;
        }
        /* Sample point after SYNC + BS1: 1 + BS1 = round(sp N). */
        bs1 = ((sample_point_permille * n) + 500u) / 1000u - 1u;
        if (bs1 > BS1_MAX) {
            bs1 = BS1_MAX;
        }
        if ((n - 1u - bs1) < 1u) {
            bs1 = n - 2u;
        }
        bs2 = n - 1u - bs1;
        if ((bs1 < 1u) || (bs2 > BS2_MAX) || (sjw_tq > bs2)) {
            continue;
        }
        sp_x1000 = 1000u * (1u + bs1);
        err = (sp_x1000 > (sample_point_permille * n)) ? (sp_x1000 - (sample_point_permille * n))
                                                       : ((sample_point_permille * n) - sp_x1000);
        /* err / n < best_err / best_n; ties keep the earlier (more tq). */
        if (!found || ((uint64_t)err * best_n < (uint64_t)best_err * n)) {
            found = true;
            best_err = err;
            best_n = n;
            best_btr = (brp - 1u) | ((bs1 - 1u) << MC_F405_CAN_BTR_TS1_SHIFT) |
                       ((bs2 - 1u) << MC_F405_CAN_BTR_TS2_SHIFT) |
                       (((uint32_t)sjw_tq - 1u) << MC_F405_CAN_BTR_SJW_SHIFT);
        }
    }
    if (!found) {
        return -EINVAL;
    }
    *p_btr = best_btr;
    return 0;
}

/* ---- frames <-> mailbox registers --------------------------------------- */

/* Identifier word of TIxR / RIxR / filter registers (§32.9.3). */
static uint32_t id_word(uint32_t id, bool ext)
{
    return ext ? ((id << MC_F405_CAN_IR_EXID_SHIFT) | MC_F405_CAN_IR_IDE)
               : (id << MC_F405_CAN_IR_STID_SHIFT);
}

static uint32_t bytes_to_word(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static void word_to_bytes(uint32_t w, uint8_t *p)
{
    p[0] = (uint8_t)(w & 0xFFu);
    p[1] = (uint8_t)((w >> 8) & 0xFFu);
    p[2] = (uint8_t)((w >> 16) & 0xFFu);
    p[3] = (uint8_t)((w >> 24) & 0xFFu);
}

static uint32_t now_ticks(const mc_hal_tick_t *p_tick)
{
    uint32_t t = 0u;

    if (p_tick != NULL) {
        (void)mc_hal_tick_read(p_tick, &t);
    }
    return t;
}

/* Read RF0R once; count and acknowledge a FIFO 0 overrun (FOVR0 is rc_w1,
 * writing 0 to the other bits changes nothing). @return the value read. */
static uint32_t rx_check_overrun(mc_f405_can_t *p)
{
    mc_f405_can_regs_t *r = p->cfg.p_can;
    const uint32_t rf0r = r->RF0R;

    if ((rf0r & MC_F405_CAN_RFR_FOVR) != 0u) {
        p->rx_overrun_count++;
        r->RF0R = MC_F405_CAN_RFR_FOVR;
    }
    return rf0r;
}

/* Take the oldest frame of hardware FIFO 0. @return false if empty. */
static bool rx_fifo_pop(mc_f405_can_t *p, mc_hal_can_frame_t *p_frame)
{
    mc_f405_can_regs_t *r = p->cfg.p_can;
    const mc_f405_can_rx_fifo_t *m = &r->RX[0];
    uint32_t rir;
    uint32_t dlc;
    uint8_t data[8];
    uint32_t k;

    if ((rx_check_overrun(p) & MC_F405_CAN_RFR_FMP_MASK) == 0u) {
        return false;
    }
    rir = m->RIR;
    dlc = m->RDTR & MC_F405_CAN_DTR_DLC_MASK;
    word_to_bytes(m->RDLR, &data[0]);
    word_to_bytes(m->RDHR, &data[4]);
    r->RF0R = MC_F405_CAN_RFR_RFOM; /* release: the next frame moves up */

    if ((rir & MC_F405_CAN_IR_IDE) != 0u) {
        p_frame->id = rir >> MC_F405_CAN_IR_EXID_SHIFT;
        p_frame->flags = (uint8_t)MC_HAL_CAN_FLAG_EXT;
    } else {
        p_frame->id = rir >> MC_F405_CAN_IR_STID_SHIFT;
        p_frame->flags = 0u;
    }
    if ((rir & MC_F405_CAN_IR_RTR) != 0u) {
        p_frame->flags |= (uint8_t)MC_HAL_CAN_FLAG_RTR;
    }
    /* A classic DLC of 9..15 still means 8 data bytes. */
    p_frame->len = (uint8_t)((dlc > MC_HAL_CAN_MAX_LEN) ? MC_HAL_CAN_MAX_LEN : dlc);
    for (k = 0u; k < 8u; k++) {
        p_frame->data[k] = data[k];
    }
    p_frame->timestamp_ticks = now_ticks(p->cfg.p_tick);
    return true;
}

/* ---- ops --------------------------------------------------------------- */

static int can_send(void *ctx, const mc_hal_can_frame_t *p_frame)
{
    mc_f405_can_t *p = ctx;
    mc_f405_can_regs_t *r;
    mc_f405_can_tx_mailbox_t *mb;
    uint32_t tsr;
    uint32_t k;
    uint32_t tir;
    uint8_t data[8] = {0u, 0u, 0u, 0u, 0u, 0u, 0u, 0u};
    int rc;

    if ((p == NULL) || (p_frame == NULL)) {
        return -EINVAL;
    }
    rc = mc_hal_can_frame_check(p_frame, false);
    if (rc != 0) {
        return rc;
    }
    r = p->cfg.p_can;
    if ((r->ESR & MC_F405_CAN_ESR_BOFF) != 0u) {
        return -ENETDOWN;
    }
    if ((r->MSR & (MC_F405_CAN_MSR_INAK | MC_F405_CAN_MSR_SLAK)) != 0u) {
        return -EIO; /* not in normal mode (never synchronised, or asleep) */
    }
    tsr = r->TSR;
    for (k = 0u; k < N_TX_MAILBOXES; k++) {
        if ((tsr & MC_F405_CAN_TSR_TME(k)) != 0u) {
            break;
        }
    }
    if (k == N_TX_MAILBOXES) {
        return -ENOBUFS;
    }
    mb = &r->TX[k];
    tir = id_word(p_frame->id, (p_frame->flags & MC_HAL_CAN_FLAG_EXT) != 0u);
    if ((p_frame->flags & MC_HAL_CAN_FLAG_RTR) != 0u) {
        tir |= MC_F405_CAN_IR_RTR;
    } else {
        for (k = 0u; k < p_frame->len; k++) {
            data[k] = p_frame->data[k];
        }
    }
    mb->TDTR = p_frame->len;
    mb->TDLR = bytes_to_word(&data[0]);
    mb->TDHR = bytes_to_word(&data[4]);
    mb->TIR = tir | MC_F405_CAN_IR_TXRQ; /* last: requests transmission */
    return 0;
}

static bool ring_empty(const mc_f405_can_t *p)
{
    return p->ring_head == p->ring_tail;
}

static int can_receive(void *ctx, mc_hal_can_frame_t *p_frame)
{
    mc_f405_can_t *p = ctx;

    if ((p == NULL) || (p_frame == NULL)) {
        return -EINVAL;
    }
    if (p->cfg.rx_irq) {
        uint32_t head;

        if (ring_empty(p)) {
            return -EAGAIN;
        }
        head = p->ring_head;
        *p_frame = p->ring[head];
        p->ring_head = (head + 1u) % MC_F405_CAN_RX_RING_LEN;
        return 0;
    }
    return rx_fifo_pop(p, p_frame) ? 0 : -EAGAIN;
}

static int can_get_status(void *ctx, mc_hal_can_status_t *p_status)
{
    mc_f405_can_t *p = ctx;
    uint32_t esr;

    if ((p == NULL) || (p_status == NULL)) {
        return -EINVAL;
    }
    if (!p->cfg.rx_irq) {
        (void)rx_check_overrun(p); /* in irq mode the ISR owns RF0R */
    }
    esr = p->cfg.p_can->ESR;
    if ((esr & MC_F405_CAN_ESR_BOFF) != 0u) {
        p_status->state = MC_HAL_CAN_STATE_BUS_OFF;
    } else if ((esr & MC_F405_CAN_ESR_EPVF) != 0u) {
        p_status->state = MC_HAL_CAN_STATE_ERROR_PASSIVE;
    } else if ((esr & MC_F405_CAN_ESR_EWGF) != 0u) {
        p_status->state = MC_HAL_CAN_STATE_ERROR_WARNING;
    } else {
        p_status->state = MC_HAL_CAN_STATE_ERROR_ACTIVE;
    }
    p_status->tx_err_count = (uint16_t)((esr >> MC_F405_CAN_ESR_TEC_SHIFT) & 0xFFu);
    p_status->rx_err_count = (uint16_t)((esr >> MC_F405_CAN_ESR_REC_SHIFT) & 0xFFu);
    p_status->rx_overrun_count = p->rx_overrun_count;
    p_status->fd_capable = false;
    return 0;
}

static const mc_hal_can_ops_t can_ops = {
    .send = can_send,
    .receive = can_receive,
    .get_status = can_get_status,
};

void mc_f405_can_rx_isr(mc_f405_can_t *p_drv)
{
    mc_hal_can_frame_t frame;
    uint32_t k;

    if (p_drv == NULL) {
        return;
    }
    /* At most the FIFO depth per call: a frame arriving meanwhile keeps
     * FMP0 non-zero and the interrupt pending, and a stuck FMP0 cannot
     * hold the CPU here. */
    for (k = 0u; (k < RX_FIFO_DEPTH) && rx_fifo_pop(p_drv, &frame); k++) {
        const uint32_t tail = p_drv->ring_tail;
        const uint32_t next = (tail + 1u) % MC_F405_CAN_RX_RING_LEN;

        if (next == p_drv->ring_head) {
            p_drv->rx_overrun_count++; /* ring full: the frame is lost */
        } else {
            p_drv->ring[tail] = frame;
            p_drv->ring_tail = next;
        }
    }
}

/* ---- init -------------------------------------------------------------- */

static bool filter_valid(const mc_f405_can_filter_t *f)
{
    const uint32_t max = f->ext ? MC_HAL_CAN_EXT_ID_MAX : MC_HAL_CAN_STD_ID_MAX;

    return (f->id <= max) && (f->mask <= max);
}

static void filters_program(mc_f405_can_regs_t *r, const mc_f405_can_config_t *c)
{
    const uint32_t n = (c->n_filters == 0u) ? 1u : c->n_filters;
    uint32_t bits = 0u;
    uint32_t k;

    for (k = 0u; k < n; k++) {
        bits |= 1u << (c->filter_bank_start + k);
    }
    r->FMR |= MC_F405_CAN_FMR_FINIT; /* filters writable, rx paused */
    r->FA1R &= ~bits;                /* deactivate while writing */
    r->FM1R &= ~bits;                /* identifier-mask mode */
    r->FS1R |= bits;                 /* single 32-bit scale */
    r->FFA1R &= ~bits;               /* all to FIFO 0: one reception order */
    for (k = 0u; k < n; k++) {
        mc_f405_can_filter_bank_t *fb = &r->FB[c->filter_bank_start + k];

        if (c->n_filters == 0u) {
            fb->FR1 = 0u; /* mask 0: accept everything */
            fb->FR2 = 0u;
        } else {
            const mc_f405_can_filter_t *f = &c->p_filters[k];

            fb->FR1 = id_word(f->id, f->ext);
            /* The mask also compares IDE, so 11- and 29-bit ids with the
             * same bits do not alias; RTR is left free. */
            fb->FR2 = id_word(f->mask, f->ext) | MC_F405_CAN_IR_IDE;
        }
    }
    r->FA1R |= bits;
    r->FMR &= ~MC_F405_CAN_FMR_FINIT;
}

int mc_f405_can_set_filters(mc_f405_can_t *p_drv, const mc_f405_can_filter_t *p_filters,
                            uint8_t n_filters)
{
    mc_f405_can_config_t c;
    uint32_t old_bits = 0u;
    uint32_t k;

    if ((p_drv == NULL) || (p_drv->cfg.p_can == NULL) ||
        ((n_filters != 0u) && (p_filters == NULL)) ||
        (((uint32_t)p_drv->cfg.filter_bank_start + ((n_filters == 0u) ? 1u : (uint32_t)n_filters)) >
         MC_F405_CAN_FILTER_BANKS)) {
        return -EINVAL;
    }
    for (k = 0u; k < n_filters; k++) {
        if (!filter_valid(&p_filters[k])) {
            return -EINVAL;
        }
    }
    c = p_drv->cfg;
    for (k = 0u; k < ((c.n_filters == 0u) ? 1u : (uint32_t)c.n_filters); k++) {
        old_bits |= 1u << (c.filter_bank_start + k);
    }
    c.p_filters = p_filters;
    c.n_filters = n_filters;
    p_drv->cfg.p_can->FMR |= MC_F405_CAN_FMR_FINIT;
    p_drv->cfg.p_can->FA1R &= ~old_bits; /* banks of the old set no longer used */
    filters_program(p_drv->cfg.p_can, &c);
    p_drv->cfg = c;
    return 0;
}

int mc_f405_can_init(mc_f405_can_t *p_drv, const mc_f405_can_config_t *p_cfg)
{
    const mc_f405_can_config_t *c = p_cfg;
    mc_f405_can_regs_t *r;
    uint32_t btr;
    uint32_t mcr;
    uint32_t k;
    uint32_t polls;

    if ((p_drv == NULL) || (c == NULL) || (c->p_can == NULL)) {
        return -EINVAL;
    }
    if (mc_f405_can_bit_timing(c->pclk_hz, c->bitrate_bps, c->sample_point_permille, c->sjw_tq,
                               &btr) != 0) {
        return -EINVAL;
    }
    if (((c->n_filters != 0u) && (c->p_filters == NULL)) ||
        (((uint32_t)c->filter_bank_start + ((c->n_filters == 0u) ? 1u : (uint32_t)c->n_filters)) >
         MC_F405_CAN_FILTER_BANKS)) {
        return -EINVAL;
    }
    for (k = 0u; k < c->n_filters; k++) {
        if (!filter_valid(&c->p_filters[k])) {
            return -EINVAL;
        }
    }

    r = c->p_can;
    mcr = MC_F405_CAN_MCR_TXFP;
    if (c->auto_bus_off_recovery) {
        mcr |= MC_F405_CAN_MCR_ABOM;
    }
    if (c->no_auto_retransmit) {
        mcr |= MC_F405_CAN_MCR_NART;
    }
    /* Leave sleep (SLEEP = 0) and request initialisation mode. */
    r->MCR = mcr | MC_F405_CAN_MCR_INRQ;
    for (polls = 0u; polls < MC_F405_CAN_INIT_POLLS; polls++) {
        if ((r->MSR & (MC_F405_CAN_MSR_INAK | MC_F405_CAN_MSR_SLAK)) == MC_F405_CAN_MSR_INAK) {
            break;
        }
    }
    if (polls == MC_F405_CAN_INIT_POLLS) {
        return -EIO; /* no clock, or the peripheral is held in reset */
    }

    p_drv->cfg = *c;
    p_drv->btr = btr;
    p_drv->ring_head = 0u;
    p_drv->ring_tail = 0u;
    p_drv->rx_overrun_count = 0u;
    p_drv->dev.ops = &can_ops;
    p_drv->dev.ctx = p_drv;

    r->BTR = btr; /* writable in initialisation mode only */
    filters_program(r, c);
    r->IER = c->rx_irq ? MC_F405_CAN_IER_FMPIE0 : 0u;
    r->MCR = mcr; /* request normal mode: joins after 11 recessive bits */
    return 0;
}

bool mc_f405_can_tx_idle(const mc_f405_can_t *p_drv)
{
    const uint32_t all =
        MC_F405_CAN_TSR_TME(0u) | MC_F405_CAN_TSR_TME(1u) | MC_F405_CAN_TSR_TME(2u);
    return (p_drv != NULL) && ((p_drv->cfg.p_can->TSR & all) == all);
}
