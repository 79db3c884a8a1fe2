/**
 * @file mc_pil_probe.c
 * @brief The PROBE frame: see mc_pil_probe.h.
 */
#include "mc_pil_probe.h"

#include <string.h>

/* Every field one 32-bit word, no padding: the struct is its payload. A
 * copy into words keeps each field's bits (a float's IEEE pattern) on any
 * byte order; the link writes the words little-endian. */
_Static_assert(sizeof(mc_app_probe_t) == sizeof(uint32_t[MC_PIL_PROBE_WORDS]),
               "mc_app_probe_t changed: update MC_PIL_PROBE_WORDS (one 32-bit word per field)");

size_t mc_pil_encode_probe(const mc_app_probe_t *p, uint8_t *buf, size_t cap)
{
    uint32_t w[MC_PIL_PROBE_WORDS];
    if (p == NULL) {
        return 0u;
    }
    (void)memcpy(w, p, sizeof w);
    return mc_pil_encode_words(MC_PIL_TYPE_PROBE, w, MC_PIL_PROBE_WORDS, buf, cap);
}

int mc_pil_decode_probe(const uint8_t *buf, size_t n, mc_app_probe_t *out)
{
    uint32_t w[MC_PIL_PROBE_WORDS];
    if (out == NULL) {
        return MC_PIL_ERR_ARG;
    }
    const int rc = mc_pil_decode_words(buf, n, MC_PIL_TYPE_PROBE, w, MC_PIL_PROBE_WORDS);
    if (rc == MC_PIL_OK) {
        (void)memcpy(out, w, sizeof w);
    }
    return rc;
}
