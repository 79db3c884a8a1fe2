/**
 * @file mc_crc32.h
 * @brief CRC-32 (IEEE 802.3 / zlib: reflected polynomial 0xEDB88320, initial
 *        value and final XOR 0xFFFFFFFF; check value of "123456789" is
 *        0xCBF43926). Bitwise: no table in flash, speed does not matter for
 *        a configuration record of a few hundred bytes.
 */
#ifndef MC_CRC32_H
#define MC_CRC32_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MC_CRC32_INIT 0xFFFFFFFFu

/** Continue a CRC over len bytes; start with MC_CRC32_INIT and finish with
 *  mc_crc32_final. */
uint32_t mc_crc32_update(uint32_t state, const void *data, size_t len);

static inline uint32_t mc_crc32_final(uint32_t state)
{
    return state ^ 0xFFFFFFFFu;
}

/** CRC-32 of one buffer. */
static inline uint32_t mc_crc32(const void *data, size_t len)
{
    return mc_crc32_final(mc_crc32_update(MC_CRC32_INIT, data, len));
}

#ifdef __cplusplus
}
#endif

#endif /* MC_CRC32_H */
