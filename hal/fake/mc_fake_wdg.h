/**
 * @file mc_fake_wdg.h
 * @brief A watchdog (hal/wdg.h) for unit tests: records the start, the
 *        timeout and every feed, and "expires" when a test advances its
 *        clock past the timeout without a feed.
 */
#ifndef MC_FAKE_WDG_H
#define MC_FAKE_WDG_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/wdg.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mc_fake_wdg {
    uint32_t reset_cause;    /**< what mc_hal_wdg_reset_cause() reports */
    uint32_t timeout_ms;     /**< 0: not started */
    uint32_t starts;         /**< successful starts */
    uint32_t timeout_max_ms; /**< largest timeout started */
    uint32_t feeds;          /**< successful feeds */
    uint32_t since_feed_ms;  /**< fake time since the last feed (or start) */
    bool expired;            /**< the timeout passed without a feed: on the
                                MCU the watchdog would have reset it */
    mc_hal_wdg_t dev;
} mc_fake_wdg_t;

/** Not started, reset cause `cause`. */
void mc_fake_wdg_init(mc_fake_wdg_t *w, uint32_t cause);

/** Let ms milliseconds pass; expired is set once the time since the last
 *  feed reaches the timeout (a started watchdog only). */
void mc_fake_wdg_advance(mc_fake_wdg_t *w, uint32_t ms);

#ifdef __cplusplus
}
#endif

#endif /* MC_FAKE_WDG_H */
