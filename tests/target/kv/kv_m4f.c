/* Target side of the kernel vectors (see kv.h): the family and the two file
 * names come from the semihosting command line
 * (-semihosting-config arg=kv,arg=<family>,arg=<in>,arg=<out>), the files
 * are the host's, read and written through semihosting. */
#include <stdint.h>
#include <string.h>

#include "kv.h"
#include "m4f/semihost.h"

static uint32_t sh_call(uint32_t op, const void *arg)
{
    register uint32_t r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

#define SYS_OPEN        0x01u
#define SYS_CLOSE       0x02u
#define SYS_WRITE       0x05u
#define SYS_READ        0x06u
#define SYS_GET_CMDLINE 0x15u
#define MODE_RB         1u
#define MODE_WB         5u

static int32_t sh_open(const char *path, uint32_t mode)
{
    const uint32_t args[3] = {(uint32_t)(uintptr_t)path, mode, (uint32_t)strlen(path)};
    return (int32_t)sh_call(SYS_OPEN, args);
}

static void sh_close(int32_t h)
{
    const uint32_t args[1] = {(uint32_t)h};
    (void)sh_call(SYS_CLOSE, args);
}

typedef struct {
    int32_t in;
    int32_t out;
} handles_t;

/* SYS_READ returns the number of bytes NOT read. */
static size_t t_read(void *ctx, void *buf, size_t n)
{
    const handles_t *h = ctx;
    const uint32_t args[3] = {(uint32_t)h->in, (uint32_t)(uintptr_t)buf, (uint32_t)n};
    const uint32_t left = sh_call(SYS_READ, args);
    return (left <= n) ? n - left : 0u;
}

static int t_write(void *ctx, const void *buf, size_t n)
{
    const handles_t *h = ctx;
    const uint32_t args[3] = {(uint32_t)h->out, (uint32_t)(uintptr_t)buf, (uint32_t)n};
    return (sh_call(SYS_WRITE, args) == 0u) ? 0 : 1;
}

static char g_cmdline[512];

int main(void)
{
    uint32_t args[2] = {(uint32_t)(uintptr_t)g_cmdline, sizeof g_cmdline - 1u};
    if (sh_call(SYS_GET_CMDLINE, args) != 0u) {
        mc_sh_write0("kv: no command line\n");
        return 11;
    }
    /* "kv <family> <in> <out>", separated by single spaces. */
    char *word[4] = {0, 0, 0, 0};
    int nw = 0;
    char *p = g_cmdline;
    while (*p != '\0' && nw < 4) {
        word[nw++] = p;
        while (*p != '\0' && *p != ' ') {
            ++p;
        }
        if (*p == ' ') {
            *p++ = '\0';
        }
    }
    if (nw != 4) {
        mc_sh_write0("kv: expected kv <family> <in> <out>\n");
        return 11;
    }
    handles_t h = {sh_open(word[2], MODE_RB), sh_open(word[3], MODE_WB)};
    if (h.in < 0 || h.out < 0) {
        mc_sh_write0("kv: cannot open the files\n");
        return 12;
    }
    const kv_io_t io = {t_read, t_write, &h};
    const int rc = kv_run(word[1], &io);
    sh_close(h.in);
    sh_close(h.out);
    return rc;
}
