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

_Static_assert(MC_PIL_PROBE1_WORDS * 4u <= MC_PIL_MAX_PAYLOAD, "PROBE fits a frame");
_Static_assert((MC_PIL_PROBE2_WORDS > 0u) && (MC_PIL_PROBE2_WORDS * 4u <= MC_PIL_MAX_PAYLOAD),
               "PROBE2 fits a frame");

/* Words [first, first + n) of the probe as a frame of type t. */
static size_t encode_part(const mc_app_probe_t *p, mc_pil_type_t t, uint32_t first, uint32_t n,
                          uint8_t *buf, size_t cap)
{
    uint32_t w[MC_PIL_PROBE1_WORDS];
    if (p == NULL) {
        return 0u;
    }
    (void)memcpy(w, (const uint8_t *)p + ((size_t)first * 4u), (size_t)n * 4u);
    return mc_pil_encode_words(t, w, n, buf, cap);
}

static int decode_part(const uint8_t *buf, size_t n, mc_pil_type_t t, uint32_t first,
                       uint32_t words, mc_app_probe_t *out)
{
    uint32_t w[MC_PIL_PROBE1_WORDS];
    if (out == NULL) {
        return MC_PIL_ERR_ARG;
    }
    const int rc = mc_pil_decode_words(buf, n, t, w, words);
    if (rc == MC_PIL_OK) {
        (void)memcpy((uint8_t *)out + ((size_t)first * 4u), w, (size_t)words * 4u);
    }
    return rc;
}

size_t mc_pil_encode_probe(const mc_app_probe_t *p, uint8_t *buf, size_t cap)
{
    return encode_part(p, MC_PIL_TYPE_PROBE, 0u, MC_PIL_PROBE1_WORDS, buf, cap);
}

size_t mc_pil_encode_probe2(const mc_app_probe_t *p, uint8_t *buf, size_t cap)
{
    return encode_part(p, MC_PIL_TYPE_PROBE2, MC_PIL_PROBE1_WORDS, MC_PIL_PROBE2_WORDS, buf, cap);
}

int mc_pil_decode_probe(const uint8_t *buf, size_t n, mc_app_probe_t *out)
{
    return decode_part(buf, n, MC_PIL_TYPE_PROBE, 0u, MC_PIL_PROBE1_WORDS, out);
}

int mc_pil_decode_probe2(const uint8_t *buf, size_t n, mc_app_probe_t *out)
{
    return decode_part(buf, n, MC_PIL_TYPE_PROBE2, MC_PIL_PROBE1_WORDS, MC_PIL_PROBE2_WORDS, out);
}
