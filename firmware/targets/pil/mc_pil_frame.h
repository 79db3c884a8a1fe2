/**
 * @file mc_pil_frame.h
 * @brief Processor-in-the-loop link: the frames the host simulator and the
 *        emulated STM32F405 exchange over USART1 once per PWM period.
 *
 * Wire format of one frame (all multi-byte values little-endian):
 *   0xA5 | type (1 byte) | payload length n (1 byte) | payload (n bytes) |
 *   CRC-16/CCITT-FALSE over type, length and payload (2 bytes)
 * Payloads are sequences of 32-bit words; floats travel as their IEEE bit
 * patterns, so both sides see exactly the same values (the link adds no
 * rounding: this is what makes the PIL trajectory bit-identical to SIL).
 *
 * One period, host first:
 *   host -> target  MEAS: what the board's HAL returned at the PWM-synchronous
 *                   sample (ADC sample and return code, encoder, fault
 *                   status, tick) and the commands of this period
 *                   (references, mode).
 *   target          fast-loop interrupt: commands, mc_drive_fast_step(); the
 *                   slow step in PendSV when due.
 *   target -> host  OUT: what the drive did to the bridge this period (last
 *                   accepted duties, enable state, gate kill, the brake
 *                   chopper's duty) and telemetry.
 *   host            applies OUT to the simulated board, integrates one period.
 * Start-up: target -> HELLO once its USART receives (bytes sent earlier
 * would be dropped), then one of
 *   drive alone:     host -> CFG (the drive configuration);
 *   whole image:     host -> PARAMS (one or more: the board's default
 *                    parameter set, (id, raw value) pairs), APP (the rest of
 *                    the application's binding); the image boots the
 *                    application (firmware/app/app/mc_app) from them;
 * then target -> READY (the drive's init result and the protocol version,
 * MC_PIL_VERSION: a host and an image built from different versions stop at
 * READY instead of misreading each other). End: host -> END, the target
 * exits (semihosting).
 *
 * CAN in the whole-image mode, carried over the same link:
 *   host -> target  CAN_RX before a period's MEAS: a frame the bus delivers
 *                   to the drive (the board's CAN receive interrupt runs);
 *   target -> host  CAN_TX between MEAS and OUT: a frame the application
 *                   sent in that period (seq), in the order it sent them.
 * Both loops run within the period, as on the drive board (main.c: the
 * ADC interrupt, then PendSV): OUT is what the bridge does for the next
 * period, whatever part of the application set it.
 *   target -> host  PROBE (version 2) once after READY (the application
 *                   after boot) and once per period after its CAN_TX
 *                   frames, before OUT: the application's probe
 *                   (mc_app_probe_t, mc_pil_probe.h), what the SIL's
 *                   mc_app_probe() gives after the same period.
 *
 * Versions (MC_PIL_VERSION, in READY):
 *   1  drive alone, whole image with CAN (READY without a version word);
 *   2  PROBE frames in the whole-image mode; READY carries the version;
 *   3  the brake chopper: APP says whether the board has one (the image's
 *      HAL then exposes mc_hal_t.brake), OUT carries the brake duty the
 *      drive set this period (count and last duty), which the host applies
 *      to its board's brake before it integrates the period;
 *   4  PROBE carries the sensorless law's I-f frame speed
 *      (mc_app_probe_t.sls_omega_if_rad_s): one word more;
 *   5  Hall sensors: APP's has_brake word becomes the board's capabilities
 *      (caps: MC_PIL_CAP_BRAKE, the value 1 it had, and MC_PIL_CAP_HALL:
 *      the image's HAL then exposes Hall inputs, bound as
 *      mc_app_cfg_t.hall as the F405 image binds mc_f405_hall); MEAS
 *      carries the host board's Hall read at the sample (hall_rc,
 *      hall_code: two words more). APP keeps its size, so a host and an
 *      image of different versions still reach READY and the host refuses
 *      the image by its version; an image given a capability it does not
 *      know answers READY with MC_PIL_READY_ERR_CAPS and its version.
 *   6  the probe carries the anticogging map's status and feed-forward
 *      (mc_app_probe_t.cog_status, cog_ff_a): two words more, past a
 *      frame's payload: PROBE keeps the first 63 words and a PROBE2 frame
 *      right after it carries the rest; FLASH
 *      frames (host -> target, whole image, between the PARAMS and APP):
 *      the board's flash content (a FileFlash file, mcsim --flash), at a
 *      byte offset into the image's RAM store, which is erased (0xFF)
 *      before the first PARAMS and booted by the application after APP;
 *      bytes the host does not send stay erased.
 *
 * Plain C11, no I/O: encoders write into a caller buffer, decoders validate
 * and parse a complete frame. Built for the target (hal/pil/mc_hal_pil.c) and for the
 * host (hal/host PilLink).
 */
