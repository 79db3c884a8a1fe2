/**
 * @file mc_boot_proto.h
 * @brief The firmware update messages of tools/can/motordrive.dbc (BOOT_REQ,
 *        BOOT_DATA, BOOT_REPLY): their byte layout, the constants both the
 *        application (mc_boot_req.h: INFO, VERSION, ENTER) and the
 *        bootloader (firmware/boot: the update itself) use, and the reply
 *        budget they share.
 *
 * Byte layout (little-endian; the DBC's signals, checked against cantools
 * by tests/update):
 *   BOOT_REQ    [0] boot_op, [1..3] arg (24 bits), [4..7] value
 *   BOOT_DATA   [0] chunk, [1..7] seven bytes of the block
 *   BOOT_REPLY  [0] boot_op, [1] boot_status, [2] boot_state,
 *               [3] boot_reason, [4..7] value
 * The op, status, state and reason values are the DBC's value tables
 * (MC_CAN_VAL_BOOT_* of mc_can_dbc.h, generated from it).
 */
#ifndef MC_BOOT_PROTO_H
#define MC_BOOT_PROTO_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/can.h"
#include "mc_can_dbc.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_BOOT_PROTO_VERSION 1u
#define MC_BOOT_BLOCK_BYTES   256u
#define MC_BOOT_CHUNK_BYTES   7u
#define MC_BOOT_BLOCK_CHUNKS  37u /**< ceil(256 / 7) */
#define MC_BOOT_FRAME_BYTES   8u  /**< every boot message is a full classic frame */
/** ENTER's value: the application resets into the bootloader only after
 *  ENTER with this key and ENTER_CONFIRM with the token it answered. */
#define MC_BOOT_ENTER_KEY 0x544F4F42u
/** Reply budget: a token bucket of MC_BOOT_REPLY_MAX_HZ replies per second
 *  and bursts of MC_BOOT_REPLY_BURST; at 135 bits per reply (8 bytes, worst
 *  case with stuff bits) 33.75 kbit/s, 6.75 % of a 500 kbit/s bus. A host
 *  that waits for each block's answer (as the protocol asks) needs at most
 *  one reply per block of 39 frames (5265 bits): 190 per second at 1 Mbit/s. */
#define MC_BOOT_REPLY_MAX_HZ 250u
#define MC_BOOT_REPLY_BURST  8u

/** A decoded BOOT_REQ. */
typedef struct {
    uint32_t op;
    uint32_t arg;   /**< 24 bits */
    uint32_t value; /**< 32 bits */
} mc_boot_msg_t;

/** The reply budget (token bucket on a millisecond clock). */
typedef struct {
    uint32_t tokens;
    uint32_t last_ms;
    uint32_t acc; /**< ms x MC_BOOT_REPLY_MAX_HZ not yet a token */
} mc_boot_bucket_t;

/** A full bucket at now_ms. */
void mc_boot_bucket_init(mc_boot_bucket_t *b, uint32_t now_ms);
/** Refill up to now_ms (a wrapping millisecond clock). */
void mc_boot_bucket_refill(mc_boot_bucket_t *b, uint32_t now_ms);
/** Take a token: true if a reply may be sent now. */
bool mc_boot_bucket_take(mc_boot_bucket_t *b);

/** Is p_frame a classic 11-bit data frame of node with command cmd? */
bool mc_boot_frame_is(const mc_hal_can_frame_t *p_frame, uint32_t node_id, uint32_t cmd);

/** Decode a BOOT_REQ's 8 data bytes. */
void mc_boot_req_decode(const uint8_t data[MC_BOOT_FRAME_BYTES], mc_boot_msg_t *p_req);

/** BOOT_REPLY of node_id with the given fields. */
void mc_boot_reply_frame(uint32_t node_id, uint32_t op, uint32_t status, uint32_t state,
                         uint32_t reason, uint32_t value, mc_hal_can_frame_t *p_frame);

/** INFO's and ANNOUNCE's value: board_id | layout_id << 8 | protocol << 16. */
uint32_t mc_boot_info_value(uint32_t board_id, uint32_t layout_id);

#ifdef __cplusplus
}
#endif

#endif /* MC_BOOT_PROTO_H */
