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
 * word). Every field of mc_app_probe_t is one 32-bit word (a compile-time
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

/** Payload words of PROBE: sizeof(mc_app_probe_t) / 4. */
#define MC_PIL_PROBE_WORDS 65u

/** Encode p; the frame's length, 0 if p or buf is NULL or buf too small. */
size_t mc_pil_encode_probe(const mc_app_probe_t *p, uint8_t *buf, size_t cap);
/** MC_PIL_OK, or an MC_PIL_ERR_* with *out unchanged. */
int mc_pil_decode_probe(const uint8_t *buf, size_t n, mc_app_probe_t *out);

#ifdef __cplusplus
}
#endif

#endif /* MC_PIL_PROBE_H */
