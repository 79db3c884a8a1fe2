/**
 * @file mc_boot_pil.c
 * @brief The bootloader of the emulated STM32F405 (QEMU netduinoplus2): the
 *        same decision and update code as the board's bootloader
 *        (firmware/boot, boot_f405.c), with the flash and the CAN bus
 *        played by the host over the boot link (mc_boot_sh.h,
 *        firmware/targets/pil/mc_boot_link.h; tests/update/emu_node.py).
 *
 * Flash: QEMU loads the host's flash file at 0x08000000 when it starts, but
 * the emulated flash is read-only to the CPU and there is no flash
 * controller. Reads come from the memory-mapped array until this boot has
 * erased or programmed anything; from then on the host answers them from
 * its file, which holds every erase and program (one link request each:
 * the host may cut the power there). The sector map is the STM32F405's;
 * only the application slot may be erased or programmed (as the board's
 * MC_BOOT_PROTECT_MASK).
 * CAN: the host's CAN_RX frames (with the bus time) queue here; replies go
 * out as CAN_TX. Time: the host's, carried by CAN_RX and TICK.
 * Reset (after COMMIT or RUN): RESET to the host, which restarts QEMU with
 * its file; the application's request arrives as on the board, through the
 * mailbox kept by QEMU's system reset.
 *
 * A valid image without a request starts at once, without any link traffic:
 * the drive's PIL tests boot their image through this bootloader.
 */
#include <errno.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "hal/flash.h"
#include "mc_boot_flash_ro.h"
#include "mc_boot_handoff.h"
#include "mc_boot_layout.h"
#include "mc_boot_run.h"
#include "mc_boot_sh.h"
#include "mc_boot_start.h"
#include "mc_cortexm.h"
#include "mc_f405_flash.h"

#ifndef MC_BOOT_BOARD_ID
#define MC_BOOT_BOARD_ID MC_BOOT_BOARD_PIL
#endif
#define CAN_RX_LEN   64u /* a power of two */
#define BOOT_VERSION 0x000100u

void HardFault_Handler(void);

typedef struct {
    mc_hal_flash_t flash;
    mc_f405_flash_t mem; /* the memory-mapped array as QEMU loaded it: reads only */
    mc_hal_can_t can;
    bool dirty;  /* this boot erased or programmed: reads from the host */
    bool linked; /* the link is open */
    uint32_t time_us;
    mc_hal_can_frame_t rx[CAN_RX_LEN];
    uint32_t rx_head, rx_tail, rx_lost;
    mc_boot_crc_table_t crc;
    mc_cfg_store_t store;
    mc_boot_start_t start;
    mc_boot_update_t upd;
    mc_boot_link_msg_t msg;
} pil_boot_t;

static pil_boot_t g_pb;

void HardFault_Handler(void)
{
    mc_boot_sh_exit(MC_BOOT_SH_EXIT_HARD_FAULT);
}

/* ---------------------------------------------------------------- link */

/* A frame from the host that is not a flash answer: CAN_RX or TICK. */
static void host_frame(const mc_boot_link_msg_t *m)
{
    if ((m->type == (uint8_t)MC_BOOT_LINK_CAN_RX) || (m->type == (uint8_t)MC_BOOT_LINK_TICK)) {
        g_pb.time_us = mc_boot_link_get32(m, 0u);
    }
    if (m->type == (uint8_t)MC_BOOT_LINK_CAN_RX) {
        mc_hal_can_frame_t f;
        if ((g_pb.rx_tail - g_pb.rx_head >= CAN_RX_LEN) || (mc_boot_link_get_can(m, 1u, &f) != 0)) {
            g_pb.rx_lost++; /* as a full hardware FIFO */
            return;
        }
        f.timestamp_ticks = g_pb.time_us;
        g_pb.rx[g_pb.rx_tail % CAN_RX_LEN] = f;
        g_pb.rx_tail++;
    }
}

/* Send a flash request and wait for its answer (CAN frames queue meanwhile). */
static const mc_boot_link_msg_t *flash_call(const mc_boot_link_msg_t *req, uint8_t answer)
{
    mc_boot_sh_send(req);
    for (;;) {
        mc_boot_sh_recv(&g_pb.msg);
        if (g_pb.msg.type == answer) {
            return &g_pb.msg;
        }
        host_frame(&g_pb.msg);
    }
}

