/**
 * @file mc_crc32.c
 * @brief CRC-32, bitwise: see mc_crc32.h.
 */
#include "mc_crc32.h"

uint32_t mc_crc32_update(uint32_t state, const void *data, size_t len)
{
    const uint8_t *p = (const uint8_t *)data;
    uint32_t c = state;
    for (size_t i = 0u; i < len; ++i) {
        c ^= (uint32_t)p[i];
        for (uint32_t b = 0u; b < 8u; ++b) {
            const uint32_t mask = 0u - (c & 1u);
            c = (c >> 1) ^ (0xEDB88320u & mask);
        }
    }
    return c;
}
