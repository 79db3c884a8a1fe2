/**
 * @file mc_boot_start.h
 * @brief The bootloader's decision at every reset: start the application
 *        or stay for an update, and on which node id and bit rate.
 *
 * The application starts only when its image passes the whole check
 * (mc_boot_image_check) and it did not ask for the bootloader (the
 * mailbox, mc_boot_layout.h). Otherwise the bootloader stays, and says why
 * (reason: REQUESTED, or the check's failure).
 *
 * The node id and bit rate are those of the newest valid record of the
 * configuration store (ids MC_PARAM_ID_CAN_NODE_ID and
 * MC_PARAM_ID_CAN_BITRATE_BPS, mc_cfg_store_find_raw: read only, nothing
 * written), each only when in its range (node 0..62; 125k, 250k, 500k, 1M),
 * else the parameter table's default (node 1, 500 kbit/s). The application
 * takes them from the same record, so both answer on the same identifiers
 * (unless the application refuses the whole record, LAYOUT or INVALID:
 * then it runs on its defaults while the bootloader keeps the stored id;
 * firmware/boot/README.md).
 */
#ifndef MC_BOOT_START_H
#define MC_BOOT_START_H

#include <stdbool.h>
#include <stdint.h>

#include "mc_boot_image.h"
#include "mc_cfg_store.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    mc_boot_slot_t slot;
    mc_cfg_store_cfg_t store; /**< the configuration store (flash NULL: none) */
    bool requested;           /**< the application asked for the bootloader */
} mc_boot_start_cfg_t;

typedef struct {
    mc_boot_img_t image;  /**< the image check */
    mc_boot_img_t reason; /**< OK: start the application; else why not */
    uint8_t node_id;
    bool node_stored; /**< node id and bit rate from the store (else defaults) */
    uint32_t bitrate_bps;
    mc_boot_image_hdr_t hdr; /**< the image's header as read */
} mc_boot_start_t;

/** Decide (file comment). store: the store's working memory (the caller's,
 *  it is large: a whole record). */
void mc_boot_start_decide(const mc_boot_start_cfg_t *cfg, mc_cfg_store_t *store,
                          mc_boot_start_t *p_out);

#ifdef __cplusplus
}
#endif

#endif /* MC_BOOT_START_H */
