/**
 * @file mc_pil_probe.h
 * @brief The PROBE frame of the processor-in-the-loop link (protocol
 *        version 2, mc_pil_frame.h): the drive application's probe
 *        (mc_app_probe_t) after a period, as the SIL's mc_app_probe() gives
 *        it, so a scenario reads the image's application as it reads the
 *        host's.
 *
 * Payload: the probe's fields in their declaration order, one 32-bit word
 * each (floats as their IEEE bit patterns, little-endian as every link
 * word), the first MC_PIL_PROBE1_WORDS in PROBE (a frame's limit), the
 * rest in PROBE2 right after it (version 6). Every field of mc_app_probe_t is one 32-bit word (a compile-time
 * check in mc_pil_probe.c): a field added to the probe changes
 * MC_PIL_PROBE_WORDS and the build says so.
 *
 * Apart from mc_pil_frame.h because it needs the application's header (the
 * bootloaders' link code does not).
 */
#ifndef MC_PIL_PROBE_H
#define MC_PIL_PROBE_H

#include <stddef.h>
#include <stdint.h>

#include "mc_app.h"
#include "mc_pil_frame.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The probe's words: sizeof(mc_app_probe_t) / 4. */
#define MC_PIL_PROBE_WORDS 65u
/** Payload words of PROBE: the probe's first words, as many as a frame
 *  holds (MC_PIL_MAX_PAYLOAD / 4). */
#define MC_PIL_PROBE1_WORDS 63u
/** Payload words of PROBE2 (version 6), sent right after PROBE: the rest. */
#define MC_PIL_PROBE2_WORDS (MC_PIL_PROBE_WORDS - MC_PIL_PROBE1_WORDS)

/** Encode p's first part (PROBE); the frame's length, 0 if p or buf is
 *  NULL or buf too small. */
size_t mc_pil_encode_probe(const mc_app_probe_t *p, uint8_t *buf, size_t cap);
/** Encode p's second part (PROBE2); as mc_pil_encode_probe. */
size_t mc_pil_encode_probe2(const mc_app_probe_t *p, uint8_t *buf, size_t cap);
/** PROBE into out's first MC_PIL_PROBE1_WORDS words (the rest untouched):
 *  MC_PIL_OK, or an MC_PIL_ERR_* with *out unchanged. */
int mc_pil_decode_probe(const uint8_t *buf, size_t n, mc_app_probe_t *out);
/** PROBE2 into out's last MC_PIL_PROBE2_WORDS words; as mc_pil_decode_probe. */
int mc_pil_decode_probe2(const uint8_t *buf, size_t n, mc_app_probe_t *out);

#ifdef __cplusplus
}
#endif

#endif /* MC_PIL_PROBE_H */