#ifndef MC_PIL_FRAME_H
#define MC_PIL_FRAME_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal.h"
#include "mc_drive.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_PIL_SYNC        0xA5u
#define MC_PIL_HEADER_LEN  3u /**< sync, type, length */
#define MC_PIL_CRC_LEN     2u
#define MC_PIL_MAX_PAYLOAD 252u
#define MC_PIL_MAX_FRAME   (MC_PIL_HEADER_LEN + MC_PIL_MAX_PAYLOAD + MC_PIL_CRC_LEN)

typedef enum {
    MC_PIL_TYPE_CFG = 1,     /**< host -> target: mc_drive_cfg_t */
    MC_PIL_TYPE_READY = 2,   /**< target -> host: drive init result */
    MC_PIL_TYPE_MEAS = 3,    /**< host -> target: one period's measurements and commands */
    MC_PIL_TYPE_OUT = 4,     /**< target -> host: one period's bridge actions and telemetry */
    MC_PIL_TYPE_END = 5,     /**< host -> target: stop, exit code in the payload */
    MC_PIL_TYPE_HELLO = 6,   /**< target -> host: receiver ready, empty payload */
    MC_PIL_TYPE_PARAMS = 7,  /**< host -> target: default parameters, (id, raw) pairs */
    MC_PIL_TYPE_APP = 8,     /**< host -> target: mc_pil_app_t, ends the set-up */
    MC_PIL_TYPE_CAN_RX = 9,  /**< host -> target: one CAN frame received by the drive */
    MC_PIL_TYPE_CAN_TX = 10, /**< target -> host: one CAN frame the drive sent */
    MC_PIL_TYPE_PROBE = 11,  /**< target -> host: the application's probe (version 2) */
    MC_PIL_TYPE_FLASH = 12,  /**< host -> target: flash content at an offset (version 6) */
    MC_PIL_TYPE_PROBE2 = 13, /**< target -> host: the probe's rest, after PROBE (version 6) */
} mc_pil_type_t;

/** The link protocol's version (see the file comment), sent in READY. */
#define MC_PIL_VERSION 6u

/** (id, raw) pairs per PARAMS frame (the payload limit). */
#define MC_PIL_PARAMS_MAX 31u
/** Flash bytes per FLASH frame: one offset word, then up to this many
 *  bytes (a multiple of 4, within the payload limit). */
#define MC_PIL_FLASH_CHUNK 248u
/** Rates of the telemetry messages past POSITION (mc_app_cfg_t). */
#define MC_PIL_TM_EXT_RATES 7u

/* Decode errors. */
#define MC_PIL_OK       0
#define MC_PIL_ERR_SYNC (-1) /**< first byte is not MC_PIL_SYNC */
#define MC_PIL_ERR_LEN  (-2) /**< length field does not fit the buffer or the type */
#define MC_PIL_ERR_CRC  (-3)
#define MC_PIL_ERR_TYPE (-4) /**< not the expected frame type */
#define MC_PIL_ERR_ARG  (-5) /**< NULL pointer or buffer too small */

/* The board's capabilities, bits of mc_pil_app_t.caps (version 5). */
#define MC_PIL_CAP_BRAKE (1u << 0) /**< a brake chopper: mc_hal_t.brake (version 3) */
#define MC_PIL_CAP_HALL  (1u << 1) /**< Hall inputs: mc_app_cfg_t.hall (version 5) */
#define MC_PIL_CAP_ALL   (MC_PIL_CAP_BRAKE | MC_PIL_CAP_HALL)

/** mc_pil_ready_t.drive_cfg_err of an image that refused APP's caps (a bit
 *  outside MC_PIL_CAP_ALL: a host of a later version); no mc_drive_init()
 *  result has every bit set. */
#define MC_PIL_READY_ERR_CAPS 0xFFFFFFFFu

