/**
 * @file mc_f405_flash.c
 * @brief STM32F405 flash driver (RM0090 3.5-3.7): see mc_f405_flash.h.
 */
#include "mc_f405_flash.h"

#include <stddef.h>

int mc_f405_flash_sector_geometry(uint32_t sector, uint32_t *p_offset, uint32_t *p_bytes)
{
    if ((p_offset == NULL) || (p_bytes == NULL) || (sector >= MC_F405_FLASH_SECTORS)) {
        return -EINVAL;
    }
    if (sector < 4u) {
        *p_offset = sector * 0x4000u;
        *p_bytes = 0x4000u;
    } else if (sector == 4u) {
        *p_offset = 0x10000u;
        *p_bytes = 0x10000u;
    } else {
        *p_offset = 0x20000u + (sector - 5u) * 0x20000u;
        *p_bytes = 0x20000u;
    }
    return 0;
}

static void poll(const mc_f405_flash_t *f)
{
    if (f->cfg.hw_poll != NULL) {
        f->cfg.hw_poll(f->cfg.hw_ctx);
    }
}

/* Wait for SR.BSY to clear; 0 or -EIO (timeout). */
static int wait_idle(const mc_f405_flash_t *f)
{
    for (uint32_t i = 0u; i < f->cfg.busy_spin_max; ++i) {
        poll(f);
        if ((f->cfg.p_regs->SR & MC_F405_FLASH_SR_BSY) == 0u) {
            return 0;
        }
    }
    return -EIO;
}

/* RM0090 3.5.1: KEY1 then KEY2 into KEYR clears CR.LOCK. */
static int unlock(const mc_f405_flash_t *f)
{
    mc_f405_flash_regs_t *r = f->cfg.p_regs;
    if (wait_idle(f) != 0) {
        return -EIO;
    }
    if ((r->CR & MC_F405_FLASH_CR_LOCK) != 0u) {
        r->KEYR = MC_F405_FLASH_KEY1;
        poll(f);
        r->KEYR = MC_F405_FLASH_KEY2;
        poll(f);
        if ((r->CR & MC_F405_FLASH_CR_LOCK) != 0u) {
            return -EIO; /* a wrong sequence locks the controller until reset */
        }
    }
    /* rc_w1: write back the flags that are set, clearing them */
    r->SR = r->SR & (MC_F405_FLASH_SR_EOP | MC_F405_FLASH_SR_ERRORS);
    return 0;
}

/* Clear the operation bits and lock again; rc passes through. */
static int finish(const mc_f405_flash_t *f, int rc)
{
    mc_f405_flash_regs_t *r = f->cfg.p_regs;
    r->CR = MC_F405_FLASH_CR_LOCK;
    return rc;
}

static int check_sr(const mc_f405_flash_t *f)
{
    mc_f405_flash_regs_t *r = f->cfg.p_regs;
    const uint32_t sr = r->SR;
    if ((sr & MC_F405_FLASH_SR_ERRORS) != 0u) {
        r->SR = sr & MC_F405_FLASH_SR_ERRORS;
        return -EIO;
    }
    return 0;
}

static int op_sector_size(void *ctx, uint32_t sector, uint32_t *p_bytes)
{
    uint32_t off = 0u;
    (void)ctx;
    return mc_f405_flash_sector_geometry(sector, &off, p_bytes);
}

static int op_erase(void *ctx, uint32_t sector)
{
    const mc_f405_flash_t *f = (const mc_f405_flash_t *)ctx;
    mc_f405_flash_regs_t *r = f->cfg.p_regs;
    int rc;
    if ((sector >= MC_F405_FLASH_SECTORS) || (((f->cfg.protect_mask >> sector) & 1u) != 0u)) {
        return -EINVAL;
    }
    if (unlock(f) != 0) {
        return finish(f, -EIO);
    }
    /* RM0090 3.6.3: SER with the sector number, then STRT */
    r->CR =
        MC_F405_FLASH_CR_PSIZE_X32 | MC_F405_FLASH_CR_SER | (sector << MC_F405_FLASH_CR_SNB_SHIFT);
    r->CR |= MC_F405_FLASH_CR_STRT;
    rc = wait_idle(f);
    if (rc == 0) {
        rc = check_sr(f);
    }
    return finish(f, rc);
}

static int op_program(void *ctx, uint32_t sector, uint32_t offset, const uint32_t *p_words,
                      uint32_t n_words)
{
    const mc_f405_flash_t *f = (const mc_f405_flash_t *)ctx;
    mc_f405_flash_regs_t *r = f->cfg.p_regs;
    uint32_t base = 0u;
    uint32_t bytes = 0u;
    int rc = 0;
    if ((mc_f405_flash_sector_geometry(sector, &base, &bytes) != 0) ||
        (((f->cfg.protect_mask >> sector) & 1u) != 0u) || ((offset & 3u) != 0u) ||
        (offset > bytes) || (n_words > (bytes - offset) / 4u)) {
        return -EINVAL;
    }
    if (unlock(f) != 0) {
        return finish(f, -EIO);
    }
    /* RM0090 3.6.4: PG with PSIZE x32, one word per write, wait BSY */
    r->CR = MC_F405_FLASH_CR_PSIZE_X32 | MC_F405_FLASH_CR_PG;
    for (uint32_t i = 0u; (i < n_words) && (rc == 0); ++i) {
        volatile uint32_t *dst =
            (volatile uint32_t *)(void *)(f->cfg.p_mem + base + offset + (size_t)4u * i);
        *dst = p_words[i];
        rc = wait_idle(f);
        if (rc == 0) {
            rc = check_sr(f);
        }
    }
    return finish(f, rc);
}

static int op_read(void *ctx, uint32_t sector, uint32_t offset, void *p_buf, uint32_t len)
{
    const mc_f405_flash_t *f = (const mc_f405_flash_t *)ctx;
    uint32_t base = 0u;
    uint32_t bytes = 0u;
    uint8_t *out = (uint8_t *)p_buf;
    if ((mc_f405_flash_sector_geometry(sector, &base, &bytes) != 0) || (offset > bytes) ||
        (len > bytes - offset)) {
        return -EINVAL;
    }
    for (uint32_t i = 0u; i < len; ++i) {
        out[i] = f->cfg.p_mem[base + offset + i];
    }
    return 0;
}

static const mc_hal_flash_ops_t f405_flash_ops = {
    .sector_size = op_sector_size,
    .erase = op_erase,
    .program = op_program,
    .read = op_read,
};

int mc_f405_flash_init(mc_f405_flash_t *f, const mc_f405_flash_config_t *cfg)
{
    if ((f == NULL) || (cfg == NULL) || (cfg->p_regs == NULL) || (cfg->p_mem == NULL) ||
        (cfg->busy_spin_max == 0u)) {
        return -EINVAL;
    }
    f->cfg = *cfg;
    f->dev.ops = &f405_flash_ops;
    f->dev.ctx = f;
    return 0;
}
