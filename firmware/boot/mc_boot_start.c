/**
 * @file mc_boot_start.c
 * @brief The bootloader's decision at reset: see mc_boot_start.h.
 */
#include "mc_boot_start.h"

#include <stddef.h>

#include "mc_can_proto.h"
#include "mc_params.h"

static bool bitrate_ok(uint32_t bps)
{
    return (bps == 125000u) || (bps == 250000u) || (bps == 500000u) || (bps == 1000000u);
}

/* Node id and bit rate from the store, each where it is valid. */
static void from_store(const mc_boot_start_cfg_t *cfg, mc_cfg_store_t *store, mc_boot_start_t *o)
{
    uint32_t node = 0u;
    uint32_t bps = 0u;
    if ((cfg->store.flash == NULL) || (mc_cfg_store_init(store, &cfg->store) != 0)) {
        return;
    }
    if ((mc_cfg_store_find_raw(store, MC_PARAM_ID_CAN_NODE_ID, &node) == 0) &&
        (node <= MC_CAN_NODE_ID_MAX)) {
        o->node_id = (uint8_t)node;
        o->node_stored = true;
    }
    if ((mc_cfg_store_find_raw(store, MC_PARAM_ID_CAN_BITRATE_BPS, &bps) == 0) && bitrate_ok(bps)) {
        o->bitrate_bps = bps;
    }
}

void mc_boot_start_decide(const mc_boot_start_cfg_t *cfg, mc_cfg_store_t *store,
                          mc_boot_start_t *p_out)
{
    mc_boot_start_t o;
    o.node_id = (uint8_t)mc_params_default.can_node_id;
    o.node_stored = false;
    o.bitrate_bps = mc_params_default.can_bitrate_bps;
    o.image = mc_boot_image_check(&cfg->slot, &o.hdr);
    if ((o.image == MC_BOOT_IMG_OK) && cfg->requested) {
        o.reason = MC_BOOT_IMG_REQUESTED;
    } else {
        o.reason = o.image;
    }
    if (store != NULL) {
        from_store(cfg, store, &o);
    }
    *p_out = o;
}
