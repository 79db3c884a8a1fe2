/**
 * @file mc_spisched.h
 * @brief One SPI bus shared by the fast loop and the slow loop: the slow
 *        loop's frames run inside the fast loop, between its own, so two
 *        devices are never on the bus at once.
 *
 * The ODrive v3.6 has its absolute encoder on SPI3 with the two DRV8301
 * gate drivers. The encoder is read in the fast loop (the ADC interrupt,
 * highest priority) every PWM period; the DRV8301 is set up at boot and
 * supervised from the slow loop (PendSV, lowest priority), which the fast
 * loop preempts. A frame of the slow loop interrupted by an encoder frame
 * would put two chip selects on the bus, so the slow side never drives the
 * bus itself once the fast loop runs:
 *
 *   before mc_spisched_defer()  the slow handle's transfer16 is the
 *                               device's own (boot: no fast loop yet);
 *   after it                    transfer16 posts the frame and waits; the
 *                               fast loop's mc_spisched_fast_slot(), called
 *                               once per PWM period in the fast-loop
 *                               interrupt (before or after its own frames,
 *                               never during them), runs at most one posted
 *                               frame and hands back the answer.
 *
 * Rate: one slow frame per PWM period (50 us at 20 kHz). The DRV8301's
 * status read (two registers, two frames each: 4 frames) takes 4 periods,
 * 200 us, inside the 1 ms slow period, so the gate driver's supervision
 * keeps its rate; its set-up after a gate release (up to 14 frames) keeps
 * the slow loop busy for 0.7 ms once. Cost in the fast loop: one DRV8301
 * frame (16 clocks at 2.625 MHz, 6.1 us, and its chip-select gap) in the
 * periods that carry one; nothing otherwise.
 *
 * The slow side waits at most timeout_us on the tick counter (-EIO, the
 * frame withdrawn): the fast loop has stopped. Single core: the fast loop
 * runs to completion inside the slow side's wait, so the handshake needs
 * no lock (volatile fields, one writer each: req_seq by the slow side,
 * done_seq by the fast side).
 *
 * Not reentrant on the slow side (one slow context uses the handle).
 */
#ifndef MC_SPISCHED_H
#define MC_SPISCHED_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/spi.h"
#include "hal/tick.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Default wait of a slow frame [us]: 20 PWM periods at 20 kHz. */
#define MC_SPISCHED_TIMEOUT_US_DEFAULT 1000u

typedef struct mc_spisched_config {
    const mc_hal_spi_t *p_dev;   /**< the slow side's device (a gate driver) */
    const mc_hal_tick_t *p_tick; /**< the clock of the wait; required */
    uint32_t timeout_us;         /**< a slow frame's wait, 1 .. 1000000 us */
    /** Called on every turn of the slow side's wait (NULL on the MCU,
     *  where the fast loop preempts the wait; a test runs a fast period
     *  here). */
    void (*wait)(void *ctx);
    void *wait_ctx;
} mc_spisched_config_t;

typedef struct mc_spisched {
    mc_spisched_config_t cfg;
    uint32_t tick_hz;
    volatile bool deferred;
    volatile uint32_t req_seq;  /**< written by the slow side */
    volatile uint32_t done_seq; /**< written by the fast side */
    volatile uint16_t tx;
    volatile uint16_t rx;
    volatile int rc;
    uint32_t n_slot_frames; /**< slow frames run by the fast slot */
    uint32_t n_timeouts;    /**< slow frames withdrawn after timeout_us */
    mc_hal_spi_t dev;       /**< the slow side's handle (ctx = this struct) */
} mc_spisched_t;

/** @return 0; -EINVAL NULL, no device or tick, timeout out of range, or
 *          the tick's frequency unreadable or below 1 MHz. */
int mc_spisched_init(mc_spisched_t *p_s, const mc_spisched_config_t *p_cfg);

/** From now on the slow side's frames run in the fast slot (call once the
 *  fast loop is about to run, before the slow loop first uses the bus). */
void mc_spisched_defer(mc_spisched_t *p_s);

/** Fast loop, once per period, outside its own frames: runs the posted
 *  slow frame, if any. @return true when it ran one. */
bool mc_spisched_fast_slot(mc_spisched_t *p_s);

#ifdef __cplusplus
}
#endif

#endif /* MC_SPISCHED_H */
