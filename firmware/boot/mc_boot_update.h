/**
 * @file mc_boot_update.h
 * @brief The bootloader's update protocol on CAN (BOOT_REQ, BOOT_DATA,
 *        BOOT_REPLY of tools/can/motordrive.dbc) as a state machine over
 *        the flash HAL: no hardware, no clock of its own, so the host tests
 *        run it on a fake flash with a power cut at every step.
 *
 * Session (states = BOOT_REPLY.boot_state):
 *   IDLE        no session. BEGIN checks the announced image against this
 *               slot (board, layout, header version, size: refused with
 *               BOARD, LAYOUT, HEADER, SIZE before anything is erased), then
 *               erases the sectors the image needs, first the one with the
 *               old header (the old image is invalid from the first erase
 *               on), and answers OK with the number of sectors erased.
 *   RECEIVING   blocks of MC_BOOT_BLOCK_BYTES in order, 0 .. n-1. WRITE k
 *               (with the block's CRC-32) opens block k, its bytes follow
 *               in BOOT_DATA chunks 0..36 of 7 bytes; the block is written
 *               only when every chunk came in order with the right length
 *               and zero padding and the CRC-32 matches; then it is read
 *               back. One reply per block: OK with the next block expected,
 *               or why it failed (FORMAT, SEQUENCE, BLOCK_CRC, HEADER,
 *               FLASH) with the block to send again. Block 0 must hold a
 *               header that agrees with BEGIN (else HEADER); its commit word
 *               is written erased whatever was sent. A WRITE of the block
 *               just written with the same CRC (the host did not hear the
 *               OK) is received and answered again, not written again; any
 *               other index is refused SEQUENCE.
 *   VERIFIED    VERIFY (with the image's CRC-32) after the last block: the
 *               whole boot check of the slot (mc_boot_image_check) must
 *               find the image complete but for the commit word.
 *   COMMITTED   COMMIT writes the commit word, checks the image again and
 *               answers OK; the board then resets (mc_boot_update_action)
 *               and the bootloader starts the new image.
 * ABORT ends a session (IDLE); RUN asks for a reset (the boot check then
 * starts a valid image, or the bootloader comes back). A flash error ends
 * the session (IDLE, FLASH): the host starts again with BEGIN.
 *
 * Frames: only this node's BOOT_REQ (exactly 8 bytes, the reserved fields 0)
 * and BOOT_DATA (8 bytes); other identifiers are ignored. Replies: one per
 * request, one per block (a failed block is answered once, its remaining
 * chunks are dropped silently), and ANNOUNCE once a second; every reply
 * passes a token bucket (MC_BOOT_REPLY_MAX_HZ, bursts of
 * MC_BOOT_REPLY_BURST): a reply beyond it is counted, not sent.
 *
 * A power cut at any step: the slot holds the old image until the first
 * erase begins, an image that fails the boot check (named) until the
 * commit word is written, and the new image after it.
 */
#ifndef MC_BOOT_UPDATE_H
#define MC_BOOT_UPDATE_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/can.h"
#include "mc_boot_image.h"
#include "mc_boot_proto.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_BOOT_ANNOUNCE_MS 1000u

/* Configuration errors (bits) of mc_boot_update_init. */
#define MC_BOOT_CFG_OK       0u
#define MC_BOOT_CFG_ERR_NULL (1u << 0) /**< NULL state, config or flash */
#define MC_BOOT_CFG_ERR_NODE (1u << 1) /**< node id > 62 */
#define MC_BOOT_CFG_ERR_SLOT \
    (1u << 2) /**< a slot sector unknown, a sector not
                                            a multiple of the block size */

typedef enum mc_boot_action {
    MC_BOOT_ACT_NONE = 0,
    MC_BOOT_ACT_RESET = 1, /**< reset once the last reply has left (COMMIT, RUN) */
} mc_boot_action_t;

typedef struct {
    mc_boot_slot_t slot;
    uint8_t node_id; /**< 0..62, from the configuration store */
    uint8_t reason;  /**< why the bootloader runs (mc_boot_img_t) */
} mc_boot_update_cfg_t;

typedef struct {
    mc_boot_update_cfg_t cfg;
    uint32_t slot_bytes;
    uint8_t state; /**< MC_CAN_VAL_BOOT_STATE_* */
    mc_boot_action_t action;
    /* session */
    uint32_t image_bytes;
    uint32_t n_blocks;
    uint32_t next_block;
    uint32_t last_crc; /**< CRC-32 of block next_block - 1 */
    /* the block being received */
    bool blk_open;
    bool blk_repeat; /**< the block already written, received again */
    uint32_t blk_index;
    uint32_t blk_len;
    uint32_t blk_crc;
    uint32_t blk_chunks; /**< chunks received in order */
    uint8_t blk[MC_BOOT_BLOCK_BYTES];
    /* replies */
    uint32_t now_ms;
    mc_boot_bucket_t bucket;
    uint32_t announce_at_ms;
    bool announce_sent;
    /* counters */
    uint32_t rx_own;          /**< BOOT_REQ and BOOT_DATA frames handled */
    uint32_t rx_ignored;      /**< other frames, and chunks of no open block */
    uint32_t replies;         /**< replies handed to the caller */
    uint32_t replies_limited; /**< replies the token bucket dropped */
    uint32_t blocks_written;
    uint32_t blocks_failed;
    uint32_t sectors_erased;
    int32_t flash_rc; /**< last flash error (0: none) */
} mc_boot_update_t;

/** Validate cfg and start in IDLE at now_ms (the first ANNOUNCE is due at
 *  once). Returns MC_BOOT_CFG_* bits; u unchanged on error. */
uint32_t mc_boot_update_init(mc_boot_update_t *u, const mc_boot_update_cfg_t *cfg, uint32_t now_ms);

/** Handle one received frame. Returns 1 with *p_reply filled when a reply
 *  is to be sent, else 0. */
uint32_t mc_boot_update_rx(mc_boot_update_t *u, const mc_hal_can_frame_t *p_frame,
                           mc_hal_can_frame_t *p_reply);

/** Time passes (now_ms, wrapping): refills the reply budget. Returns 1 with
 *  *p_out an ANNOUNCE when one is due, else 0. */
uint32_t mc_boot_update_poll(mc_boot_update_t *u, uint32_t now_ms, mc_hal_can_frame_t *p_out);

/** What the board must do once the replies handed out have been sent. */
mc_boot_action_t mc_boot_update_action(const mc_boot_update_t *u);

#ifdef __cplusplus
}
#endif

#endif /* MC_BOOT_UPDATE_H */
