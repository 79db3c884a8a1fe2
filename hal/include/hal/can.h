/**
 * @file can.h
 * @brief HAL capability: CAN 2.0 (classic) with optional CAN FD frames.
 *
 * On the STM32F405: bxCAN (classic only, 3 tx mailboxes, 2 rx FIFOs of 3)
 * behind small software queues; on the host: SocketCAN. Send and receive
 * never block: send queues the frame or says why not, receive returns a
 * queued frame or -EAGAIN. Acceptance filters, bit timing and automatic
 * bus-off recovery (128 x 11 recessive bits, bxCAN ABOM) are set by the
 * implementation's config at init.
 *
 * See hal/hal.h for the conventions (error codes, timing classes).
 */
#ifndef MC_HAL_CAN_H
#define MC_HAL_CAN_H

#include <errno.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Bits of mc_hal_can_frame_t.flags. */
#define MC_HAL_CAN_FLAG_EXT (1u << 0) /**< 29-bit identifier (else 11-bit) */
#define MC_HAL_CAN_FLAG_RTR (1u << 1) /**< classic remote frame (no data) */
#define MC_HAL_CAN_FLAG_FD  (1u << 2) /**< CAN FD frame (len up to 64) */
#define MC_HAL_CAN_FLAG_BRS (1u << 3) /**< FD bit-rate switch (needs FD) */
#define MC_HAL_CAN_FLAG_ALL \
    (MC_HAL_CAN_FLAG_EXT | MC_HAL_CAN_FLAG_RTR | MC_HAL_CAN_FLAG_FD | MC_HAL_CAN_FLAG_BRS)

#define MC_HAL_CAN_STD_ID_MAX 0x7FFu      /**< largest 11-bit identifier */
#define MC_HAL_CAN_EXT_ID_MAX 0x1FFFFFFFu /**< largest 29-bit identifier */
#define MC_HAL_CAN_MAX_LEN    8u          /**< classic data bytes */
#define MC_HAL_CAN_FD_MAX_LEN 64u         /**< FD data bytes */

/**
 * One frame. `len` is the number of data bytes: 0..8 for a classic frame
 * (equal to its DLC; for a remote frame the requested DLC, data unused),
 * one of 0..8, 12, 16, 20, 24, 32, 48, 64 for an FD frame. Bytes of data[]
 * beyond len are unspecified. data[] is sized for FD (a frame is 76 bytes);
 * classic-only queues pay that in RAM to keep one frame type.
 */
typedef struct mc_hal_can_frame {
    uint32_t id;              /**< identifier, <= 0x7FF or <= 0x1FFFFFFF */
    uint32_t timestamp_ticks; /**< rx: tick counter at reception; tx: ignored */
    uint8_t len;              /**< data length [bytes] */
    uint8_t flags;            /**< MC_HAL_CAN_FLAG_* */
    uint8_t data[MC_HAL_CAN_FD_MAX_LEN];
} mc_hal_can_frame_t;

/** Fault confinement state (ISO 11898-1), from the error counters. */
typedef enum mc_hal_can_bus_state {
    MC_HAL_CAN_STATE_ERROR_ACTIVE = 0, /**< both counters < 96: normal */
    MC_HAL_CAN_STATE_ERROR_WARNING,    /**< a counter >= 96 */
    MC_HAL_CAN_STATE_ERROR_PASSIVE,    /**< a counter >= 128 */
    MC_HAL_CAN_STATE_BUS_OFF           /**< tx counter > 255: not sending */
} mc_hal_can_bus_state_t;

typedef struct mc_hal_can_status {
    mc_hal_can_bus_state_t state;
    uint16_t tx_err_count;     /**< transmit error counter (TEC) */
    uint16_t rx_err_count;     /**< receive error counter (REC) */
    uint32_t rx_overrun_count; /**< frames lost because rx was full; wraps */
    bool fd_capable;           /**< implementation sends/receives FD frames */
} mc_hal_can_status_t;

typedef struct mc_hal_can_ops {
    /** See mc_hal_can_send(). */
    int (*send)(void *ctx, const mc_hal_can_frame_t *p_frame);
    /** See mc_hal_can_receive(). */
    int (*receive)(void *ctx, mc_hal_can_frame_t *p_frame);
    /** See mc_hal_can_get_status(). */
    int (*get_status)(void *ctx, mc_hal_can_status_t *p_status);
} mc_hal_can_ops_t;

