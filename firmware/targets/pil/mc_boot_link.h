/**
 * @file mc_boot_link.h
 * @brief The link between the emulated bootloader (and the update tests'
 *        applications) and the host that plays their flash and their CAN
 *        bus (tests/update/emu_node.py): frames over two host FIFOs opened
 *        through ARM semihosting.
 *
 * Why not USART1 as the drive's PIL link: QEMU's USART hands the target one
 * byte per main-loop turn, 24 kB/s with the receive interrupt (4.5 kB/s
 * polled), measured here; semihosting reads whole buffers (60 MB/s). An
 * update of 100 KiB carries 400 kB of link frames; the power-cut test runs
 * hundreds of updates.
 *
 * Frame (multi-byte values little-endian):
 *   0xB5 | type | length (2 bytes) | payload | CRC-16/CCITT-FALSE over
 *   type, length and payload (2 bytes)
 * Target -> host:
 *   HELLO    role (1 bootloader, 2 application), version, reason, node id
 *   CAN_TX   id, length | flags << 8, 8 data bytes: a frame sent on the bus
 *   ERASE    sector                       } one flash step each: the host
 *   PROGRAM  sector, offset, words...     } applies it to its file and
 *   READ     sector, offset, length       } answers (or cuts the power)
 *   RESET    the target asks to be reset: the host restarts it with the
 *            flash file as it is (a system reset in QEMU would keep the
 *            flash as QEMU loaded it: its flash is read-only to the CPU)
 * Host -> target:
 *   CAN_RX     time [us], id, length | flags << 8, 8 data bytes
 *   TICK       time [us]: the bus time now (the host's emulated clock)
 *   FLASH_DONE result (0 or a negative errno)
 *   FLASH_DATA result, then the bytes read
 */
#ifndef MC_BOOT_LINK_H
#define MC_BOOT_LINK_H

#include <stddef.h>
#include <stdint.h>

#include "hal/can.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_BOOT_LINK_SYNC        0xB5u
#define MC_BOOT_LINK_HEADER      4u
#define MC_BOOT_LINK_MAX_PAYLOAD 300u /**< a PROGRAM of 256 bytes and its fields */
#define MC_BOOT_LINK_MAX_FRAME   (MC_BOOT_LINK_HEADER + MC_BOOT_LINK_MAX_PAYLOAD + 2u)
/** Bytes one READ or PROGRAM carries at most. */
#define MC_BOOT_LINK_MAX_DATA 256u

typedef enum {
    MC_BOOT_LINK_HELLO = 1,
    MC_BOOT_LINK_CAN_TX = 2,
    MC_BOOT_LINK_ERASE = 3,
    MC_BOOT_LINK_PROGRAM = 4,
    MC_BOOT_LINK_READ = 5,
    MC_BOOT_LINK_RESET = 6,
    MC_BOOT_LINK_CAN_RX = 16,
    MC_BOOT_LINK_TICK = 17,
    MC_BOOT_LINK_FLASH_DONE = 18,
    MC_BOOT_LINK_FLASH_DATA = 19,
} mc_boot_link_type_t;

#define MC_BOOT_LINK_ROLE_BOOT 1u
#define MC_BOOT_LINK_ROLE_APP  2u

/** A frame being built or parsed. */
typedef struct {
    uint8_t type;
    uint16_t len;
    uint8_t payload[MC_BOOT_LINK_MAX_PAYLOAD];
} mc_boot_link_msg_t;

/** Append a little-endian word to m's payload (no-op when full). */
void mc_boot_link_put32(mc_boot_link_msg_t *m, uint32_t v);
/** Word i of m's payload (0 beyond its length). */
uint32_t mc_boot_link_get32(const mc_boot_link_msg_t *m, uint32_t i);

/** Encode m into buf (capacity cap); the frame's length, 0 if it does not fit. */
size_t mc_boot_link_encode(const mc_boot_link_msg_t *m, uint8_t *buf, size_t cap);

/** A CAN frame as CAN_TX (or CAN_RX with time_us) payload. */
void mc_boot_link_put_can(mc_boot_link_msg_t *m, const mc_hal_can_frame_t *f);
/** The CAN frame at word `at` of a CAN_RX/CAN_TX payload; 0 or -1 (length
 *  word out of range). */
int mc_boot_link_get_can(const mc_boot_link_msg_t *m, uint32_t at, mc_hal_can_frame_t *f);

/** Incremental decoder: feed bytes; skips to the next sync byte after
 *  garbage or a CRC error (the link survives a target reset mid-frame). */
typedef struct {
    uint8_t buf[MC_BOOT_LINK_MAX_FRAME];
    size_t n;
    uint32_t dropped; /**< bytes skipped resynchronising */
} mc_boot_link_rx_t;

/** Feed one byte; returns 1 with *m filled when a whole valid frame ended. */
int mc_boot_link_feed(mc_boot_link_rx_t *rx, uint8_t b, mc_boot_link_msg_t *m);

#ifdef __cplusplus
}
#endif

#endif /* MC_BOOT_LINK_H */
