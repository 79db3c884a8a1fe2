/**
 * @file mc_hal_fake.h
 * @brief A fake HAL board for tests: every capability of hal/hal.h,
 *        backed by plain fields of one struct the test owns.
 *
 * Use:
 *     mc_hal_fake_t fake;
 *     mc_hal_fake_config_t cfg;
 *     mc_hal_fake_config_default(&cfg);
 *     mc_hal_fake_init(&fake, &cfg);
 *     const mc_hal_t *hal = &fake.board;   // hand this to the code under test
 *
 * Inspect: every field of mc_hal_fake_t is public and may be read at any
 * time (last duties and enable state in fake.pwm3 / fake.pwm2, fault state
 * in fake.fault, call counts in fake.call_count[]). Drive inputs with the
 * mc_hal_fake_* setters (they validate like hardware would); write fields
 * directly only to build states the setters refuse.
 *
 * Behaviour mirrors what the real drivers must do: invalid duties and frames
 * are rejected with -EINVAL and change nothing; enables are refused with
 * -EBUSY while the gate kill is latched; CAN queues are FIFOs of fixed
 * capacity (-ENOBUFS full, -EAGAIN empty); the gate kill always works.
 *
 * Error injection: mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_PWM3_DISABLE,
 * -EIO, 1) makes the next call of that op return -EIO with no effect.
 *
 * No heap, no globals: all storage is inside mc_hal_fake_t. The struct holds
 * pointers to itself (handles -> ctx, board -> handles): do not copy it
 * after init. Not thread-safe (tests are single-threaded).
 */
#ifndef MC_HAL_FAKE_H
#define MC_HAL_FAKE_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/hal.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Capacity of each fake CAN queue (tx and rx) [frames]. */
#define MC_HAL_FAKE_CAN_QUEUE_LEN 8u

/** One entry per fallible HAL op: index of call_count[] and injections. */
typedef enum mc_hal_fake_call {
    MC_HAL_FAKE_ADC_READ = 0,
    MC_HAL_FAKE_ADC_READ_TEMP,
    MC_HAL_FAKE_PWM3_SET_DUTY,
    MC_HAL_FAKE_PWM3_ENABLE,
    MC_HAL_FAKE_PWM3_DISABLE,
    MC_HAL_FAKE_PWM3_GET_STATE,
    MC_HAL_FAKE_PWM2_SET_DUTY,
    MC_HAL_FAKE_PWM2_ENABLE,
    MC_HAL_FAKE_PWM2_DISABLE,
    MC_HAL_FAKE_PWM2_GET_STATE,
    MC_HAL_FAKE_ENCODER_READ,
    MC_HAL_FAKE_CAN_SEND,
    MC_HAL_FAKE_CAN_RECEIVE,
    MC_HAL_FAKE_CAN_GET_STATUS,
    MC_HAL_FAKE_TICK_READ,
    MC_HAL_FAKE_TICK_GET_FREQ,
    MC_HAL_FAKE_FAULT_READ,
    MC_HAL_FAKE_FAULT_GATE_RELEASE,
    MC_HAL_FAKE_BRAKE_SET_DUTY,
    MC_HAL_FAKE_CALL_COUNT /**< number of entries, not a call */
} mc_hal_fake_call_t;

typedef struct mc_hal_fake_config {
    float pwm3_period_s;             /**< (0, 1] s */
    float pwm2_period_s;             /**< (0, 1] s */
    uint32_t tick_freq_hz;           /**< > 0 */
    uint32_t encoder_counts_per_rev; /**< > 0 */
    bool can_fd_capable;             /**< accept FD frames */
    bool fault_input_kills;          /**< a fault input latches the gate kill,
                                          as when wired to the timer BKIN */
} mc_hal_fake_config_t;

/** A fixed-capacity FIFO of frames (ring buffer). */
typedef struct mc_hal_fake_can_queue {
    mc_hal_can_frame_t frames[MC_HAL_FAKE_CAN_QUEUE_LEN];
    uint32_t head;  /**< index of the oldest frame */
    uint32_t count; /**< frames queued, 0 .. MC_HAL_FAKE_CAN_QUEUE_LEN */
} mc_hal_fake_can_queue_t;

typedef struct mc_hal_fake {
    mc_hal_fake_config_t cfg;

    /* adc */
    mc_hal_adc_sample_t adc_sample; /**< what the next read returns */
    bool adc_pending;               /**< a sample not yet read */
    mc_hal_adc_temp_t adc_temp;

    /* pwm */
    mc_hal_pwm3_state_t pwm3; /**< last accepted duties, enable, period */
    mc_hal_pwm2_state_t pwm2;

    /* encoder */
    mc_hal_encoder_sample_t encoder;

    /* can */
    mc_hal_fake_can_queue_t can_tx; /**< frames the code under test sent */
    mc_hal_fake_can_queue_t can_rx; /**< frames waiting to be received */
    mc_hal_can_status_t can_status;

    /* tick */
    uint32_t tick_now;

    /* fault */
    mc_hal_fault_status_t fault;
    uint32_t gate_kill_count; /**< gate kills requested (cannot fail) */

    /* brake chopper */
    float brake_duty; /**< last accepted chopper duty, [0, 1] */

    /* instrumentation */
    uint32_t call_count[MC_HAL_FAKE_CALL_COUNT];       /**< calls per op, also
                                                      the failed ones */
    int inject_err[MC_HAL_FAKE_CALL_COUNT];            /**< error to return */
    uint32_t inject_remaining[MC_HAL_FAKE_CALL_COUNT]; /**< calls to fail */

    /* handles, ctx = this struct; board points at them */
    mc_hal_adc_t adc_dev;
    mc_hal_pwm3_t pwm3_dev;
    mc_hal_pwm2_t pwm2_dev;
    mc_hal_encoder_t encoder_dev;
    mc_hal_can_t can_dev;
    mc_hal_tick_t tick_dev;
    mc_hal_fault_t fault_dev;
    mc_hal_brake_t brake_dev;
    mc_hal_t board; /**< every capability present */
} mc_hal_fake_t;

