/**
 * @file mc_boot_enter.c
 * @brief The application's side of the firmware update: see mc_boot_enter.h.
 */
#include "mc_boot_enter.h"

#include <stddef.h>

#define S_OK      MC_CAN_VAL_BOOT_STATUS_OK
#define S_OPCODE  MC_CAN_VAL_BOOT_STATUS_OPCODE
#define S_FORMAT  MC_CAN_VAL_BOOT_STATUS_FORMAT
#define S_STATE   MC_CAN_VAL_BOOT_STATUS_STATE
#define S_CONFIRM MC_CAN_VAL_BOOT_STATUS_CONFIRM
#define S_KEY     MC_CAN_VAL_BOOT_STATUS_KEY
#define S_BUSY    MC_CAN_VAL_BOOT_STATUS_BUSY

#define CONFIRM_US (1000u * MC_BOOT_CONFIRM_MS)

void mc_boot_enter_init(mc_boot_enter_t *e, const mc_boot_enter_cfg_t *cfg, uint8_t node_id,
                        uint32_t step_hz, uint32_t seed)
{
    static const mc_boot_enter_t z = {0};
    *e = z;
    e->cfg = *cfg;
    e->node_id = node_id;
    e->us_per_step = ((step_hz == 0u) || (step_hz > 1000000u)) ? 1000u : (1000000u / step_hz);
    e->rng = seed ^ 0x9E3779B9u;
    if (e->rng == 0u) {
        e->rng = 1u;
    }
    mc_boot_bucket_init(&e->bucket, 0u);
}

/* A fresh non-zero token (xorshift32, mixed with the time of the request). */
static uint32_t next_token(mc_boot_enter_t *e)
{
    uint32_t x = e->rng ^ e->now_us;
    do {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
    } while (x == 0u);
    e->rng = x;
    return x;
}

static uint32_t do_enter(mc_boot_enter_t *e, const mc_boot_msg_t *q, bool busy, uint32_t *p_value)
{
    if (q->value != MC_BOOT_ENTER_KEY) {
        return S_KEY;
    }
    if (busy) {
        return S_BUSY;
    }
    e->token = next_token(e);
    e->token_us = e->now_us;
    *p_value = e->token;
    return S_CONFIRM;
}

static uint32_t do_confirm(mc_boot_enter_t *e, const mc_boot_msg_t *q, bool busy)
{
    const bool fresh = (e->token != 0u) && ((e->now_us - e->token_us) <= CONFIRM_US);
    if (busy) {
        return S_BUSY;
    }
    if (!fresh || (q->value != e->token)) {
        e->token = 0u; /* one try per token */
        return S_KEY;
    }
    e->token = 0u;
    e->due = true;
    return S_OK;
}

uint32_t mc_boot_enter_handle(mc_boot_enter_t *e, const mc_hal_can_frame_t *p_frame, bool busy,
                              mc_hal_can_frame_t *p_reply)
{
    mc_boot_msg_t q = {0u, 0u, 0u};
    uint32_t st = S_OK;
    uint32_t value = 0u;
    if ((e == NULL) || (p_frame == NULL) || (p_reply == NULL)) {
        return 0u;
    }
    if ((p_frame->len != MC_BOOT_FRAME_BYTES) ||
        ((p_frame->flags & (MC_HAL_CAN_FLAG_RTR | MC_HAL_CAN_FLAG_FD)) != 0u)) {
        q.op = (p_frame->len > 0u) ? p_frame->data[0] : 0u;
        st = S_FORMAT;
    } else {
        mc_boot_req_decode(p_frame->data, &q);
        if (q.arg != 0u) {
            st = (q.op < MC_CAN_VAL_BOOT_OP_BEGIN) ? S_FORMAT : S_STATE;
        } else if (q.op == MC_CAN_VAL_BOOT_OP_INFO) {
            value = mc_boot_info_value(e->cfg.board_id, e->cfg.layout_id);
            st = (q.value == 0u) ? S_OK : S_FORMAT;
        } else if (q.op == MC_CAN_VAL_BOOT_OP_VERSION) {
            value = e->cfg.app_version;
            st = (q.value == 0u) ? S_OK : S_FORMAT;
        } else if (q.op == MC_CAN_VAL_BOOT_OP_ENTER) {
            st = do_enter(e, &q, busy, &value);
        } else if (q.op == MC_CAN_VAL_BOOT_OP_ENTER_CONFIRM) {
            st = do_confirm(e, &q, busy);
        } else if ((q.op >= MC_CAN_VAL_BOOT_OP_BEGIN) && (q.op <= MC_CAN_VAL_BOOT_OP_RUN)) {
            st = S_STATE; /* the bootloader's */
        } else {
            st = S_OPCODE;
        }
    }
    if (!mc_boot_bucket_take(&e->bucket)) {
        e->replies_limited++;
        return 0u;
    }
    mc_boot_reply_frame(e->node_id, q.op, st, MC_CAN_VAL_BOOT_STATE_APP,
                        MC_CAN_VAL_BOOT_REASON_NONE, value, p_reply);
    return 1u;
}

void mc_boot_enter_step(mc_boot_enter_t *e)
{
    if (e == NULL) {
        return;
    }
    e->now_us += e->us_per_step;
    mc_boot_bucket_refill(&e->bucket, e->now_us / 1000u);
    if ((e->token != 0u) && ((e->now_us - e->token_us) > CONFIRM_US)) {
        e->token = 0u;
    }
}

bool mc_boot_enter_due(const mc_boot_enter_t *e)
{
    return (e != NULL) && e->due;
}
