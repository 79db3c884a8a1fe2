/**
 * @file bench_out.h
 * @brief The benchmark images' output: one text line at a time, written
 *        through semihosting when flushed (bench_m4f.c, bench_isr.c).
 */
#ifndef MC_BENCH_OUT_H
#define MC_BENCH_OUT_H

#include <stdint.h>

/** Append a string to the line (cut at the line's capacity). */
void bench_out_str(const char *s);
/** Append an unsigned decimal number. */
void bench_out_u32(uint32_t v);
/** End the line with a newline and write it. */
void bench_out_flush(void);

#endif /* MC_BENCH_OUT_H */
