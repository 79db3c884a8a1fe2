/**
 * @file mc_boot_update.c
 * @brief The bootloader's update protocol: see mc_boot_update.h.
 */
#include "mc_boot_update.h"

#include <stddef.h>
#include <string.h>

#include "mc_can_proto.h"
#include "mc_crc32.h"

#define ST_IDLE      MC_CAN_VAL_BOOT_STATE_IDLE
#define ST_RECEIVING MC_CAN_VAL_BOOT_STATE_RECEIVING
#define ST_VERIFIED  MC_CAN_VAL_BOOT_STATE_VERIFIED
#define ST_COMMITTED MC_CAN_VAL_BOOT_STATE_COMMITTED

#define S_OK        MC_CAN_VAL_BOOT_STATUS_OK
#define S_OPCODE    MC_CAN_VAL_BOOT_STATUS_OPCODE
#define S_FORMAT    MC_CAN_VAL_BOOT_STATUS_FORMAT
#define S_STATE     MC_CAN_VAL_BOOT_STATUS_STATE
#define S_BOARD     MC_CAN_VAL_BOOT_STATUS_BOARD
#define S_LAYOUT    MC_CAN_VAL_BOOT_STATUS_LAYOUT
#define S_HEADER    MC_CAN_VAL_BOOT_STATUS_HEADER
#define S_SIZE      MC_CAN_VAL_BOOT_STATUS_SIZE
#define S_SEQUENCE  MC_CAN_VAL_BOOT_STATUS_SEQUENCE
#define S_BLOCK_CRC MC_CAN_VAL_BOOT_STATUS_BLOCK_CRC
#define S_FLASH     MC_CAN_VAL_BOOT_STATUS_FLASH
#define S_IMAGE_CRC MC_CAN_VAL_BOOT_STATUS_IMAGE_CRC
#define S_KEY       MC_CAN_VAL_BOOT_STATUS_KEY

/* A reply: fields of BOOT_REPLY besides the node, state and reason. */
typedef struct {
    uint32_t op;
    uint32_t status;
    uint32_t value;
} reply_t;

/* ------------------------------------------------------------------ init */

static bool slot_blocks_ok(const mc_boot_slot_t *s)
{
    for (uint32_t i = 0u; i < s->n_sectors; ++i) {
        uint32_t b = 0u;
        if ((mc_hal_flash_sector_size(s->flash, s->first_sector + i, &b) != 0) ||
            ((b % MC_BOOT_BLOCK_BYTES) != 0u)) {
            return false; /* a block never straddles two sectors */
        }
    }
    return true;
}

uint32_t mc_boot_update_init(mc_boot_update_t *u, const mc_boot_update_cfg_t *cfg, uint32_t now_ms)
{
    uint32_t err = MC_BOOT_CFG_OK;
    uint32_t bytes;
    if ((u == NULL) || (cfg == NULL) || (cfg->slot.flash == NULL)) {
        return MC_BOOT_CFG_ERR_NULL;
    }
    if ((uint32_t)cfg->node_id > MC_CAN_NODE_ID_MAX) {
        err |= MC_BOOT_CFG_ERR_NODE;
    }
    bytes = mc_boot_slot_bytes(&cfg->slot);
    if ((bytes < MC_BOOT_IMAGE_MIN_BYTES) || !slot_blocks_ok(&cfg->slot)) {
        err |= MC_BOOT_CFG_ERR_SLOT;
    }
    if (err != MC_BOOT_CFG_OK) {
        return err;
    }
    {
        static const mc_boot_update_t z = {0};
        *u = z;
    }
    u->cfg = *cfg;
    u->slot_bytes = bytes;
    u->state = (uint8_t)ST_IDLE;
    u->now_ms = now_ms;
    u->announce_at_ms = now_ms;
    mc_boot_bucket_init(&u->bucket, now_ms);
    return MC_BOOT_CFG_OK;
}

/* --------------------------------------------------------------- replies */

static uint32_t reply(mc_boot_update_t *u, const reply_t *r, mc_hal_can_frame_t *p_out)
{
    if (!mc_boot_bucket_take(&u->bucket)) {
        u->replies_limited++;
        return 0u;
    }
    mc_boot_reply_frame(u->cfg.node_id, r->op, r->status, u->state, u->cfg.reason, r->value, p_out);
    u->replies++;
    return 1u;
}

