/**
 * @file mc_boot_proto.c
 * @brief Firmware update messages: see mc_boot_proto.h.
 */
#include "mc_boot_proto.h"

#include <stddef.h>

#include "mc_can_proto.h"

void mc_boot_bucket_init(mc_boot_bucket_t *b, uint32_t now_ms)
{
    b->tokens = MC_BOOT_REPLY_BURST;
    b->last_ms = now_ms;
    b->acc = 0u;
}

void mc_boot_bucket_refill(mc_boot_bucket_t *b, uint32_t now_ms)
{
    uint32_t dt = now_ms - b->last_ms;
    b->last_ms = now_ms;
    if (dt > 1000u) {
        dt = 1000u; /* a second refills the whole burst anyway */
    }
    b->acc += dt * MC_BOOT_REPLY_MAX_HZ;
    while (b->acc >= 1000u) {
        b->acc -= 1000u;
        if (b->tokens < MC_BOOT_REPLY_BURST) {
            b->tokens++;
        }
    }
}

bool mc_boot_bucket_take(mc_boot_bucket_t *b)
{
    if (b->tokens == 0u) {
        return false;
    }
    b->tokens--;
    return true;
}

bool mc_boot_frame_is(const mc_hal_can_frame_t *p_frame, uint32_t node_id, uint32_t cmd)
{
    return ((p_frame->flags & MC_HAL_CAN_FLAG_EXT) == 0u) &&
           (p_frame->id <= MC_HAL_CAN_STD_ID_MAX) && (p_frame->id == mc_can_id(node_id, cmd));
}

static uint32_t le32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

void mc_boot_req_decode(const uint8_t data[MC_BOOT_FRAME_BYTES], mc_boot_msg_t *p_req)
{
    p_req->op = data[0];
    p_req->arg = (uint32_t)data[1] | ((uint32_t)data[2] << 8) | ((uint32_t)data[3] << 16);
    p_req->value = le32(&data[4]);
}

void mc_boot_reply_frame(uint32_t node_id, uint32_t op, uint32_t status, uint32_t state,
                         uint32_t reason, uint32_t value, mc_hal_can_frame_t *p_frame)
{
    p_frame->id = mc_can_id(node_id, MC_CAN_CMD_BOOT_REPLY);
    p_frame->timestamp_ticks = 0u;
    p_frame->len = (uint8_t)MC_BOOT_FRAME_BYTES;
    p_frame->flags = 0u;
    p_frame->data[0] = (uint8_t)op;
    p_frame->data[1] = (uint8_t)status;
    p_frame->data[2] = (uint8_t)state;
    p_frame->data[3] = (uint8_t)reason;
    for (uint32_t i = 0u; i < 4u; ++i) {
        p_frame->data[4u + i] = (uint8_t)(value >> (8u * i));
    }
}

uint32_t mc_boot_info_value(uint32_t board_id, uint32_t layout_id)
{
    return (board_id & 0xFFu) | ((layout_id & 0xFFu) << 8) | (MC_BOOT_PROTO_VERSION << 16);
}
