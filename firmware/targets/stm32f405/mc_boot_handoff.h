/**
 * @file mc_boot_handoff.h
 * @brief The hand-offs between the bootloader and the application on the
 *        STM32F405 (both images link this file):
 *   - the request an application leaves for the bootloader across a reset:
 *     two words at the top of SRAM (MC_BOOT_MAILBOX_ADDR, outside both
 *     images' sections, firmware/boot/mc_boot_layout.h). SRAM keeps its
 *     contents through a system reset, not through a power cut: after one
 *     the words hold whatever the SRAM powered up with, which equals the
 *     request with odds 2^-64;
 *   - the system reset (AIRCR.SYSRESETREQ);
 *   - the bootloader's jump into a checked image (VTOR, MSP, reset handler).
 */
#ifndef MC_BOOT_HANDOFF_H
#define MC_BOOT_HANDOFF_H

#include <stdbool.h>
#include <stdint.h>

/** The application: leave the request and reset the MCU; does not return.
 *  ctx unused (the signature of mc_app_cfg_t.enter_boot). */
void mc_boot_mailbox_enter(void *ctx) __attribute__((noreturn));

/** The bootloader, first thing at boot: was the request there? The mailbox
 *  is cleared either way, so the next reset starts the application again. */
bool mc_boot_mailbox_take(void);

/** Reset the MCU (AIRCR.SYSRESETREQ); does not return. */
void mc_boot_system_reset(void) __attribute__((noreturn));

/** Start the image whose vector table is at addr: VTOR, the initial stack
 *  pointer, its reset handler. Called with the core as the reset left it
 *  (no interrupt enabled, clocks untouched). Does not return. */
void mc_boot_start_image(uint32_t addr) __attribute__((noreturn));

#endif /* MC_BOOT_HANDOFF_H */
