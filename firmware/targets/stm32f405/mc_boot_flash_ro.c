/**
 * @file mc_boot_flash_ro.c
 * @brief The flash array, read only: see mc_boot_flash_ro.h.
 */
#include "mc_boot_flash_ro.h"

#include <stddef.h>

static void *at(uintptr_t a)
{
    return (void *)a; /* NOLINT(performance-no-int-to-ptr): the flash interface and array */
}

void mc_boot_flash_ro_init(mc_f405_flash_t *f)
{
    const mc_f405_flash_config_t c = {
        .p_regs = at(MC_F405_FLASH_R_BASE), /* never touched: reads only */
        .p_mem = at(MC_F405_FLASH_MEM_BASE),
        .protect_mask = (1u << MC_F405_FLASH_SECTORS) - 1u,
        .busy_spin_max = 1u,
        .hw_poll = NULL,
        .hw_ctx = NULL,
    };
    (void)mc_f405_flash_init(f, &c);
}
