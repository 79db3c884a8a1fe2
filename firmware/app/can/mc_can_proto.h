/**
 * @file mc_can_proto.h
 * @brief CAN protocol codec: identifiers, and table-driven packing and
 *        unpacking of the messages described by tools/can/motordrive.dbc.
 *
 * Identifiers (ODrive CANSimple convention): 11 bits, id = node_id << 5 |
 * cmd; node_id 0..62 (63 is kept for a broadcast address), cmd 0..31.
 * Signals are little-endian (Intel) bit fields of classic frames of up to 8
 * bytes; physical = raw * scale + offset.
 *
 * The message and signal tables (mc_can_dbc.c) and the indices
 * (mc_can_dbc.h) are generated from the DBC by `tools/can/mc_can.py gen-c`;
 * a test regenerates them and fails on any difference, and another packs
 * frames here and decodes them with cantools.
 *
 * Error codes (mc_can_err_t) are those the drive puts in its CMD_ERROR
 * reply (DBC value table of CMD_ERROR.error), plus MC_CAN_ERR_ARG for a
 * caller's mistake and MC_CAN_ERR_IGNORED for a frame addressed elsewhere;
 * those two are never sent.
 *
 * Floats only (no double): pack rounds to the nearest raw value (halves
 * away from zero) after saturating the physical value to the signal's
 * [min, max]; NaN packs as the raw value nearest to 0.
 */
#ifndef MC_CAN_PROTO_H
#define MC_CAN_PROTO_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/can.h"
#include "mc_can_dbc.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_CAN_CMD_BITS    5u
#define MC_CAN_CMD_MASK    0x1Fu
#define MC_CAN_NODE_ID_MAX 62u

typedef enum {
    MC_CAN_ERR_NONE = 0,
    MC_CAN_ERR_UNKNOWN_CMD = 1,    /**< no such command (or a telemetry id) */
    MC_CAN_ERR_LENGTH = 2,         /**< data length differs from the DBC's */
    MC_CAN_ERR_RANGE = 3,          /**< a signal outside its range */
    MC_CAN_ERR_MODE = 4,           /**< not allowed in the present state */
    MC_CAN_ERR_REFUSED = 5,        /**< the drive refused it (see its API) */
    MC_CAN_ERR_BUDGET = 6,         /**< telemetry rates above the bus budget */
    MC_CAN_ERR_UNSUPPORTED = 7,    /**< this build has no handler for it */
    MC_CAN_ERR_FORMAT = 8,         /**< remote, CAN FD frame on a classic id */
    MC_CAN_ERR_STALE = 9,          /**< HOST_HEARTBEAT counter did not advance by
                                        1..MC_CAN_HB_STEP_MAX (a repeat, a step back,
                                        a jump) */
    MC_CAN_ERR_HEARTBEAT_MIN = 10, /**< HEARTBEAT rate below MC_TM_HEARTBEAT_MIN_HZ */
    MC_CAN_ERR_LIMITED = 11,       /**< not served: its reply could not be sent under
                                        the reply rate limit (PARAM_REQ while another
                                        waits; only in HEARTBEAT.last_error) */
    MC_CAN_ERR_ANGLE_UNKNOWN = 12, /**< SET_ENABLE refused: the mode needs the rotor
                                        angle and it is unknown since power-up
                                        (angle_ref index / align, no find at enable) */
    MC_CAN_ERR_ARG = 0xFE,         /**< API misuse (NULL, bad index, short array) */
    MC_CAN_ERR_IGNORED = 0xFF      /**< not addressed to this node */
} mc_can_err_t;

typedef enum {
    MC_CAN_DIR_TX = 0, /**< sent by the drive (telemetry, replies) */
    MC_CAN_DIR_RX = 1  /**< sent to the drive (commands) */
} mc_can_dir_t;

/** One signal: a little-endian bit field. */
typedef struct {
    uint8_t start_bit; /**< bit of the LSB; bit k is bit k%8 of byte k/8 */
    uint8_t length;    /**< bits, 1..32 */
    bool is_signed;    /**< two's complement */
    float scale;       /**< physical per raw unit */
    float offset;      /**< physical at raw 0 */
    float min;         /**< physical range (DBC [min|max]) */
    float max;
} mc_can_signal_t;

/** One message. */
typedef struct {
    uint8_t cmd; /**< low 5 bits of the id */
    uint8_t dlc; /**< data bytes, exact */
    uint8_t dir; /**< mc_can_dir_t */
    uint8_t n_signals;
    const mc_can_signal_t *signals;
} mc_can_message_t;

/** Generated from the DBC, indexed by MC_CAN_MSG_*. */
extern const mc_can_message_t mc_can_messages[MC_CAN_MSG_COUNT];

static inline uint32_t mc_can_id(uint32_t node_id, uint32_t cmd)
{
    return (node_id << MC_CAN_CMD_BITS) | (cmd & MC_CAN_CMD_MASK);
}
static inline uint32_t mc_can_id_node(uint32_t id)
{
    return (id >> MC_CAN_CMD_BITS) & 0x3Fu;
}
static inline uint32_t mc_can_id_cmd(uint32_t id)
{
    return id & MC_CAN_CMD_MASK;
}

/** Index (MC_CAN_MSG_*) of the message with command id cmd, or
 *  MC_CAN_MSG_COUNT if there is none. */
uint32_t mc_can_proto_find(uint32_t cmd);

/**
 * Pack message msg (MC_CAN_MSG_*) for node node_id from values[] (one per
 * signal, in signal order; n_values >= the message's signal count).
 * Fills id, len, flags (classic, 11-bit) and data; timestamp left as is.
 * values must not be NULL (even for a message without signals).
 * @return MC_CAN_ERR_NONE; MC_CAN_ERR_ARG (NULL pointer, msg unknown,
 *         node_id > 62, n_values too small; *p_frame unchanged).
 */
mc_can_err_t mc_can_proto_pack(uint32_t msg, uint32_t node_id, const float *values,
                               uint32_t n_values, mc_hal_can_frame_t *p_frame);

/**
 * Decode a frame of any node: find its message by the id's command bits,
 * check the format and the exact length, decode every signal and check it
 * against the signal's range (half a raw step of slack).
 * @return MC_CAN_ERR_NONE and *p_msg, values[] filled;
 *         MC_CAN_ERR_FORMAT (extended, remote or FD frame),
 *         MC_CAN_ERR_UNKNOWN_CMD, MC_CAN_ERR_LENGTH, MC_CAN_ERR_RANGE
 *         (values[] unspecified), MC_CAN_ERR_ARG (a NULL pointer, or
 *         n_values too small for the message). Checked first: the format
 *         and identifier, so MC_CAN_ERR_ARG only for a caller's mistake.
 */
mc_can_err_t mc_can_proto_unpack(const mc_hal_can_frame_t *p_frame, uint32_t *p_msg, float *values,
                                 uint32_t n_values);

/** Worst-case bus time of a classic 11-bit frame with dlc data bytes, in
 *  bits, stuff bits and the 3-bit intermission included: 55 + 10 dlc. */
static inline uint32_t mc_can_frame_bits_worst(uint32_t dlc)
{
    return 55u + 10u * dlc;
}

#ifdef __cplusplus
}
#endif

#endif /* MC_CAN_PROTO_H */
