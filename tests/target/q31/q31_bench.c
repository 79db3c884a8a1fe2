/* Instruction counts of the q31 twin kernels and of their f32 twins on the
 * same inputs (tools/bench/bench_cases_q31.c), on the emulated Cortex-M3
 * (QEMU netduino2, STM32F205, no FPU: f32 in software) or Cortex-M4F
 * (netduinoplus2), by the method of tools/bench/bench_m4f.c: TIM2 at PSC 0
 * under -icount shift=0 ticks once per instruction; the cost of an empty
 * wrapper is subtracted. One JSON object per line through semihosting. */
#include <stdint.h>

#include "bench_cases.h"
#include "m4f/semihost.h"

int bench_setup_q31(void);
const bench_case_t *bench_cases_q31(void);
const bench_case_t *bench_cases_q31_f32twins(void);

#define TIM2_CR1 (*(volatile uint32_t *)0x40000000u)
#define TIM2_EGR (*(volatile uint32_t *)0x40000014u)
#define TIM2_CNT (*(volatile uint32_t *)0x40000024u)
#define TIM2_PSC (*(volatile uint32_t *)0x40000028u)
#define TIM2_ARR (*(volatile uint32_t *)0x4000002Cu)

/* Needed by bench_cases.h users; only the empty case calls it here. */
static volatile uint32_t g_sink;
void bench_sink_u32(uint32_t v)
{
    g_sink = v;
}

static __attribute__((noinline)) uint32_t measure_once(bench_fn_t fn, uint32_t i)
{
    const uint32_t t0 = TIM2_CNT;
    fn(i);
    const uint32_t t1 = TIM2_CNT;
    return t1 - t0;
}

static __attribute__((noinline)) void empty_case(uint32_t i)
{
    bench_sink_u32(i);
}

static char g_line[200];
static uint32_t g_pos;

static void out_str(const char *s)
{
    while ((*s != '\0') && ((g_pos + 1u) < sizeof g_line)) {
        g_line[g_pos++] = *s++;
    }
    g_line[g_pos] = '\0';
}

static void out_u32(uint32_t v)
{
    char t[11];
    char s[12];
    int n = 0;
    do {
        t[n++] = (char)('0' + (char)(v % 10u));
        v /= 10u;
    } while (v != 0u);
    for (int k = 0; k < n; ++k) {
        s[k] = t[n - 1 - k];
    }
    s[n] = '\0';
    out_str(s);
}

static void flush_line(void)
{
    out_str("\n");
    mc_sh_write0(g_line);
    g_pos = 0u;
    g_line[0] = '\0';
}

static uint32_t g_overhead;

static void run_table(const bench_case_t *cases)
{
    for (uint32_t k = 0u; cases[k].fn != 0; ++k) {
        const bench_case_t *c = &cases[k];
        uint32_t mn = 0xFFFFFFFFu;
        uint32_t mx = 0u;
        uint32_t sum = 0u;
        for (uint32_t i = 0u; i < c->calls; ++i) {
            const uint32_t raw = measure_once(c->fn, i);
            const uint32_t d = (raw > g_overhead) ? (raw - g_overhead) : 0u;
            mn = (d < mn) ? d : mn;
            mx = (d > mx) ? d : mx;
            sum += d;
        }
        out_str("{\"name\": \"");
        out_str(c->name);
        out_str("\", \"format\": \"");
        out_str(c->format);
        out_str("\", \"calls\": ");
        out_u32(c->calls);
        out_str(", \"instr_min\": ");
        out_u32(mn);
        out_str(", \"instr_mean\": ");
        out_u32((sum + (c->calls / 2u)) / c->calls);
        out_str(", \"instr_max\": ");
        out_u32(mx);
        out_str("}");
        flush_line();
    }
}

int main(void)
{
    if (bench_setup_q31() != 0) {
        mc_sh_write0("q31 bench: a kernel refused its configuration\n");
        return 1;
    }
    TIM2_CR1 = 0u;
    TIM2_PSC = 0u;
    TIM2_ARR = 0xFFFFFFFFu;
    TIM2_EGR = 1u;
    TIM2_CR1 = 1u;
    g_overhead = 0xFFFFFFFFu;
    for (uint32_t i = 0u; i < 16u; ++i) {
        const uint32_t d = measure_once(empty_case, i);
        g_overhead = (d < g_overhead) ? d : g_overhead;
    }
    if (TIM2_CNT == 0u) {
        mc_sh_write0("q31 bench: TIM2 does not count (run under -icount shift=0)\n");
        return 2;
    }
    out_str("{\"overhead_instr\": ");
    out_u32(g_overhead);
    out_str("}");
    flush_line();
    run_table(bench_cases_q31());
    run_table(bench_cases_q31_f32twins());
    return 0;
}
