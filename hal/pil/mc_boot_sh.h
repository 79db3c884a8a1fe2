/**
 * @file mc_boot_sh.h
 * @brief The transport of the emulated bootloader's link
 *        (firmware/targets/pil/mc_boot_link.h): ARM semihosting file calls
 *        on two FIFOs the host creates in QEMU's working directory,
 *        mc_boot_h2t (host to target) and mc_boot_t2h (target to host).
 *        Emulation only (QEMU netduinoplus2 with semihosting enabled).
 *
 * Reads block the emulated core until the host writes: the target's time
 * is the host's (CAN_RX and TICK frames carry it), so a run is lock-step
 * and its result does not depend on how fast the host is.
 */
#ifndef MC_BOOT_SH_H
#define MC_BOOT_SH_H

#include <stdint.h>

#include "mc_boot_link.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Semihosting exit codes of the emulated images (the host reads them). */
#define MC_BOOT_SH_EXIT_RESET      0  /**< asked for a reset (RESET sent) */
#define MC_BOOT_SH_EXIT_NO_LINK    4  /**< the FIFOs could not be opened */
#define MC_BOOT_SH_EXIT_LINK_EOF   5  /**< the host closed the link */
#define MC_BOOT_SH_EXIT_HARD_FAULT 99 /**< a hard fault */

/** Open the two FIFOs; 0, or -1 (no host: nothing else works). */
int mc_boot_sh_open(void);

/** Send one frame (blocks until written). */
void mc_boot_sh_send(const mc_boot_link_msg_t *m);

/** Receive the next whole frame (blocks). Exits with
 *  MC_BOOT_SH_EXIT_LINK_EOF when the host has gone. */
void mc_boot_sh_recv(mc_boot_link_msg_t *m);

/** Leave QEMU with an exit code (SYS_EXIT_EXTENDED); does not return. */
void mc_boot_sh_exit(int code) __attribute__((noreturn));

#ifdef __cplusplus
}
#endif

#endif /* MC_BOOT_SH_H */
