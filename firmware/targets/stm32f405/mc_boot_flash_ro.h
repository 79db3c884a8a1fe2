/**
 * @file mc_boot_flash_ro.h
 * @brief The STM32F405's flash array as a read-only flash HAL device: the
 *        register-level driver (hal/stm32f405/mc_f405_flash.h) with every
 *        sector protected, so it only ever reads the memory-mapped array
 *        and writes no register. For images that only read the flash (the
 *        emulated bootloader before it writes, the update tests'
 *        application reading the configuration store).
 */
#ifndef MC_BOOT_FLASH_RO_H
#define MC_BOOT_FLASH_RO_H

#include "mc_f405_flash.h"

/** f reads the array at 0x08000000 (erase and program refused -EINVAL). */
void mc_boot_flash_ro_init(mc_f405_flash_t *f);

#endif /* MC_BOOT_FLASH_RO_H */