/* Command bits of mc_pil_meas_t.cmd_flags. */
#define MC_PIL_CMD_SET_MODE (1u << 0)
#define MC_PIL_CMD_SET_REFS (1u << 1)

/** Host -> target, once per period. */
typedef struct {
    uint32_t seq;            /**< period number */
    int32_t adc_rc;          /**< board adc read() result (0, -EAGAIN, ...) */
    mc_hal_adc_sample_t adc; /**< valid when adc_rc == 0 */
    int32_t enc_rc;
    mc_hal_encoder_sample_t enc;
    int32_t fault_rc;
    mc_hal_fault_status_t fault; /**< board fault inputs at the sample */
    uint32_t tick_ticks;         /**< board tick counter at the sample */
    uint32_t tick_hz;            /**< board tick counter frequency */
    uint32_t cmd_flags;          /**< MC_PIL_CMD_* */
    uint32_t mode;               /**< mc_drive_mode_t, with MC_PIL_CMD_SET_MODE */
    float id_ref_a;              /**< with MC_PIL_CMD_SET_REFS */
    float iq_ref_a;
    int32_t temp_rc;        /**< board adc read_temp() result */
    mc_hal_adc_temp_t temp; /**< temperature channels, valid when temp_rc == 0 */
    int32_t hall_rc;        /**< board Hall read() result (-ENODEV: no Hall inputs;
                                 version 5) */
    uint32_t hall_code;     /**< the sensors' code 0..7, valid when hall_rc == 0 */
} mc_pil_meas_t;

/** Target -> host, once per period. */
typedef struct {
    uint32_t seq;                 /**< echo of the MEAS seq */
    uint32_t duty_set_count;      /**< accepted pwm3 set_duty calls this period */
    float duty_a, duty_b, duty_c; /**< last accepted duties */
    uint32_t pwm_enabled;         /**< 1: modulating at the end of the period */
    uint32_t gate_kill_count;     /**< gate kills this period */
    int32_t cmd_rc;               /**< result of this period's commands (first error) */
    uint32_t mode;                /**< drive mode after the period */
    uint32_t faults;              /**< sticky MC_DRIVE_FAULT_* */
    uint32_t first_fault;
    uint32_t foc_err;
    float id_a, iq_a; /**< FOC measured dq currents */
    float vd_v, vq_v; /**< FOC applied dq voltages */
    float theta_e_rad;
    float omega_m_rad_s;
    uint32_t ipsr_fast; /**< exception number of the fast step (34 = ADC IRQ) */
    uint32_t ipsr_slow; /**< of the slow step (14 = PendSV), 0 if none ran */
    uint32_t slow_ran;
    uint32_t brake_set_count; /**< accepted brake set_duty calls this period
                                   (version 3) */
    float brake_duty;         /**< the last accepted brake chopper duty */
    /* What the application's slow work did to the bridge (whole-image mode;
     * zero counts and pwm_enabled unchanged otherwise): applied by the host
     * after the period's integration. */
} mc_pil_out_t;

/** Host -> target (whole-image mode): the application's binding besides the
 *  parameters (the fields of mc_app_cfg_t the board gets from the rig). */
typedef struct {
    float tm_budget_frac;
    uint32_t tm_ext_rate_hz[MC_PIL_TM_EXT_RATES];
    uint32_t pwm_hz_fixed;
    uint32_t slow_loop_div_fixed;
    uint32_t tick_hz; /**< the board's tick frequency, answered before the first MEAS */
    uint32_t caps;    /**< MC_PIL_CAP_* the board has, the image's HAL exposes
                        (version 5; version 3 and 4: has_brake, 1 or 0) */
} mc_pil_app_t;

/** Target -> host after CFG. */
typedef struct {
    uint32_t drive_cfg_err; /**< mc_drive_init() result */
    uint32_t sysclk_hz;     /**< clock set-up result (0: no RCC, emulator) */
    uint32_t version;       /**< MC_PIL_VERSION of the image */
} mc_pil_ready_t;

/** CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection). */
uint16_t mc_pil_crc16(const uint8_t *p, size_t n);

/* Encoders: write a whole frame into buf (capacity cap), return its length,
 * or 0 if buf is NULL or too small. */