static uint32_t info_value(const mc_boot_update_t *u)
{
    return mc_boot_info_value(u->cfg.slot.board_id, u->cfg.slot.layout_id);
}

/* ----------------------------------------------------------------- flash */

static void end_session(mc_boot_update_t *u)
{
    u->state = (uint8_t)ST_IDLE;
    u->blk_open = false;
    u->next_block = 0u;
    u->n_blocks = 0u;
    u->image_bytes = 0u;
}

static bool flash_failed(mc_boot_update_t *u, int rc)
{
    if (rc == 0) {
        return false;
    }
    u->flash_rc = (int32_t)rc;
    end_session(u);
    return true;
}

/* Erase the sectors [0, bytes) of the slot spans, from the first one. */
static int erase_for(mc_boot_update_t *u, uint32_t bytes, uint32_t *p_sectors)
{
    uint32_t off = 0u;
    *p_sectors = 0u;
    while (off < bytes) {
        uint32_t sector = 0u;
        uint32_t sector_off = 0u;
        uint32_t room = 0u;
        int rc;
        if (!mc_boot_slot_locate(&u->cfg.slot, off, &sector, &sector_off, &room)) {
            return -EINVAL;
        }
        rc = mc_hal_flash_erase(u->cfg.slot.flash, sector);
        if (rc != 0) {
            return rc;
        }
        u->sectors_erased++;
        (*p_sectors)++;
        off += room;
    }
    return 0;
}

/* Program len bytes of buf at off of the slot (inside one sector) and read
 * them back. */
static int program_checked(mc_boot_update_t *u, uint32_t off, const uint8_t *buf, uint32_t len)
{
    uint32_t words[MC_BOOT_BLOCK_BYTES / 4u];
    uint8_t back[MC_BOOT_BLOCK_BYTES];
    uint32_t sector = 0u;
    uint32_t sector_off = 0u;
    uint32_t room = 0u;
    int rc;
    if ((len > MC_BOOT_BLOCK_BYTES) || ((len % 4u) != 0u) ||
        !mc_boot_slot_locate(&u->cfg.slot, off, &sector, &sector_off, &room) || (room < len)) {
        return -EINVAL;
    }
    (void)memcpy(words, buf, len); /* little-endian, as the flash's words */
    rc = mc_hal_flash_program(u->cfg.slot.flash, sector, sector_off, words, len / 4u);
    if (rc == 0) {
        rc = mc_hal_flash_read(u->cfg.slot.flash, sector, sector_off, back, len);
    }
    for (uint32_t i = 0u; (rc == 0) && (i < len); ++i) {
        if (back[i] != buf[i]) {
            rc = -EIO;
        }
    }
    return rc;
}

/* -------------------------------------------------------------- requests */

static uint32_t hdr_status(mc_boot_img_t r)
{
    switch (r) {
    case MC_BOOT_IMG_OK:
        return S_OK;
    case MC_BOOT_IMG_BOARD:
        return S_BOARD;
    case MC_BOOT_IMG_LAYOUT:
        return S_LAYOUT;
    case MC_BOOT_IMG_SIZE:
        return S_SIZE;
    default:
        return S_HEADER;
    }
}

static void do_begin(mc_boot_update_t *u, const mc_boot_msg_t *q, reply_t *r)
{
    mc_boot_image_hdr_t h = {0};
    uint32_t sectors = 0u;
    h.magic = MC_BOOT_IMAGE_MAGIC;
    h.board_id = q->arg & 0xFFu;
    h.layout_id = (q->arg >> 8) & 0xFFu;
    h.hdr_version = (q->arg >> 16) & 0xFFu;
    h.image_bytes = q->value;
    r->status = hdr_status(mc_boot_image_check_hdr(&u->cfg.slot, &h));
    if (r->status != S_OK) {
        return; /* refused before anything is erased */
    }
    end_session(u);
    if (flash_failed(u, erase_for(u, h.image_bytes, &sectors))) {
        r->status = S_FLASH;
        return;
    }
    u->state = (uint8_t)ST_RECEIVING;
    u->image_bytes = h.image_bytes;
    u->n_blocks = (h.image_bytes + MC_BOOT_BLOCK_BYTES - 1u) / MC_BOOT_BLOCK_BYTES;
    r->value = sectors;
}

