/**
 * @file bench_cases.h
 * @brief The benchmark's cases: one wrapper per kernel (and per whole fast
 *        loop), called with a sample index; see bench_m4f.c for how they
 *        are counted.
 */
#ifndef MC_BENCH_CASES_H
#define MC_BENCH_CASES_H

#include <stdint.h>

typedef void (*bench_fn_t)(uint32_t i);

typedef struct {
    const char *name;   /**< kernel or loop name */
    const char *format; /**< "f32" or "q31" */
    const char *kind;   /**< "kernel" or "fast_loop" */
    bench_fn_t fn;      /**< NULL ends the table */
    uint32_t calls;     /**< samples measured (<= BENCH_N) */
} bench_case_t;

#define BENCH_N 64u

/** Draw the inputs and initialise every kernel; non-zero if one refused its
 *  configuration. */
int bench_setup(void);

/** The cases, terminated by an entry with fn == NULL. */
const bench_case_t *bench_cases(void);

/** 0 if the stateful cases stayed on their nominal path (drive running). */
int bench_check(void);

/** q31 twins of the control kernels (bench_cases_q31.c): set-up and cases. */
int bench_setup_q31(void);
const bench_case_t *bench_cases_q31(void);

/** Keep a result alive (the compiler must not drop the kernel call). */
void bench_sink_u32(uint32_t v);

#endif /* MC_BENCH_CASES_H */
