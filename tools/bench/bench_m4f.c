/**
 * @file bench_m4f.c
 * @brief Instruction counts of the control kernels and of the whole fast
 *        loop on the emulated Cortex-M4F (QEMU netduinoplus2).
 *
 * Counting: TIM2 at PSC = 0 under `qemu-system-arm -icount shift=0` advances
 * exactly one tick per executed instruction. Each case is a small wrapper
 * (index -> inputs from a table -> kernel -> outputs to a sink) called
 * through a function pointer between two reads of TIM2_CNT; the same
 * measurement of an empty wrapper is subtracted, so a count is what the
 * kernel call costs at its call site (argument set-up, call, body, return),
 * per call. Inputs are drawn once, before counting, from the operating
 * ranges; stateful kernels (PI, FOC, drive) run on as in a loop.
 *
 * Output: one JSON object per line through semihosting:
 *   {"name": ..., "format": "f32"|"q31", "kind": "kernel"|"fast_loop",
 *    "calls": N, "instr_min": .., "instr_mean": .., "instr_max": ..}
 * tools/bench/run_bench.py turns them into the report (time at 168 MHz,
 * CPU load at 20 kHz, image sizes).
 */
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "bench_cases.h"
#include "bench_out.h"
#include "m4f/semihost.h"

#define TIM2_CR1 (*(volatile uint32_t *)0x40000000u)
#define TIM2_EGR (*(volatile uint32_t *)0x40000014u)
#define TIM2_CNT (*(volatile uint32_t *)0x40000024u)
#define TIM2_PSC (*(volatile uint32_t *)0x40000028u)
#define TIM2_ARR (*(volatile uint32_t *)0x4000002Cu)

static void tim2_start(void)
{
    TIM2_CR1 = 0u;
    TIM2_PSC = 0u;
    TIM2_ARR = 0xFFFFFFFFu;
    TIM2_EGR = 1u; /* UG: load PSC, CNT = 0 */
    TIM2_CR1 = 1u; /* CEN */
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

/* ---- text output ------------------------------------------------------- */

/* mean with one decimal: sum / n, printed as <int>.<tenth> */
static void out_mean(uint32_t sum, uint32_t n)
{
    const uint32_t tenths = (10u * sum + n / 2u) / n;
    bench_out_u32(tenths / 10u);
    bench_out_str(".");
    bench_out_u32(tenths % 10u);
}

/* ---- main -------------------------------------------------------------- */

static uint32_t g_overhead;

static void run_case(const bench_case_t *c)
{
    uint32_t mn = 0xFFFFFFFFu;
    uint32_t mx = 0u;
    uint32_t sum = 0u;
    for (uint32_t i = 0u; i < c->calls; ++i) {
        const uint32_t raw = measure_once(c->fn, i);
        const uint32_t d = (raw > g_overhead) ? raw - g_overhead : 0u;
        mn = (d < mn) ? d : mn;
        mx = (d > mx) ? d : mx;
        sum += d;
    }
    bench_out_str("{\"name\": \"");
    bench_out_str(c->name);
    bench_out_str("\", \"format\": \"");
    bench_out_str(c->format);
    bench_out_str("\", \"kind\": \"");
    bench_out_str(c->kind);
    bench_out_str("\", \"calls\": ");
    bench_out_u32(c->calls);
    bench_out_str(", \"instr_min\": ");
    bench_out_u32(mn);
    bench_out_str(", \"instr_mean\": ");
    out_mean(sum, c->calls);
    bench_out_str(", \"instr_max\": ");
    bench_out_u32(mx);
    bench_out_str("}");
    bench_out_flush();
}

int main(void)
{
    if (bench_setup() != 0 || bench_setup_q31() != 0) {
        mc_sh_write0("bench: a kernel refused its configuration\n");
        return 1;
    }
    tim2_start();
    /* Overhead: the smallest cost of measuring an empty wrapper. */
    g_overhead = 0xFFFFFFFFu;
    for (uint32_t i = 0u; i < 16u; ++i) {
        const uint32_t d = measure_once(empty_case, i);
        g_overhead = (d < g_overhead) ? d : g_overhead;
    }
    bench_out_str("{\"overhead_instr\": ");
    bench_out_u32(g_overhead);
    bench_out_str("}");
    bench_out_flush();
    if (TIM2_CNT == 0u) {
        mc_sh_write0("bench: TIM2 does not count (run under -icount shift=0)\n");
        return 2;
    }
    const bench_case_t *cases = bench_cases();
    for (uint32_t k = 0u; cases[k].fn != 0; ++k) {
        run_case(&cases[k]);
    }
    const bench_case_t *q31_cases = bench_cases_q31();
    for (uint32_t k = 0u; q31_cases[k].fn != 0; ++k) {
        run_case(&q31_cases[k]);
    }
    if (bench_check() != 0) {
        mc_sh_write0("bench: the drive left current mode during the run\n");
        return 3;
    }
    return 0;
}