static void do_write(mc_boot_update_t *u, const mc_boot_msg_t *q, reply_t *r, uint32_t *p_send)
{
    const bool repeat =
        (u->next_block > 0u) && (q->arg == u->next_block - 1u) && (q->value == u->last_crc);
    u->blk_open = false;
    r->value = u->next_block;
    if (u->state != ST_RECEIVING) {
        r->status = S_STATE;
        return;
    }
    if ((q->arg != u->next_block || u->next_block >= u->n_blocks) && !repeat) {
        r->status = S_SEQUENCE;
        return;
    }
    /* the block's bytes follow; it is answered when complete or failed */
    u->blk_open = true;
    u->blk_repeat = repeat;
    u->blk_index = q->arg;
    u->blk_crc = q->value;
    u->blk_chunks = 0u;
    u->blk_len = u->image_bytes - q->arg * MC_BOOT_BLOCK_BYTES;
    if (u->blk_len > MC_BOOT_BLOCK_BYTES) {
        u->blk_len = MC_BOOT_BLOCK_BYTES;
    }
    *p_send = 0u;
}

static void do_verify(mc_boot_update_t *u, const mc_boot_msg_t *q, reply_t *r)
{
    mc_boot_image_hdr_t h;
    if ((u->state == ST_RECEIVING) && (u->next_block == u->n_blocks) && !u->blk_open) {
        const mc_boot_img_t c = mc_boot_image_check(&u->cfg.slot, &h);
        r->value = h.crc32;
        if (c == MC_BOOT_IMG_FLASH) {
            r->status = S_FLASH;
        } else if ((c == MC_BOOT_IMG_CRC) || (h.crc32 != q->value)) {
            r->status = S_IMAGE_CRC;
            (void)mc_boot_slot_crc(&u->cfg.slot, h.image_bytes, &r->value);
        } else if ((c != MC_BOOT_IMG_UNCOMMITTED) || (h.image_bytes != u->image_bytes)) {
            r->status = S_HEADER; /* complete, but the boot check would refuse it */
        } else {
            u->state = (uint8_t)ST_VERIFIED;
            return;
        }
        end_session(u);
        return;
    }
    r->status = (u->state == ST_VERIFIED) ? S_OK : S_STATE;
}

static void do_commit(mc_boot_update_t *u, reply_t *r)
{
    static const uint8_t commit[4] = {
        (uint8_t)MC_BOOT_COMMIT_MAGIC, (uint8_t)(MC_BOOT_COMMIT_MAGIC >> 8),
        (uint8_t)(MC_BOOT_COMMIT_MAGIC >> 16), (uint8_t)(MC_BOOT_COMMIT_MAGIC >> 24)};
    if (u->state != ST_VERIFIED) {
        r->status = S_STATE;
        return;
    }
    if (flash_failed(u, program_checked(u, MC_BOOT_COMMIT_WORD_OFFSET, commit, 4u)) ||
        (mc_boot_image_check(&u->cfg.slot, NULL) != MC_BOOT_IMG_OK)) {
        end_session(u);
        r->status = S_FLASH;
        return;
    }
    u->state = (uint8_t)ST_COMMITTED;
    u->action = MC_BOOT_ACT_RESET;
}

/* Reserved fields must be zero: an op's unused arg and value. */
static bool fields_ok(const mc_boot_msg_t *q, bool arg_used, bool value_used)
{
    return (arg_used || (q->arg == 0u)) && (value_used || (q->value == 0u));
}

