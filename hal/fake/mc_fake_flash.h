/**
 * @file mc_fake_flash.h
 * @brief A fake NOR flash (hal/flash.h) in caller-owned RAM, with power-cut
 *        injection, for the configuration store's tests.
 *
 * Behaviour: erase sets a sector to 0xFF; program ANDs each word into the
 * memory (NOR: bits only clear); read copies. Every erase and every
 * programmed word is one step (steps counts them from init).
 *
 * Power cut: mc_fake_flash_cut_at(f, k, tear) makes step k (1-based, from
 * now) the last one: with MC_FAKE_FLASH_TEAR_NONE it does not happen at all;
 * with MC_FAKE_FLASH_TEAR_HALF an erase erases only the first half of the
 * sector and leaves the rest as it was, and a program clears only the bits
 * of the word's low half (a word caught half way). From then on the device
 * is powered off: every call returns -EIO and changes nothing. "Reboot" by
 * calling mc_fake_flash_init again on the same memory.
 *
 * No heap: the memory and the sector map belong to the caller.
 */
#ifndef MC_FAKE_FLASH_H
#define MC_FAKE_FLASH_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/flash.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_FAKE_FLASH_MAX_SECTORS 16u

typedef enum {
    MC_FAKE_FLASH_TEAR_NONE = 0, /**< the cut step has no effect */
    MC_FAKE_FLASH_TEAR_HALF = 1, /**< the cut step is half done */
} mc_fake_flash_tear_t;

typedef struct {
    mc_hal_flash_t dev; /**< hand this to the code under test */
    uint8_t *mem;       /**< all sectors back to back */
    uint32_t n_sectors;
    uint32_t sector_bytes[MC_FAKE_FLASH_MAX_SECTORS];
    uint32_t sector_start[MC_FAKE_FLASH_MAX_SECTORS];
    uint32_t steps; /**< erases + programmed words since init */
    uint32_t erases;
    uint32_t words;
    uint32_t cut_step; /**< step number that loses power; 0: none */
    mc_fake_flash_tear_t tear;
    bool dead;     /**< power is off */
    int fail_next; /**< next erase/program returns this (<0), once */
} mc_fake_flash_t;

/** Bind f to mem (sum of sector sizes bytes; left as is: "power on" with
 *  the old contents). Sizes multiples of 4. Returns 0 or -EINVAL. */
int mc_fake_flash_init(mc_fake_flash_t *f, uint8_t *mem, const uint32_t *sector_bytes,
                       uint32_t n_sectors);

/** Lose power at the k-th step from now (k >= 1). */
void mc_fake_flash_cut_at(mc_fake_flash_t *f, uint32_t k, mc_fake_flash_tear_t tear);

#ifdef __cplusplus
}
#endif

#endif /* MC_FAKE_FLASH_H */
