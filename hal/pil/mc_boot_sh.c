/**
 * @file mc_boot_sh.c
 * @brief The emulated bootloader's link over semihosting: see mc_boot_sh.h.
 */
#include "mc_boot_sh.h"

#include <stddef.h>

#include "mc_cortexm.h"

/* Semihosting operations (ARM's semihosting specification 2.0). */
#define SH_OPEN             0x01u
#define SH_WRITE            0x05u
#define SH_READ             0x06u
#define SH_EXIT             0x20u
#define SH_MODE_RB          1u /* "rb" */
#define SH_MODE_WB          5u /* "wb" */
#define SH_EXIT_APPLICATION 0x20026u

static struct {
    uint32_t fd_in;
    uint32_t fd_out;
    uint8_t in[256];
    uint32_t in_n;
    uint32_t in_at;
    mc_boot_link_rx_t rx;
    uint8_t out[MC_BOOT_LINK_MAX_FRAME];
} g_sh;

#if defined(__arm__)
static uint32_t sh_call(uint32_t op, const void *arg)
{
    register uint32_t r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}
#else
static uint32_t sh_call(uint32_t op, const void *arg)
{
    (void)op;
    (void)arg;
    return 0xFFFFFFFFu;
}
#endif

static uint32_t sh_open(const char *name, uint32_t len, uint32_t mode)
{
    const uint32_t a[3] = {(uint32_t)(uintptr_t)name, mode, len};
    return sh_call(SH_OPEN, a);
}

void mc_boot_sh_exit(int code)
{
    static uint32_t block[2];
    block[0] = SH_EXIT_APPLICATION;
    block[1] = (uint32_t)code;
    (void)sh_call(SH_EXIT, block);
    for (;;) {
        mc_wfi();
    }
}

int mc_boot_sh_open(void)
{
    static const char h2t[] = "mc_boot_h2t";
    static const char t2h[] = "mc_boot_t2h";
    g_sh.fd_in = sh_open(h2t, sizeof h2t - 1u, SH_MODE_RB);
    g_sh.fd_out = sh_open(t2h, sizeof t2h - 1u, SH_MODE_WB);
    g_sh.in_n = 0u;
    g_sh.in_at = 0u;
    g_sh.rx.n = 0u;
    return ((g_sh.fd_in == 0xFFFFFFFFu) || (g_sh.fd_out == 0xFFFFFFFFu)) ? -1 : 0;
}

void mc_boot_sh_send(const mc_boot_link_msg_t *m)
{
    const size_t n = mc_boot_link_encode(m, g_sh.out, sizeof g_sh.out);
    uint32_t a[3] = {g_sh.fd_out, (uint32_t)(uintptr_t)g_sh.out, (uint32_t)n};
    while (a[2] > 0u) {
        const uint32_t left = sh_call(SH_WRITE, a); /* bytes not written */
        if (left >= a[2]) {
            mc_boot_sh_exit(MC_BOOT_SH_EXIT_LINK_EOF);
        }
        a[1] += a[2] - left;
        a[2] = left;
    }
}

void mc_boot_sh_recv(mc_boot_link_msg_t *m)
{
    for (;;) {
        while (g_sh.in_at < g_sh.in_n) {
            if (mc_boot_link_feed(&g_sh.rx, g_sh.in[g_sh.in_at++], m) == 1) {
                return;
            }
        }
        const uint32_t a[3] = {g_sh.fd_in, (uint32_t)(uintptr_t)g_sh.in, sizeof g_sh.in};
        const uint32_t left = sh_call(SH_READ, a); /* bytes not read */
        if (left >= sizeof g_sh.in) {
            mc_boot_sh_exit(MC_BOOT_SH_EXIT_LINK_EOF);
        }
        g_sh.in_n = (uint32_t)sizeof g_sh.in - left;
        g_sh.in_at = 0u;
    }
}