/**
 * Defaults: 20 kHz PWM (50 us) for both bridges, 168 MHz tick, 16384
 * counts/rev, classic CAN only, fault inputs latch the gate kill.
 * @return 0; -EINVAL if p_cfg is NULL.
 */
int mc_hal_fake_config_default(mc_hal_fake_config_t *p_cfg);

/**
 * Validate the config and reset the fake to power-up: duties at
 * MC_HAL_PWM3_DUTY_INIT / MC_HAL_PWM2_DUTY_INIT, outputs disabled, no ADC
 * sample pending, all-zero temperatures with no valid bit, encoder at count
 * 0 with no flags, queues empty, bus error-active, tick 0, no fault, no
 * injection, call counts 0.
 * @return 0; -EINVAL NULL pointer, period not in (0, 1] s (NaN included),
 *         tick_freq_hz or encoder_counts_per_rev zero: *p_fake unchanged.
 */
int mc_hal_fake_init(mc_hal_fake_t *p_fake, const mc_hal_fake_config_t *p_cfg);

/**
 * The next `times` calls of `call` return `err` and have no effect (the call
 * is still counted). times = 0 cancels an injection.
 * @return 0; -EINVAL if call is out of range or err is not negative.
 */
int mc_hal_fake_inject_error(mc_hal_fake_t *p_fake, mc_hal_fake_call_t call, int err,
                             uint32_t times);

/**
 * Complete a conversion: the next mc_hal_adc_read() returns these values
 * with timestamp = current tick and seq incremented (wrapping).
 * @return 0; -EINVAL unknown valid_mask bits (nothing changes).
 */
int mc_hal_fake_adc_set_sample(mc_hal_fake_t *p_fake, float ia_a, float ib_a, float ic_a,
                               float vbus_v, uint32_t valid_mask);

/**
 * Set the temperatures mc_hal_adc_read_temp() returns.
 * @return 0; -EINVAL unknown valid_mask bits (nothing changes).
 */
int mc_hal_fake_adc_set_temp(mc_hal_fake_t *p_fake, float power_stage_temp_c, float motor_temp_c,
                             uint32_t valid_mask);

/**
 * Set the position mc_hal_encoder_read() returns (timestamp = current tick).
 * @return 0; -EINVAL count >= counts_per_rev or unknown flag bits.
 */
int mc_hal_fake_encoder_set(mc_hal_fake_t *p_fake, uint32_t count, uint32_t flags);

/**
 * A frame arrives from the bus: queue it for mc_hal_can_receive(), stamped
 * with the current tick.
 * @return 0; -EINVAL / -ENOTSUP as mc_hal_can_frame_check(); -ENOBUFS rx
 *         queue full: the frame is lost and rx_overrun_count incremented,
 *         as a controller would.
 */
int mc_hal_fake_can_rx_push(mc_hal_fake_t *p_fake, const mc_hal_can_frame_t *p_frame);

/**
 * Take the oldest frame the code under test sent.
 * @return 0; -EAGAIN tx queue empty (*p_frame unchanged); -EINVAL NULL.
 */
int mc_hal_fake_can_tx_pop(mc_hal_fake_t *p_fake, mc_hal_can_frame_t *p_frame);

/**
 * Set the error counters; the bus state follows from them as in ISO
 * 11898-1: tx_err_count > 255 bus-off, either >= 128 error-passive, either
 * >= 96 error-warning, else error-active.
 * @return 0; -EINVAL NULL.
 */
int mc_hal_fake_can_set_errors(mc_hal_fake_t *p_fake, uint16_t tx_err_count, uint16_t rx_err_count);

/** Advance the tick counter by `ticks` (wraps modulo 2^32). 0; -EINVAL. */
int mc_hal_fake_tick_advance(mc_hal_fake_t *p_fake, uint32_t ticks);

/** Set the tick counter to `now_ticks`. 0; -EINVAL NULL. */
int mc_hal_fake_tick_set(mc_hal_fake_t *p_fake, uint32_t now_ticks);

/**
 * Set the level of the fault inputs (MC_HAL_FAULT_* bits). Asserted inputs
 * are added to latched_mask; with cfg.fault_input_kills any asserted input
 * also latches the gate kill (all outputs off), as the timer break input
 * does in hardware.
 * @return 0; -EINVAL unknown bits (nothing changes).
 */
int mc_hal_fake_fault_set_inputs(mc_hal_fake_t *p_fake, uint32_t active_mask);

#ifdef __cplusplus
}
#endif

#endif /* MC_HAL_FAKE_H */
