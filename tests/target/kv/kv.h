/* Kernel vectors: each kernel family runs over a file of recorded input
 * records and writes a file of output records, identically on the host and
 * on the emulated Cortex-M4F; tests/target compares the two files bit for
 * bit (run_kv.sh). Records are sequences of 32-bit little-endian words
 * (floats as their bit patterns); NaN outputs are written as one canonical
 * pattern, because x86 and ARM generate different default NaNs and the
 * kernels only promise "NaN". */
#ifndef MC_KV_H
#define MC_KV_H

#include <stddef.h>
#include <stdint.h>

/* Platform I/O: read exactly n bytes (returns n, or less at the end of the
 * input), write n bytes (returns 0 on success). */
typedef struct {
    size_t (*read)(void *ctx, void *buf, size_t n);
    int (*write)(void *ctx, const void *buf, size_t n);
    void *ctx;
} kv_io_t;

typedef struct {
    const char *name;
    uint32_t in_words;  /**< 32-bit words per input record */
    uint32_t out_words; /**< per output record */
} kv_family_t;

/** The families, terminated by name == NULL. */
const kv_family_t *kv_families(void);

/** Find a family by name, or NULL. */
const kv_family_t *kv_find(const char *name);

/**
 * Run one family over every input record. Returns 0, or: 1 unknown family,
 * 2 a kernel refused its configuration, 3 the input ends inside a record,
 * 4 write error, 5 no records.
 */
int kv_run(const char *family, const kv_io_t *io);

#endif /* MC_KV_H */