static uint32_t on_request(mc_boot_update_t *u, const mc_hal_can_frame_t *f,
                           mc_hal_can_frame_t *p_reply)
{
    mc_boot_msg_t q;
    reply_t r = {0u, S_OK, 0u};
    uint32_t send = 1u;
    bool ok;
    mc_boot_req_decode(f->data, &q);
    r.op = q.op;
    switch (q.op) {
    case MC_CAN_VAL_BOOT_OP_INFO:
        ok = fields_ok(&q, false, false);
        r.value = info_value(u);
        break;
    case MC_CAN_VAL_BOOT_OP_VERSION: {
        mc_boot_image_hdr_t h = {0};
        ok = fields_ok(&q, false, false);
        if ((mc_boot_slot_read(&u->cfg.slot, MC_BOOT_HDR_OFFSET, &h, MC_BOOT_HDR_BYTES) == 0) &&
            (h.magic == MC_BOOT_IMAGE_MAGIC)) {
            r.value = h.app_version;
        }
        break;
    }
    case MC_CAN_VAL_BOOT_OP_ENTER:
        ok = fields_ok(&q, false, true);
        r.status = (q.value == MC_BOOT_ENTER_KEY) ? S_OK : S_KEY; /* here already */
        break;
    case MC_CAN_VAL_BOOT_OP_ENTER_CONFIRM:
        ok = fields_ok(&q, false, true);
        break;
    case MC_CAN_VAL_BOOT_OP_BEGIN:
        ok = (u->state != ST_COMMITTED);
        if (ok) {
            do_begin(u, &q, &r);
        }
        break;
    case MC_CAN_VAL_BOOT_OP_WRITE:
        ok = true;
        do_write(u, &q, &r, &send);
        break;
    case MC_CAN_VAL_BOOT_OP_VERIFY:
        ok = fields_ok(&q, false, true);
        if (ok) {
            do_verify(u, &q, &r);
        }
        break;
    case MC_CAN_VAL_BOOT_OP_COMMIT:
        ok = fields_ok(&q, false, false);
        if (ok) {
            do_commit(u, &r);
        }
        break;
    case MC_CAN_VAL_BOOT_OP_ABORT:
        ok = fields_ok(&q, false, false) && (u->state != ST_COMMITTED);
        if (ok) {
            end_session(u);
        }
        break;
    case MC_CAN_VAL_BOOT_OP_RUN:
        ok = fields_ok(&q, false, false);
        if (ok) {
            u->blk_open = false;
            u->action = MC_BOOT_ACT_RESET;
        }
        break;
    default:
        ok = true;
        r.status = S_OPCODE;
        break;
    }
    if (!ok) {
        r.status = ((q.op == MC_CAN_VAL_BOOT_OP_BEGIN) || (q.op == MC_CAN_VAL_BOOT_OP_ABORT))
                       ? S_STATE
                       : S_FORMAT;
    }
    return (send != 0u) ? reply(u, &r, p_reply) : 0u;
}

/* ------------------------------------------------------------ block data */

static uint32_t block_failed(mc_boot_update_t *u, uint32_t status, mc_hal_can_frame_t *p_reply)
{
    const reply_t r = {MC_CAN_VAL_BOOT_OP_WRITE, status, u->next_block};
    u->blk_open = false;
    u->blocks_failed++;
    return reply(u, &r, p_reply);
}

/* The block that holds the header (a header never straddles two blocks). */
#define HDR_BLOCK     (MC_BOOT_HDR_OFFSET / MC_BOOT_BLOCK_BYTES)
#define HDR_IN_BLOCK  (MC_BOOT_HDR_OFFSET % MC_BOOT_BLOCK_BYTES)
#define COMMIT_IN_BLK (MC_BOOT_COMMIT_WORD_OFFSET % MC_BOOT_BLOCK_BYTES)
_Static_assert(HDR_IN_BLOCK + MC_BOOT_HDR_BYTES <= MC_BOOT_BLOCK_BYTES,
               "the image header must lie inside one block");

/* The header's block: the header must agree with BEGIN (it is the same
 * image), and its commit word is written erased (the bootloader writes it
 * at COMMIT, after VERIFY). Host and MCU are little-endian, as the flash. */
static uint32_t header_block(mc_boot_update_t *u)
{
    mc_boot_image_hdr_t h;
    (void)memcpy(&h, &u->blk[HDR_IN_BLOCK], sizeof h);
    if ((mc_boot_image_check_hdr(&u->cfg.slot, &h) != MC_BOOT_IMG_OK) ||
        (h.image_bytes != u->image_bytes)) {
        return S_HEADER;
    }
    (void)memset(&u->blk[COMMIT_IN_BLK], 0xFF, 4u);
    return S_OK;
}

