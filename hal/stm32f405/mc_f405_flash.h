/**
 * @file mc_f405_flash.h
 * @brief STM32F405 embedded flash (RM0090 section 3): the hal/flash.h
 *        contract at register level: unlock (FLASH_KEYR), sector erase
 *        (CR.SER/SNB/STRT), 32-bit word program (CR.PG, PSIZE = x32, needs
 *        VDD 2.7..3.6 V), error flags (SR.WRPERR/PGAERR/PGPERR/PGSERR/
 *        OPERR), lock again after every operation (CR.LOCK).
 *
 * Sector map of the 1 MiB F405 (RM0090 table 5): sectors 0..3 16 KiB at
 * 0x08000000, sector 4 64 KiB at 0x08010000, sectors 5..11 128 KiB from
 * 0x08020000. Sectors whose bit is set in protect_mask (the code) are
 * refused with -EINVAL.
 *
 * Like the other drivers it reaches the hardware only through pointers in
 * its config (the FLASH registers and the memory-mapped array), so the host
 * test runs it against RAM. hw_poll (NULL on the MCU) lets that test model
 * the controller: it is called after each KEYR write and in every busy wait.
 */
#ifndef MC_F405_FLASH_H
#define MC_F405_FLASH_H

#include <stdint.h>

#include "hal/flash.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_F405_FLASH_R_BASE   0x40023C00u /**< FLASH interface registers */
#define MC_F405_FLASH_MEM_BASE 0x08000000u /**< main memory */
#define MC_F405_FLASH_SECTORS  12u

#define MC_F405_FLASH_KEY1 0x45670123u
#define MC_F405_FLASH_KEY2 0xCDEF89ABu

#define MC_F405_FLASH_SR_EOP    (1u << 0)
#define MC_F405_FLASH_SR_OPERR  (1u << 1)
#define MC_F405_FLASH_SR_WRPERR (1u << 4)
#define MC_F405_FLASH_SR_PGAERR (1u << 5)
#define MC_F405_FLASH_SR_PGPERR (1u << 6)
#define MC_F405_FLASH_SR_PGSERR (1u << 7)
#define MC_F405_FLASH_SR_BSY    (1u << 16)
#define MC_F405_FLASH_SR_ERRORS                                                   \
    (MC_F405_FLASH_SR_OPERR | MC_F405_FLASH_SR_WRPERR | MC_F405_FLASH_SR_PGAERR | \
     MC_F405_FLASH_SR_PGPERR | MC_F405_FLASH_SR_PGSERR)

#define MC_F405_FLASH_CR_PG        (1u << 0)
#define MC_F405_FLASH_CR_SER       (1u << 1)
#define MC_F405_FLASH_CR_SNB_SHIFT 3u
#define MC_F405_FLASH_CR_SNB_MASK  (0xFu << 3)
#define MC_F405_FLASH_CR_PSIZE_X32 (2u << 8)
#define MC_F405_FLASH_CR_STRT      (1u << 16)
#define MC_F405_FLASH_CR_LOCK      (1u << 31)

typedef struct mc_f405_flash_regs {
    volatile uint32_t ACR;     /* 0x00 */
    volatile uint32_t KEYR;    /* 0x04 */
    volatile uint32_t OPTKEYR; /* 0x08 */
    volatile uint32_t SR;      /* 0x0C, flags rc_w1 */
    volatile uint32_t CR;      /* 0x10 */
    volatile uint32_t OPTCR;   /* 0x14 */
} mc_f405_flash_regs_t;

typedef struct {
    mc_f405_flash_regs_t *p_regs;
    volatile uint8_t *p_mem;    /**< the array's base (0x08000000 on the MCU) */
    uint32_t protect_mask;      /**< bit n: sector n refused (holds the code) */
    uint32_t busy_spin_max;     /**< polls of SR.BSY before -EIO (erase of
                                       128 KiB: up to 2 s) */
    void (*hw_poll)(void *ctx); /**< host test model; NULL on the MCU */
    void *hw_ctx;
} mc_f405_flash_config_t;

typedef struct {
    mc_hal_flash_t dev;
    mc_f405_flash_config_t cfg;
} mc_f405_flash_t;

/** Sector start offset from the array base and size (RM0090 table 5). */
int mc_f405_flash_sector_geometry(uint32_t sector, uint32_t *p_offset, uint32_t *p_bytes);

/** Returns 0 or -EINVAL (NULL pointers, busy_spin_max 0). */
int mc_f405_flash_init(mc_f405_flash_t *f, const mc_f405_flash_config_t *cfg);

#ifdef __cplusplus
}
#endif

#endif /* MC_F405_FLASH_H */
