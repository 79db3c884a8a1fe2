/**
 * @file mc_image_header.h
 * @brief This application image's header (firmware/boot/mc_boot_image.h),
 *        in section .mc_image_header right after the vector table; the build
 *        seals it after the link (tools/boot/mc_image.py: image_bytes,
 *        crc32, commit). Its board id is the build's MC_BOOT_BOARD_ID, its
 *        version MC_FW_VERSION (major << 16 | minor << 8 | patch).
 */
#ifndef MC_IMAGE_HEADER_H
#define MC_IMAGE_HEADER_H

#include "mc_boot_enter.h"
#include "mc_boot_image.h"

extern const mc_boot_image_hdr_t mc_image_header;

/** What BOOT_REQ INFO and VERSION answer for this image. */
extern const mc_boot_enter_cfg_t mc_image_boot_cfg;

#endif /* MC_IMAGE_HEADER_H */
