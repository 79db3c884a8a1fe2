/**
 * @file mc_boot_layout.h
 * @brief The STM32F405 flash map with the bootloader (layout 1), the board
 *        identifiers and the mailbox the application uses to ask for the
 *        bootloader. The linker scripts (firmware/targets/stm32f405/
 *        stm32f405.ld, stm32f405_boot.ld) state the same addresses; the
 *        cross build checks them against this file (mc_image.py seal).
 *
 *   sector  address      size     what
 *   0       0x08000000   16 KiB   the bootloader (reset vector); never
 *                                 written by itself or the application
 *   1..9    0x08004000   752 KiB  the application slot: one image,
 *                                 vectors at its start (VTOR), header at
 *                                 MC_BOOT_HDR_OFFSET (mc_boot_image.h);
 *                                 an update erases the sectors it needs
 *   10, 11  0x080C0000   2x128 KiB the configuration store (A/B records,
 *                                 firmware/app/config/mc_cfg_store.h):
 *                                 written by the application only; the
 *                                 bootloader only reads the node id and
 *                                 the bit rate there
 *
 * RAM: the top MC_BOOT_MAILBOX_BYTES of SRAM (0x2001FFE0) belong to
 * neither image's sections: the application writes the request there
 * before it resets, the bootloader reads and clears it at boot.
 */
#ifndef MC_BOOT_LAYOUT_H
#define MC_BOOT_LAYOUT_H

#include <stdint.h>

#define MC_BOOT_LAYOUT_ID 1u

#define MC_BOOT_FLASH_BASE       0x08000000u
#define MC_BOOT_SECTOR           0u /**< the bootloader's own sector */
#define MC_BOOT_APP_FIRST_SECTOR 1u
#define MC_BOOT_APP_SECTORS      9u /**< sectors 1..9 */
#define MC_BOOT_APP_ADDR         0x08004000u
#define MC_BOOT_APP_MAX_BYTES    (752u * 1024u)
#define MC_BOOT_CFG_SECTOR_A     10u
#define MC_BOOT_CFG_SECTOR_B     11u
/** Flash driver protection of the bootloader: every sector but the slot's. */
#define MC_BOOT_PROTECT_MASK 0xC01u /* sectors 0, 10, 11 */

#define MC_BOOT_RAM_START     0x20000000u
#define MC_BOOT_RAM_END       0x20020000u /**< top of SRAM (an initial SP may equal it) */
#define MC_BOOT_MAILBOX_ADDR  0x2001FFE0u
#define MC_BOOT_MAILBOX_BYTES 32u
/** Mailbox words 0 and 1 hold these when the application asks for the
 *  bootloader (two words: a power-up pattern matches with odds 2^-64). */
#define MC_BOOT_REQ_MAGIC0 0x544F4F42u /* "BOOT" */
#define MC_BOOT_REQ_MAGIC1 0xABB0B00Bu

/** Board identifiers of the image header (BOOT_REPLY INFO: board_id). */
#define MC_BOOT_BOARD_EXAMPLE      1u
#define MC_BOOT_BOARD_ODRIVE36     2u
#define MC_BOOT_BOARD_VESC6        3u
#define MC_BOOT_BOARD_ODRIVE36_24V 4u
#define MC_BOOT_BOARD_PIL          100u /**< the emulated STM32F405 (QEMU) */

/** The update protocol's version (BOOT_REPLY INFO, ANNOUNCE). */
#define MC_BOOT_PROTO_VERSION 1u

#endif /* MC_BOOT_LAYOUT_H */