size_t mc_pil_encode_cfg(const mc_drive_cfg_t *cfg, uint8_t *buf, size_t cap);
size_t mc_pil_encode_ready(const mc_pil_ready_t *r, uint8_t *buf, size_t cap);
size_t mc_pil_encode_meas(const mc_pil_meas_t *m, uint8_t *buf, size_t cap);
size_t mc_pil_encode_out(const mc_pil_out_t *o, uint8_t *buf, size_t cap);
size_t mc_pil_encode_end(int32_t exit_code, uint8_t *buf, size_t cap);
size_t mc_pil_encode_hello(uint8_t *buf, size_t cap);
/** n (1..MC_PIL_PARAMS_MAX) parameter ids and raw values. */
size_t mc_pil_encode_params(const uint32_t *ids, const uint32_t *raws, uint32_t n, uint8_t *buf,
                            size_t cap);
size_t mc_pil_encode_app(const mc_pil_app_t *a, uint8_t *buf, size_t cap);
/** n (4..MC_PIL_FLASH_CHUNK, a multiple of 4) bytes of flash at offset. */
size_t mc_pil_encode_flash(uint32_t offset, const uint8_t *data, uint32_t n, uint8_t *buf,
                           size_t cap);
size_t mc_pil_encode_can_rx(const mc_hal_can_frame_t *f, uint8_t *buf, size_t cap);
/** seq: the period (MEAS seq) in which the application sent f. */
size_t mc_pil_encode_can_tx(uint32_t seq, const mc_hal_can_frame_t *f, uint8_t *buf, size_t cap);

/** A frame of n_words 32-bit words (n_words <= MC_PIL_MAX_PAYLOAD / 4), for
 *  payloads defined beside this file (mc_pil_probe.h). */
size_t mc_pil_encode_words(mc_pil_type_t type, const uint32_t *words, uint32_t n_words,
                           uint8_t *buf, size_t cap);

/**
 * Length of the frame that starts at buf given its first n bytes: 0 while
 * fewer than the header are known, else header + payload + CRC.
 */
size_t mc_pil_frame_len(const uint8_t *buf, size_t n);

/** Type of a complete, CRC-checked frame (MC_PIL_TYPE_*), or a negative
 *  MC_PIL_ERR_*. */
int mc_pil_frame_type(const uint8_t *buf, size_t n);

/* Decoders: parse a complete frame of the given type. MC_PIL_OK, or an
 * MC_PIL_ERR_* with *out unchanged. */
int mc_pil_decode_cfg(const uint8_t *buf, size_t n, mc_drive_cfg_t *out);
int mc_pil_decode_ready(const uint8_t *buf, size_t n, mc_pil_ready_t *out);
int mc_pil_decode_meas(const uint8_t *buf, size_t n, mc_pil_meas_t *out);
int mc_pil_decode_out(const uint8_t *buf, size_t n, mc_pil_out_t *out);
int mc_pil_decode_end(const uint8_t *buf, size_t n, int32_t *out);
/** ids and raws hold MC_PIL_PARAMS_MAX entries; *p_n the pairs decoded. */
int mc_pil_decode_params(const uint8_t *buf, size_t n, uint32_t *ids, uint32_t *raws,
                         uint32_t *p_n);
int mc_pil_decode_app(const uint8_t *buf, size_t n, mc_pil_app_t *out);
/** A FLASH frame's offset, and its bytes in place (*p_data points into
 *  buf: no copy), *p_n of them. */
int mc_pil_decode_flash(const uint8_t *buf, size_t n, uint32_t *p_offset, const uint8_t **p_data,
                        uint32_t *p_n);
/** A data length that is not a CAN (FD) length, or one that disagrees with
 *  the payload size: MC_PIL_ERR_LEN. */
int mc_pil_decode_can_rx(const uint8_t *buf, size_t n, mc_hal_can_frame_t *out);
int mc_pil_decode_can_tx(const uint8_t *buf, size_t n, uint32_t *p_seq, mc_hal_can_frame_t *out);
/** A complete frame of the given type and exactly n_words words into words. */
int mc_pil_decode_words(const uint8_t *buf, size_t n, mc_pil_type_t type, uint32_t *words,
                        uint32_t n_words);
/** MC_PIL_OK if buf is a complete HELLO frame. */
int mc_pil_check_hello(const uint8_t *buf, size_t n);

#ifdef __cplusplus
}
#endif

#endif /* MC_PIL_FRAME_H */