/* --------------------------------------------------------------- flash */

static bool in_slot(uint32_t sector)
{
    return (sector >= MC_BOOT_APP_FIRST_SECTOR) &&
           (sector < MC_BOOT_APP_FIRST_SECTOR + MC_BOOT_APP_SECTORS);
}

static int op_sector_size(void *ctx, uint32_t sector, uint32_t *p_bytes)
{
    (void)ctx;
    return mc_hal_flash_sector_size(&g_pb.mem.dev, sector, p_bytes);
}

static int op_erase(void *ctx, uint32_t sector)
{
    mc_boot_link_msg_t m = {.type = (uint8_t)MC_BOOT_LINK_ERASE, .len = 0u};
    (void)ctx;
    if (!in_slot(sector) || !g_pb.linked) {
        return -EINVAL;
    }
    g_pb.dirty = true;
    mc_boot_link_put32(&m, sector);
    return (int)mc_boot_link_get32(flash_call(&m, (uint8_t)MC_BOOT_LINK_FLASH_DONE), 0u);
}

static int op_program(void *ctx, uint32_t sector, uint32_t offset, const uint32_t *p_words,
                      uint32_t n_words)
{
    uint32_t base = 0u;
    uint32_t bytes = 0u;
    (void)ctx;
    if (!in_slot(sector) || !g_pb.linked ||
        (mc_f405_flash_sector_geometry(sector, &base, &bytes) != 0) || ((offset & 3u) != 0u) ||
        (offset > bytes) || (n_words > (bytes - offset) / 4u)) {
        return -EINVAL;
    }
    g_pb.dirty = true;
    for (uint32_t done = 0u; done < n_words;) {
        const uint32_t n = ((n_words - done) < MC_BOOT_LINK_MAX_DATA / 4u)
                               ? (n_words - done)
                               : MC_BOOT_LINK_MAX_DATA / 4u;
        mc_boot_link_msg_t m = {.type = (uint8_t)MC_BOOT_LINK_PROGRAM, .len = 0u};
        mc_boot_link_put32(&m, sector);
        mc_boot_link_put32(&m, offset + 4u * done);
        for (uint32_t i = 0u; i < n; ++i) {
            mc_boot_link_put32(&m, p_words[done + i]);
        }
        const int rc =
            (int)mc_boot_link_get32(flash_call(&m, (uint8_t)MC_BOOT_LINK_FLASH_DONE), 0u);
        if (rc != 0) {
            return rc;
        }
        done += n;
    }
    return 0;
}

static int op_read(void *ctx, uint32_t sector, uint32_t offset, void *p_buf, uint32_t len)
{
    uint32_t base = 0u;
    uint32_t bytes = 0u;
    uint8_t *out = (uint8_t *)p_buf;
    (void)ctx;
    if (!g_pb.dirty) {
        return mc_hal_flash_read(&g_pb.mem.dev, sector, offset, p_buf, len);
    }
    if ((mc_f405_flash_sector_geometry(sector, &base, &bytes) != 0) || (offset > bytes) ||
        (len > bytes - offset)) {
        return -EINVAL;
    }
    for (uint32_t done = 0u; done < len;) {
        const uint32_t n =
            ((len - done) < MC_BOOT_LINK_MAX_DATA) ? (len - done) : MC_BOOT_LINK_MAX_DATA;
        mc_boot_link_msg_t m = {.type = (uint8_t)MC_BOOT_LINK_READ, .len = 0u};
        mc_boot_link_put32(&m, sector);
        mc_boot_link_put32(&m, offset + done);
        mc_boot_link_put32(&m, n);
        const mc_boot_link_msg_t *a = flash_call(&m, (uint8_t)MC_BOOT_LINK_FLASH_DATA);
        const int rc = (int)mc_boot_link_get32(a, 0u);
        if (rc != 0) {
            return rc;
        }
        if (a->len != 4u + n) {
            return -EIO;
        }
        (void)memcpy(&out[done], &a->payload[4], n);
        done += n;
    }
    return 0;
}

static const mc_hal_flash_ops_t k_flash_ops = {op_sector_size, op_erase, op_program, op_read};

/* ----------------------------------------------------------------- CAN */