static uint32_t block_complete(mc_boot_update_t *u, mc_hal_can_frame_t *p_reply)
{
    const reply_t ok = {MC_CAN_VAL_BOOT_OP_WRITE, S_OK, 0u};
    reply_t r = ok;
    u->blk_open = false;
    if (mc_crc32(u->blk, u->blk_len) != u->blk_crc) {
        return block_failed(u, S_BLOCK_CRC, p_reply);
    }
    if (!u->blk_repeat) {
        const uint32_t st = (u->blk_index == HDR_BLOCK) ? header_block(u) : S_OK;
        if (st != S_OK) {
            return block_failed(u, st, p_reply);
        }
        if (flash_failed(
                u, program_checked(u, u->blk_index * MC_BOOT_BLOCK_BYTES, u->blk, u->blk_len))) {
            return block_failed(u, S_FLASH, p_reply);
        }
        u->next_block++;
        u->last_crc = u->blk_crc;
        u->blocks_written++;
    }
    r.value = u->next_block;
    return reply(u, &r, p_reply);
}

static uint32_t on_data(mc_boot_update_t *u, const mc_hal_can_frame_t *f,
                        mc_hal_can_frame_t *p_reply)
{
    const uint32_t at = u->blk_chunks * MC_BOOT_CHUNK_BYTES;
    uint32_t n;
    if (!u->blk_open) {
        u->rx_ignored++; /* no block open, or the rest of a failed one */
        return 0u;
    }
    if (f->data[0] != u->blk_chunks) {
        return block_failed(u, S_SEQUENCE, p_reply); /* dropped, repeated, reordered */
    }
    n = u->blk_len - at;
    if (n > MC_BOOT_CHUNK_BYTES) {
        n = MC_BOOT_CHUNK_BYTES;
    }
    for (uint32_t i = 0u; i < MC_BOOT_CHUNK_BYTES; ++i) {
        if (i < n) {
            u->blk[at + i] = f->data[1u + i];
        } else if (f->data[1u + i] != 0u) {
            return block_failed(u, S_FORMAT, p_reply); /* padding must be 0 */
        }
    }
    u->blk_chunks++;
    return (at + n >= u->blk_len) ? block_complete(u, p_reply) : 0u;
}

/* -------------------------------------------------------------- frames */

uint32_t mc_boot_update_rx(mc_boot_update_t *u, const mc_hal_can_frame_t *p_frame,
                           mc_hal_can_frame_t *p_reply)
{
    const reply_t format = {0u, S_FORMAT, 0u};
    reply_t r = format;
    bool req;
    if ((u == NULL) || (p_frame == NULL) || (p_reply == NULL)) {
        return 0u;
    }
    req = mc_boot_frame_is(p_frame, u->cfg.node_id, MC_CAN_CMD_BOOT_REQ);
    if (!req && !mc_boot_frame_is(p_frame, u->cfg.node_id, MC_CAN_CMD_BOOT_DATA)) {
        u->rx_ignored++;
        return 0u;
    }
    u->rx_own++;
    if (((p_frame->flags & (MC_HAL_CAN_FLAG_RTR | MC_HAL_CAN_FLAG_FD)) != 0u) ||
        (p_frame->len != MC_BOOT_FRAME_BYTES)) {
        if (!req) {
            return u->blk_open ? block_failed(u, S_FORMAT, p_reply) : 0u;
        }
        r.op = (p_frame->len > 0u) ? p_frame->data[0] : 0u;
        return reply(u, &r, p_reply);
    }
    return req ? on_request(u, p_frame, p_reply) : on_data(u, p_frame, p_reply);
}

uint32_t mc_boot_update_poll(mc_boot_update_t *u, uint32_t now_ms, mc_hal_can_frame_t *p_out)
{
    reply_t r = {MC_CAN_VAL_BOOT_OP_ANNOUNCE, S_OK, 0u};
    if ((u == NULL) || (p_out == NULL)) {
        return 0u;
    }
    u->now_ms = now_ms;
    mc_boot_bucket_refill(&u->bucket, now_ms);
    if ((u->state == ST_COMMITTED) || ((int32_t)(now_ms - u->announce_at_ms) < 0)) {
        return 0u;
    }
    u->announce_at_ms = now_ms + MC_BOOT_ANNOUNCE_MS;
    r.value = info_value(u);
    return reply(u, &r, p_out);
}

mc_boot_action_t mc_boot_update_action(const mc_boot_update_t *u)
{
    return (u != NULL) ? u->action : MC_BOOT_ACT_NONE;
}
