/**
 * @file mc_can_proto.c
 * @brief CAN protocol codec: see mc_can_proto.h.
 */
#include "mc_can_proto.h"

#include <stddef.h>

#include "math/mc_math.h"

uint32_t mc_can_proto_find(uint32_t cmd)
{
    uint32_t i;
    for (i = 0u; i < MC_CAN_MSG_COUNT; i++) {
        if ((uint32_t)mc_can_messages[i].cmd == cmd) {
            return i;
        }
    }
    return MC_CAN_MSG_COUNT;
}

static uint64_t load_le64(const uint8_t *data, uint32_t len)
{
    uint64_t w = 0u;
    uint32_t i;
    for (i = 0u; (i < len) && (i < 8u); i++) {
        w |= (uint64_t)data[i] << (8u * i);
    }
    return w;
}

static void store_le64(uint64_t w, uint8_t *data, uint32_t len)
{
    uint32_t i;
    for (i = 0u; (i < len) && (i < 8u); i++) {
        data[i] = (uint8_t)((w >> (8u * i)) & 0xFFu);
    }
}

static uint64_t field_mask(uint32_t length)
{
    return (length >= 64u) ? ~(uint64_t)0u : (((uint64_t)1u << length) - 1u);
}

/* Raw range of a field: [-2^(n-1), 2^(n-1) - 1] or [0, 2^n - 1]. */
static void raw_limits(const mc_can_signal_t *s, int64_t *p_lo, int64_t *p_hi)
{
    if (s->is_signed) {
        const int64_t half = (int64_t)((uint64_t)1u << (s->length - 1u));
        *p_lo = -half;
        *p_hi = half - 1;
    } else {
        *p_lo = 0;
        *p_hi = (int64_t)field_mask(s->length);
    }
}

static int64_t phys_to_raw(const mc_can_signal_t *s, float value)
{
    float v = value;
    int64_t lo;
    int64_t hi;
    int64_t raw;
    if (!mc_isfinite_f32(v)) {
        /* NaN -> 0; infinities saturate below */
        if (v > 0.0f) {
            v = s->max;
        } else if (v < 0.0f) {
            v = s->min;
        } else {
            v = 0.0f;
        }
    }
    if (v < s->min) {
        v = s->min;
    }
    if (v > s->max) {
        v = s->max;
    }
    {
        const float r = (v - s->offset) / s->scale;
        raw = (r >= 0.0f) ? (int64_t)(r + 0.5f) : -(int64_t)(0.5f - r);
    }
    raw_limits(s, &lo, &hi);
    if (raw < lo) {
        raw = lo;
    }
    if (raw > hi) {
        raw = hi;
    }
    return raw;
}

mc_can_err_t mc_can_proto_pack(uint32_t msg, uint32_t node_id, const float *values,
                               uint32_t n_values, mc_hal_can_frame_t *p_frame)
{
    const mc_can_message_t *m;
    uint64_t w = 0u;
    uint32_t i;
    if ((values == NULL) || (p_frame == NULL) || (msg >= MC_CAN_MSG_COUNT) ||
        (node_id > MC_CAN_NODE_ID_MAX)) {
        return MC_CAN_ERR_ARG;
    }
    m = &mc_can_messages[msg];
    if (n_values < (uint32_t)m->n_signals) {
        return MC_CAN_ERR_ARG;
    }
    for (i = 0u; i < (uint32_t)m->n_signals; i++) {
        const mc_can_signal_t *s = &m->signals[i];
        const uint64_t raw = (uint64_t)phys_to_raw(s, values[i]) & field_mask(s->length);
        w |= raw << s->start_bit;
    }
    p_frame->id = mc_can_id(node_id, m->cmd);
    p_frame->len = m->dlc;
    p_frame->flags = 0u;
    for (i = 0u; i < MC_HAL_CAN_FD_MAX_LEN; i++) {
        p_frame->data[i] = 0u;
    }
    store_le64(w, p_frame->data, m->dlc);
    return MC_CAN_ERR_NONE;
}

mc_can_err_t mc_can_proto_unpack(const mc_hal_can_frame_t *p_frame, uint32_t *p_msg, float *values,
                                 uint32_t n_values)
{
    const mc_can_message_t *m;
    uint32_t msg;
    uint64_t w;
    uint32_t i;
    if ((p_frame == NULL) || (p_msg == NULL) || (values == NULL)) {
        return MC_CAN_ERR_ARG;
    }
    if ((p_frame->flags & (MC_HAL_CAN_FLAG_EXT | MC_HAL_CAN_FLAG_RTR | MC_HAL_CAN_FLAG_FD |
                           MC_HAL_CAN_FLAG_BRS)) != 0u) {
        return MC_CAN_ERR_FORMAT;
    }
    msg = mc_can_proto_find(mc_can_id_cmd(p_frame->id));
    if (msg >= MC_CAN_MSG_COUNT) {
        return MC_CAN_ERR_UNKNOWN_CMD;
    }
    m = &mc_can_messages[msg];
    if (p_frame->len != m->dlc) {
        return MC_CAN_ERR_LENGTH;
    }
    if (n_values < (uint32_t)m->n_signals) {
        return MC_CAN_ERR_ARG;
    }
    w = load_le64(p_frame->data, p_frame->len);
    for (i = 0u; i < (uint32_t)m->n_signals; i++) {
        const mc_can_signal_t *s = &m->signals[i];
        const uint64_t u = (w >> s->start_bit) & field_mask(s->length);
        int64_t raw = (int64_t)u;
        float v;
        if (s->is_signed && ((u >> (s->length - 1u)) & 1u) != 0u) {
            raw -= (int64_t)((uint64_t)1u << s->length); /* two's complement */
        }
        v = (float)raw * s->scale + s->offset;
        /* half a raw step of slack: a DBC bound that is not a multiple of
         * the scale is still reachable by the nearest raw value */
        if ((v < s->min - 0.5f * s->scale) || (v > s->max + 0.5f * s->scale)) {
            return MC_CAN_ERR_RANGE;
        }
        values[i] = v;
    }
    *p_msg = msg;
    return MC_CAN_ERR_NONE;
}