static int can_send(void *ctx, const mc_hal_can_frame_t *p_frame)
{
    mc_boot_link_msg_t m = {.type = (uint8_t)MC_BOOT_LINK_CAN_TX, .len = 0u};
    (void)ctx;
    if (mc_hal_can_frame_check(p_frame, false) != 0) {
        return -EINVAL;
    }
    mc_boot_link_put_can(&m, p_frame);
    mc_boot_sh_send(&m);
    return 0;
}

static int can_receive(void *ctx, mc_hal_can_frame_t *p_frame)
{
    (void)ctx;
    if (g_pb.rx_head == g_pb.rx_tail) {
        return -EAGAIN;
    }
    *p_frame = g_pb.rx[g_pb.rx_head % CAN_RX_LEN];
    g_pb.rx_head++;
    return 0;
}

static int can_get_status(void *ctx, mc_hal_can_status_t *p_status)
{
    (void)ctx;
    (void)memset(p_status, 0, sizeof *p_status);
    p_status->state = MC_HAL_CAN_STATE_ERROR_ACTIVE;
    p_status->rx_overrun_count = g_pb.rx_lost;
    return 0;
}

static const mc_hal_can_ops_t k_can_ops = {can_send, can_receive, can_get_status};

/* --------------------------------------------------------------- board */

static uint32_t board_now_ms(void *ctx)
{
    (void)ctx;
    return g_pb.time_us / 1000u;
}

/* Nothing queued: wait for the host's next frame. */
static void board_idle(void *ctx)
{
    (void)ctx;
    mc_boot_sh_recv(&g_pb.msg);
    host_frame(&g_pb.msg);
}

static void board_reset(void *ctx)
{
    const mc_boot_link_msg_t m = {.type = (uint8_t)MC_BOOT_LINK_RESET, .len = 0u};
    (void)ctx;
    mc_boot_sh_send(&m);
    mc_boot_sh_exit(MC_BOOT_SH_EXIT_RESET);
}

static mc_boot_slot_t slot(void)
{
    return mc_boot_slot_layout1(&g_pb.flash, MC_BOOT_BOARD_ID, &g_pb.crc);
}

int main(void)
{
    mc_boot_start_cfg_t sc;
    mc_boot_update_cfg_t uc;
    mc_boot_board_t b;
    mc_boot_link_msg_t hello = {.type = (uint8_t)MC_BOOT_LINK_HELLO, .len = 0u};
    mc_boot_flash_ro_init(&g_pb.mem);
    g_pb.flash.ops = &k_flash_ops;
    g_pb.flash.ctx = &g_pb;
    g_pb.can.ops = &k_can_ops;
    g_pb.can.ctx = &g_pb;
    mc_boot_crc_table_init(&g_pb.crc);
    sc.slot = slot();
    sc.store.flash = &g_pb.flash;
    sc.store.sector[0] = MC_BOOT_CFG_SECTOR_A;
    sc.store.sector[1] = MC_BOOT_CFG_SECTOR_B;
    sc.store.axis = 0u; /* the node id and bit rate it listens with: axis 0's */
    sc.requested = mc_boot_mailbox_take();
    mc_boot_start_decide(&sc, &g_pb.store, &g_pb.start);
    if (g_pb.start.reason == MC_BOOT_IMG_OK) {
        mc_boot_start_image(MC_BOOT_APP_ADDR);
    }
    if (mc_boot_sh_open() != 0) {
        mc_boot_sh_exit(MC_BOOT_SH_EXIT_NO_LINK);
    }
    g_pb.linked = true;
    mc_boot_link_put32(&hello, MC_BOOT_LINK_ROLE_BOOT);
    mc_boot_link_put32(&hello, BOOT_VERSION);
    mc_boot_link_put32(&hello, (uint32_t)g_pb.start.reason);
    mc_boot_link_put32(&hello, g_pb.start.node_id);
    mc_boot_sh_send(&hello);
    uc.slot = slot();
    uc.node_id = g_pb.start.node_id;
    uc.reason = (uint8_t)g_pb.start.reason;
    b.can = &g_pb.can;
    b.now_ms = board_now_ms;
    b.idle = board_idle;
    b.feed = NULL;
    b.tx_idle = NULL; /* CAN_TX is written at once */
    b.reset = board_reset;
    b.ctx = &g_pb;
    (void)mc_boot_run(&g_pb.upd, &uc, &b);
    board_reset(&g_pb);
    return 0;
}
