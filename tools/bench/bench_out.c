/**
 * @file bench_out.c
 * @brief The benchmark images' line output (bench_out.h).
 */
#include "bench_out.h"

#include "m4f/semihost.h"

static char g_line[320];
static uint32_t g_pos;

void bench_out_str(const char *s)
{
    while (*s != '\0' && g_pos + 1u < sizeof g_line) {
        g_line[g_pos++] = *s++;
    }
    g_line[g_pos] = '\0';
}

void bench_out_u32(uint32_t v)
{
    char tmp[11];
    int n = 0;
    do {
        tmp[n++] = (char)('0' + (char)(v % 10u));
        v /= 10u;
    } while (v != 0u);
    char s[12];
    for (int k = 0; k < n; ++k) {
        s[k] = tmp[n - 1 - k];
    }
    s[n] = '\0';
    bench_out_str(s);
}

void bench_out_flush(void)
{
    bench_out_str("\n");
    mc_sh_write0(g_line);
    g_pos = 0u;
    g_line[0] = '\0';
}
