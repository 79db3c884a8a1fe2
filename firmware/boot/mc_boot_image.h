/**
 * @file mc_boot_image.h
 * @brief The application image the bootloader starts: its header, the slot
 *        it lives in, and the check the bootloader makes at every boot.
 *
 * An image is the application's flash contents from the start of the
 * application slot: its vector table (VTOR = the slot's address), then at
 * MC_BOOT_HDR_OFFSET the header below (section .mc_image_header, placed by
 * the linker script right after the vectors), then code and constants.
 * The build fills the header after the link (tools/boot/mc_image.py seal:
 * image_bytes, crc32, commit).
 *
 * CRC-32 (IEEE, as mc_crc32.h) over every byte of [0, image_bytes) except
 * the header's crc32 and commit words (the last two words of the header):
 * the bootloader writes commit itself, after it has verified the image.
 *
 * The check (mc_boot_image_check), in this order, each failure named:
 *   FLASH        the header or the image could not be read;
 *   EMPTY        the header's magic word reads erased (0xFFFFFFFF);
 *   MAGIC        any other magic;
 *   HDR_VERSION  a header format this bootloader does not know;
 *   BOARD        an image for another board (board_id);
 *   LAYOUT       an image linked for another memory map (layout_id);
 *   SIZE         image_bytes not a multiple of 4, smaller than the vectors
 *                and header, or larger than the slot;
 *   CRC          the CRC-32 over the slot differs from the header's;
 *   UNCOMMITTED  the commit word is not MC_BOOT_COMMIT_MAGIC (the update
 *                that wrote it did not finish);
 *   VECTORS      the initial stack pointer is not in RAM or the reset
 *                handler is not a Thumb address inside the image.
 * The values are those of BOOT_REPLY.boot_reason (tools/can/motordrive.dbc).
 *
 * The slot is read only through the flash HAL (hal/flash.h): the same code
 * runs on the MCU, on the emulated MCU and on a fake flash in the tests.
 */
#ifndef MC_BOOT_IMAGE_H
#define MC_BOOT_IMAGE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/flash.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_BOOT_IMAGE_MAGIC  0x474D494Du /**< "MIMG" in memory order */
#define MC_BOOT_COMMIT_MAGIC 0x54494D43u /**< "CMIT": written by the bootloader */
#define MC_BOOT_HDR_VERSION  1u
/** Offset of the header in the image: right after the STM32F405's vector
 *  table (16 + 82 entries of 4 bytes); the linker script asserts it. */
#define MC_BOOT_HDR_OFFSET 0x188u
#define MC_BOOT_HDR_WORDS  8u
#define MC_BOOT_HDR_BYTES  (4u * MC_BOOT_HDR_WORDS)
/** Offsets in the image of the two words the CRC leaves out. */
#define MC_BOOT_CRC_WORD_OFFSET    (MC_BOOT_HDR_OFFSET + 24u)
#define MC_BOOT_COMMIT_WORD_OFFSET (MC_BOOT_HDR_OFFSET + 28u)
/** The smallest image: the vectors and the header. */
#define MC_BOOT_IMAGE_MIN_BYTES (MC_BOOT_HDR_OFFSET + MC_BOOT_HDR_BYTES)

/** The header (32-bit little-endian words, in this order). */
typedef struct mc_boot_image_hdr {
    uint32_t magic;       /**< MC_BOOT_IMAGE_MAGIC */
    uint32_t hdr_version; /**< MC_BOOT_HDR_VERSION */
    uint32_t board_id;    /**< MC_BOOT_BOARD_* (mc_boot_layout.h) */
    uint32_t layout_id;   /**< MC_BOOT_LAYOUT_ID of the linker script */
    uint32_t app_version; /**< major << 16 | minor << 8 | patch */
    uint32_t image_bytes; /**< from the slot's start, a multiple of 4 */
    uint32_t crc32;       /**< see the file comment */
    uint32_t commit;      /**< MC_BOOT_COMMIT_MAGIC once committed */
} mc_boot_image_hdr_t;

/** Result of the check: BOOT_REPLY.boot_reason values (REQUESTED is the
 *  bootloader's, not the check's). */
