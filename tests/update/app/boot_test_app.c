/**
 * @file boot_test_app.c
 * @brief The application images of the update tests on the emulated
 *        STM32F405 (tests/update/emu_node.py): linked for the application
 *        slot like the drive (firmware/targets/stm32f405/stm32f405.ld, its
 *        start-up and image header, sealed by tools/boot/mc_image.py), two
 *        versions (MC_FW_VERSION) whose padding (pad.c, generated) differs
 *        in every byte, so a mixture of the two can never pass for either.
 *
 * At start: HELLO (role application, its version, its node id) on the boot
 * link, then the application's side of the update as the drive runs it
 * (firmware/app/can/mc_boot_enter.c): INFO, VERSION, the confirmed ENTER,
 * after which it resets into the bootloader through the mailbox
 * (mc_boot_handoff.c), as the drive's board binding does. The node id is
 * the configuration store's (mc_cfg_store_find_raw), default 1.
 */
#include <stddef.h>
#include <stdint.h>

#include "mc_boot_enter.h"
#include "mc_boot_flash_ro.h"
#include "mc_boot_handoff.h"
#include "mc_boot_layout.h"
#include "mc_boot_sh.h"
#include "mc_can_proto.h"
#include "mc_cfg_store.h"
#include "mc_image_header.h"
#include "mc_params_gen.h"

/* The padding (pad.c): its checksum goes into HELLO, so it is linked. */
extern const uint8_t mc_test_pad[];
extern const uint32_t mc_test_pad_bytes;

void HardFault_Handler(void);

static mc_boot_enter_t g_enter;
static mc_boot_link_msg_t g_msg;
static mc_cfg_store_t g_store;

void HardFault_Handler(void)
{
    mc_boot_sh_exit(MC_BOOT_SH_EXIT_HARD_FAULT);
}

static uint8_t node_id(void)
{
    static mc_f405_flash_t flash;
    mc_boot_flash_ro_init(&flash);
    const mc_cfg_store_cfg_t c = {&flash.dev, {MC_BOOT_CFG_SECTOR_A, MC_BOOT_CFG_SECTOR_B}, 0u};
    uint32_t raw = 1u;
    if ((mc_cfg_store_init(&g_store, &c) != 0) ||
        (mc_cfg_store_find_raw(&g_store, MC_PARAM_ID_CAN_NODE_ID, &raw) != 0) || (raw > 62u)) {
        raw = 1u;
    }
    return (uint8_t)raw;
}

static uint32_t pad_sum(void)
{
    uint32_t s = 0u;
    for (uint32_t i = 0u; i < mc_test_pad_bytes; ++i) {
        s = (s << 1 | s >> 31) ^ mc_test_pad[i];
    }
    return s;
}

static void reply(const mc_hal_can_frame_t *r)
{
    mc_boot_link_msg_t m = {.type = (uint8_t)MC_BOOT_LINK_CAN_TX, .len = 0u};
    mc_boot_link_put_can(&m, r);
    mc_boot_sh_send(&m);
}

int main(void)
{
    mc_boot_link_msg_t hello = {.type = (uint8_t)MC_BOOT_LINK_HELLO, .len = 0u};
    uint32_t last_ms = 0u;
    const uint8_t node = node_id();
    if (mc_boot_sh_open() != 0) {
        mc_boot_sh_exit(MC_BOOT_SH_EXIT_NO_LINK);
    }
    mc_boot_enter_init(&g_enter, &mc_image_boot_cfg, node, 1000u, pad_sum());
    mc_boot_link_put32(&hello, MC_BOOT_LINK_ROLE_APP);
    mc_boot_link_put32(&hello, mc_image_header.app_version);
    mc_boot_link_put32(&hello, pad_sum());
    mc_boot_link_put32(&hello, node);
    mc_boot_sh_send(&hello);
    for (;;) {
        mc_boot_sh_recv(&g_msg);
        if ((g_msg.type == (uint8_t)MC_BOOT_LINK_CAN_RX) ||
            (g_msg.type == (uint8_t)MC_BOOT_LINK_TICK)) {
            /* the slow loop's millisecond steps up to the host's time */
            const uint32_t now_ms = mc_boot_link_get32(&g_msg, 0u) / 1000u;
            for (uint32_t n = 0u; (now_ms - last_ms) > 0u && n < 10000u; ++n) {
                if (mc_boot_enter_due(&g_enter)) {
                    mc_boot_mailbox_enter(NULL); /* the OK has been written */
                }
                mc_boot_enter_step(&g_enter);
                last_ms++;
            }
        }
        mc_hal_can_frame_t f;
        mc_hal_can_frame_t r;
        if ((g_msg.type == (uint8_t)MC_BOOT_LINK_CAN_RX) &&
            (mc_boot_link_get_can(&g_msg, 1u, &f) == 0) &&
            mc_boot_frame_is(&f, node, MC_CAN_CMD_BOOT_REQ) &&
            (mc_boot_enter_handle(&g_enter, &f, false, &r) == 1u)) {
            reply(&r);
        }
    }
}
