/**
 * @file mc_boot_link.c
 * @brief The emulated bootloader's link frames: see mc_boot_link.h.
 */
#include "mc_boot_link.h"

#include <string.h>

#include "mc_pil_frame.h"

void mc_boot_link_put32(mc_boot_link_msg_t *m, uint32_t v)
{
    if ((size_t)m->len + 4u > MC_BOOT_LINK_MAX_PAYLOAD) {
        return;
    }
    for (uint32_t i = 0u; i < 4u; ++i) {
        m->payload[m->len + i] = (uint8_t)(v >> (8u * i));
    }
    m->len = (uint16_t)(m->len + 4u);
}

uint32_t mc_boot_link_get32(const mc_boot_link_msg_t *m, uint32_t i)
{
    uint32_t v = 0u;
    if ((size_t)4u * i + 4u > m->len) {
        return 0u;
    }
    for (uint32_t k = 0u; k < 4u; ++k) {
        v |= (uint32_t)m->payload[4u * i + k] << (8u * k);
    }
    return v;
}

size_t mc_boot_link_encode(const mc_boot_link_msg_t *m, uint8_t *buf, size_t cap)
{
    const size_t n = MC_BOOT_LINK_HEADER + (size_t)m->len + 2u;
    uint16_t crc;
    if ((buf == NULL) || (cap < n) || (m->len > MC_BOOT_LINK_MAX_PAYLOAD)) {
        return 0u;
    }
    buf[0] = MC_BOOT_LINK_SYNC;
    buf[1] = m->type;
    buf[2] = (uint8_t)(m->len & 0xFFu);
    buf[3] = (uint8_t)(m->len >> 8);
    (void)memcpy(&buf[MC_BOOT_LINK_HEADER], m->payload, m->len);
    crc = mc_pil_crc16(&buf[1], (size_t)3u + m->len);
    buf[n - 2u] = (uint8_t)(crc & 0xFFu);
    buf[n - 1u] = (uint8_t)(crc >> 8);
    return n;
}

void mc_boot_link_put_can(mc_boot_link_msg_t *m, const mc_hal_can_frame_t *f)
{
    uint32_t lo = 0u;
    uint32_t hi = 0u;
    for (uint32_t i = 0u; i < 4u; ++i) {
        lo |= (uint32_t)f->data[i] << (8u * i);
        hi |= (uint32_t)f->data[4u + i] << (8u * i);
    }
    mc_boot_link_put32(m, f->id);
    mc_boot_link_put32(m, (uint32_t)f->len | ((uint32_t)f->flags << 8));
    mc_boot_link_put32(m, lo);
    mc_boot_link_put32(m, hi);
}

int mc_boot_link_get_can(const mc_boot_link_msg_t *m, uint32_t at, mc_hal_can_frame_t *f)
{
    const uint32_t lf = mc_boot_link_get32(m, at + 1u);
    const uint32_t lo = mc_boot_link_get32(m, at + 2u);
    const uint32_t hi = mc_boot_link_get32(m, at + 3u);
    if (((lf & 0xFFu) > MC_HAL_CAN_MAX_LEN) || ((size_t)m->len < (size_t)4u * (at + 4u))) {
        return -1;
    }
    (void)memset(f, 0, sizeof *f);
    f->id = mc_boot_link_get32(m, at);
    f->len = (uint8_t)(lf & 0xFFu);
    f->flags = (uint8_t)((lf >> 8) & 0xFFu);
    for (uint32_t i = 0u; i < 4u; ++i) {
        f->data[i] = (uint8_t)(lo >> (8u * i));
        f->data[4u + i] = (uint8_t)(hi >> (8u * i));
    }
    return 0;
}

/* Drop the first byte of the buffer and look for the next sync in it. */
static void resync(mc_boot_link_rx_t *rx)
{
    size_t k = 1u;
    while ((k < rx->n) && (rx->buf[k] != MC_BOOT_LINK_SYNC)) {
        k++;
    }
    rx->dropped += (uint32_t)k;
    (void)memmove(rx->buf, &rx->buf[k], rx->n - k);
    rx->n -= k;
}

int mc_boot_link_feed(mc_boot_link_rx_t *rx, uint8_t b, mc_boot_link_msg_t *m)
{
    if ((rx->n == 0u) && (b != MC_BOOT_LINK_SYNC)) {
        rx->dropped++;
        return 0;
    }
    rx->buf[rx->n++] = b;
    for (;;) {
        if (rx->n < MC_BOOT_LINK_HEADER) {
            return 0;
        }
        const size_t len = (size_t)rx->buf[2] | ((size_t)rx->buf[3] << 8);
        if (len > MC_BOOT_LINK_MAX_PAYLOAD) {
            resync(rx);
            continue;
        }
        const size_t total = MC_BOOT_LINK_HEADER + len + 2u;
        if (rx->n < total) {
            return 0;
        }
        const uint16_t crc =
            (uint16_t)((uint32_t)rx->buf[total - 2u] | ((uint32_t)rx->buf[total - 1u] << 8));
        if (crc != mc_pil_crc16(&rx->buf[1], 3u + len)) {
            resync(rx);
            continue;
        }
        m->type = rx->buf[1];
        m->len = (uint16_t)len;
        (void)memcpy(m->payload, &rx->buf[MC_BOOT_LINK_HEADER], len);
        rx->n -= total;
        (void)memmove(rx->buf, &rx->buf[total], rx->n);
        return 1;
    }
}
