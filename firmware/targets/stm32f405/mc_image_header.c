/**
 * @file mc_image_header.c
 * @brief This application image's header: see mc_image_header.h.
 */
#include "mc_image_header.h"

#include "mc_boot_layout.h"

/* The build names the board and the version; static analysis without the
 * build's definitions sees the example board's first version. */
#ifndef MC_BOOT_BOARD_ID
#define MC_BOOT_BOARD_ID MC_BOOT_BOARD_EXAMPLE
#endif
#ifndef MC_FW_VERSION
#define MC_FW_VERSION 0x000100u
#endif

__attribute__((section(".mc_image_header"), used)) const mc_boot_image_hdr_t mc_image_header = {
    .magic = MC_BOOT_IMAGE_MAGIC,
    .hdr_version = MC_BOOT_HDR_VERSION,
    .board_id = MC_BOOT_BOARD_ID,
    .layout_id = MC_BOOT_LAYOUT_ID,
    .app_version = MC_FW_VERSION,
    .image_bytes = 0u,     /* the seal: the image's length */
    .crc32 = 0xFFFFFFFFu,  /* the seal */
    .commit = 0xFFFFFFFFu, /* the seal (committed, for an image flashed over SWD) */
};

const mc_boot_enter_cfg_t mc_image_boot_cfg = {
    .board_id = MC_BOOT_BOARD_ID,
    .layout_id = MC_BOOT_LAYOUT_ID,
    .app_version = MC_FW_VERSION,
};