typedef struct mc_hal_can {
    const mc_hal_can_ops_t *ops;
    void *ctx;
} mc_hal_can_t;

/** true if len is a data length an FD frame can carry. */
static inline bool mc_hal_can_fd_len_valid(uint8_t len)
{
    return (len <= 8u) || (len == 12u) || (len == 16u) || (len == 20u) || (len == 24u) ||
           (len == 32u) || (len == 48u) || (len == 64u);
}

/**
 * Check a frame before sending (every implementation calls this, so all of
 * them reject the same frames).
 * @return 0 valid;
 *         -EINVAL unknown flag bits, id beyond 11 bits (or 29 bits with
 *                 MC_HAL_CAN_FLAG_EXT), classic len > 8, FD len not a valid
 *                 FD length, RTR on an FD frame, BRS without FD;
 *         -ENOTSUP a valid FD frame and fd_capable is false.
 */
static inline int mc_hal_can_frame_check(const mc_hal_can_frame_t *p_frame, bool fd_capable)
{
    uint32_t id_max;

    if (p_frame == NULL) {
        return -EINVAL;
    }
    if ((p_frame->flags & ~MC_HAL_CAN_FLAG_ALL) != 0u) {
        return -EINVAL;
    }
    id_max = ((p_frame->flags & MC_HAL_CAN_FLAG_EXT) != 0u) ? MC_HAL_CAN_EXT_ID_MAX
                                                            : MC_HAL_CAN_STD_ID_MAX;
    if (p_frame->id > id_max) {
        return -EINVAL;
    }
    if ((p_frame->flags & MC_HAL_CAN_FLAG_FD) != 0u) {
        if (((p_frame->flags & MC_HAL_CAN_FLAG_RTR) != 0u) ||
            !mc_hal_can_fd_len_valid(p_frame->len)) {
            return -EINVAL;
        }
        if (!fd_capable) {
            return -ENOTSUP;
        }
        return 0;
    }
    if (((p_frame->flags & MC_HAL_CAN_FLAG_BRS) != 0u) || (p_frame->len > MC_HAL_CAN_MAX_LEN)) {
        return -EINVAL;
    }
    return 0;
}

/**
 * Queue a frame for transmission.                       Timing: SLOW.
 *
 * Non-blocking. 0 means queued, not yet acknowledged on the bus; frames
 * leave in the order they were queued.
 * @return 0; -EINVAL / -ENOTSUP as mc_hal_can_frame_check() (nothing
 *         queued); -ENOBUFS tx queue full (nothing queued, retry later or
 *         drop); -ENETDOWN controller is bus-off (nothing queued); -EIO;
 *         -ENODEV.
 */
static inline int mc_hal_can_send(const mc_hal_can_t *dev, const mc_hal_can_frame_t *p_frame)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->send == NULL)) {
        return -ENODEV;
    }
    if (p_frame == NULL) {
        return -EINVAL;
    }
    return dev->ops->send(dev->ctx, p_frame);
}

/**
 * Take the oldest received frame.                       Timing: SLOW.
 *
 * Non-blocking; frames come out in reception order.
 * @return 0 and *p_frame filled; -EAGAIN nothing received (*p_frame
 *         unchanged); -EIO; -ENODEV; -EINVAL.
 */
static inline int mc_hal_can_receive(const mc_hal_can_t *dev, mc_hal_can_frame_t *p_frame)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->receive == NULL)) {
        return -ENODEV;
    }
    if (p_frame == NULL) {
        return -EINVAL;
    }
    return dev->ops->receive(dev->ctx, p_frame);
}

/**
 * Bus state, error counters, overruns, FD capability.   Timing: SLOW.
 * @return 0 and *p_status filled; -EIO; -ENODEV; -EINVAL.
 */
static inline int mc_hal_can_get_status(const mc_hal_can_t *dev, mc_hal_can_status_t *p_status)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->get_status == NULL)) {
        return -ENODEV;
    }
    if (p_status == NULL) {
        return -EINVAL;
    }
    return dev->ops->get_status(dev->ctx, p_status);
}

#ifdef __cplusplus
}
#endif

#endif /* MC_HAL_CAN_H */