typedef enum mc_boot_img {
    MC_BOOT_IMG_OK = 0,
    MC_BOOT_IMG_REQUESTED = 1,
    MC_BOOT_IMG_EMPTY = 2,
    MC_BOOT_IMG_MAGIC = 3,
    MC_BOOT_IMG_HDR_VERSION = 4,
    MC_BOOT_IMG_BOARD = 5,
    MC_BOOT_IMG_LAYOUT = 6,
    MC_BOOT_IMG_SIZE = 7,
    MC_BOOT_IMG_CRC = 8,
    MC_BOOT_IMG_UNCOMMITTED = 9,
    MC_BOOT_IMG_VECTORS = 10,
    MC_BOOT_IMG_FLASH = 11,
} mc_boot_img_t;

/** Sectors the slot spans, at most. */
#define MC_BOOT_SLOT_SECTORS_MAX 12u

/** CRC-32 (mc_crc32.h) by a 256-entry table: about six times faster than
 *  the bitwise mc_crc32_update, which matters for the boot check of a whole
 *  image. The table is the caller's (1 KiB of RAM, no table in flash),
 *  filled from mc_crc32_update itself by mc_boot_crc_table_init. */
typedef struct mc_boot_crc_table {
    uint32_t t[256];
} mc_boot_crc_table_t;

void mc_boot_crc_table_init(mc_boot_crc_table_t *tab);

/** Continue a CRC-32 as mc_crc32_update does (same state and result). */
uint32_t mc_boot_crc32_update(const mc_boot_crc_table_t *tab, uint32_t state, const void *data,
                              size_t len);

/** The application slot: consecutive sectors of one flash device. */
typedef struct mc_boot_slot {
    const mc_hal_flash_t *flash;
    uint32_t first_sector; /**< the slot starts at this sector's offset 0 */
    uint32_t n_sectors;    /**< 1 .. MC_BOOT_SLOT_SECTORS_MAX */
    uint32_t addr;         /**< the slot's address on the MCU (vector table) */
    uint32_t ram_start;    /**< the range an initial stack pointer may take */
    uint32_t ram_end;      /**< (inclusive end: the top of RAM) */
    uint32_t board_id;     /**< this board's MC_BOOT_BOARD_* */
    uint32_t layout_id;    /**< this memory map's MC_BOOT_LAYOUT_ID */
    /** A filled CRC table, or NULL (the bitwise mc_crc32_update). */
    const mc_boot_crc_table_t *crc_table;
} mc_boot_slot_t;

/** The STM32F405's application slot of layout 1 (mc_boot_layout.h: sectors
 *  1..9 at 0x08004000, SRAM for the stack) on flash, for board_id, with the
 *  CRC table crc (or NULL). */
mc_boot_slot_t mc_boot_slot_layout1(const mc_hal_flash_t *flash, uint32_t board_id,
                                    const mc_boot_crc_table_t *crc);

/** The slot's size [bytes] (sum of its sectors), 0 when a sector is unknown
 *  or the description is incomplete. */
uint32_t mc_boot_slot_bytes(const mc_boot_slot_t *s);

/** Map an offset in the slot to its sector and the offset in it; false
 *  outside the slot. *p_room: bytes from there to the sector's end. */
bool mc_boot_slot_locate(const mc_boot_slot_t *s, uint32_t off, uint32_t *p_sector,
                         uint32_t *p_sector_off, uint32_t *p_room);

/** Read len bytes of the slot at off (across sectors). 0 or a HAL error. */
int mc_boot_slot_read(const mc_boot_slot_t *s, uint32_t off, void *p_buf, uint32_t len);

/**
 * The image CRC of the slot's first image_bytes bytes (the crc32 and commit
 * words left out). 0 and *p_crc, or a HAL error (-EINVAL beyond the slot).
 */
int mc_boot_slot_crc(const mc_boot_slot_t *s, uint32_t image_bytes, uint32_t *p_crc);

/** The header fields a BEGIN or a header itself must agree with this slot
 *  on: magic, version, board, layout, size. MC_BOOT_IMG_OK or the first
 *  failing check of the list above (without CRC, commit and vectors). */
mc_boot_img_t mc_boot_image_check_hdr(const mc_boot_slot_t *s, const mc_boot_image_hdr_t *h);

/**
 * The whole check of the image in the slot (file comment). *p_hdr (may be
 * NULL) receives the header as read (zeroed when it could not be read).
 */
mc_boot_img_t mc_boot_image_check(const mc_boot_slot_t *s, mc_boot_image_hdr_t *p_hdr);

#ifdef __cplusplus
}
#endif

#endif /* MC_BOOT_IMAGE_H */
