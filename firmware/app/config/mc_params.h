/**
 * @file mc_params.h
 * @brief The drive's parameters: lookup by id, checked single writes, the
 *        whole-configuration validation and the mapping onto the drive's
 *        mc_drive_cfg_t.
 *
 * The table (ids, types, ranges, defaults, access) is generated from
 * tools/config/params.toml into mc_params_gen.{h,c}; this module only
 * interprets it. A single value is checked against its type and range
 * (f32: finite and in [min, max]; u32: in [min, max]); values that are only
 * valid together are checked by mc_params_validate() on the whole set,
 * which ends with the drive's own init validation (mc_drive_check_cfg), so
 * a configuration is accepted only if mc_drive_init would accept it.
 */
#ifndef MC_PARAMS_H
#define MC_PARAMS_H

#include <stdint.h>

#include "mc_drive.h"
#include "mc_gains.h"
#include "mc_params_gen.h"
#include "hall/mc_hall.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Status of one parameter operation (the CAN PARAM_REPLY.status values). */
typedef enum {
    MC_PARAM_OK = 0,
    MC_PARAM_ERR_UNKNOWN_ID = 1,     /**< no parameter with this id */
    MC_PARAM_ERR_READONLY = 2,       /**< written, but computed by the drive */
    MC_PARAM_ERR_RANGE = 3,          /**< outside [min, max], or NaN/inf */
    MC_PARAM_ERR_RUNNING = 4,        /**< stopped/reboot parameter (or save, load
                                      defaults, an apply that needs it) while
                                      the bridge is on */
    MC_PARAM_ERR_FAULT = 5,          /**< a fault is latched: only the clear path */
    MC_PARAM_ERR_INVALID = 6,        /**< the whole configuration fails validation
                                      (see PARAM_REPLY.value: MC_PARAMS_ERR_* bits) */
    MC_PARAM_ERR_STORE = 7,          /**< the flash store failed */
    MC_PARAM_ERR_OPCODE = 8,         /**< unknown opcode */
    MC_PARAM_ERR_NEEDS_CONFIRM = 9,  /**< a reboot parameter's new value waits
                                          for its CONFIRM (nothing staged yet) */
    MC_PARAM_ERR_NOT_CONFIRMED = 10, /**< CONFIRM without the WRITE just before
                                          it, of another id or value, or late */
    MC_PARAM_ERR_RATE_LIMIT = 11,    /**< SAVE refused by its rate limit (the
                                          value: seconds until the next one) */
} mc_param_status_t;

/* Whole-configuration errors (bits) of mc_params_validate. */
#define MC_PARAMS_OK            0u
#define MC_PARAMS_ERR_NULL      (1u << 0) /**< NULL argument */
#define MC_PARAMS_ERR_RANGE     (1u << 1) /**< a value outside its table range, or not finite */
#define MC_PARAMS_ERR_SENSE     (1u << 2) /**< i_max_a or i_trip_a above i_sense_max_a */
#define MC_PARAMS_ERR_BANDWIDTH (1u << 3) /**< current_bw_rad_s / pwm_hz > 0.5 */
#define MC_PARAMS_ERR_DEAD_TIME (1u << 4) /**< dead time above 10 % of the PWM period */
#define MC_PARAMS_ERR_BITRATE   (1u << 5) /**< CAN bit rate not 125k, 250k, 500k or 1M */
#define MC_PARAMS_ERR_DRIVE \
    (1u << 6) /**< mc_drive_check_cfg refused the derived
                                                  mc_drive_cfg_t */
#define MC_PARAMS_ERR_LAW \
    (1u << 7) /**< the speed_law selected has no valid gains for these
                   motor values, or its init refused them (the
                   law_error parameter says why: mc_law_cfg.h) */
#define MC_PARAMS_ERR_GAINS \
    (1u << 8) /**< no safe gains for these motor and board values
                   (mc_params_resolve returns the MC_GAINS_ERR_* reason) */
#define MC_PARAMS_ERR_ENCODER \
    (1u << 9) /**< encoder_cpr 1 to 3 (0: none, else >= 4); encoder_type 1
                   (Hall) with encoder_cpr not 6 pole_pairs, angle_ref not
                   0 (stored), or a Hall table mc_hall_f32_validate refuses */
#define MC_PARAMS_ERR_BOARD \
    (1u << 10) /**< the board cannot run it: brake_enable on a board
                    without a brake chopper, vbus_board_max_v above the
                    board's own (the application's checks, mc_app.h);
                    vbus_max_v above vbus_board_max_v, or vbus_v not
                    below it */
#define MC_PARAMS_ERR_HALL_OBS \
    (1u << 12) /**< the Hall + observer hand-over is on (hall_obs_end_e_rad_s
                    > 0) and cannot run: mc_law_hallobs_cfg names why
                    (MC_DRIVE_HALLOBS_ERR_*: not a Hall encoder, the
                    observer's motor values, start / end / disagree) */
#define MC_PARAMS_ERR_COG_CAL \
    (1u << 13) /**< anticogging 2 (calibrate) applied while the drive is
                    not enabled in SPEED mode with its angle known and a
                    speed reference of 0, or a calibration already runs
                    (mc_app.h) */
#define MC_PARAMS_ERR_ANGLE_REF \
    (1u << 11) /**< angle_ref index or align (or angle_find_at_enable) on
                    a drive without an encoder (encoder_cpr 0) */

/** Largest current_bw_rad_s * dt (dt = 1 / pwm_hz): above it the one-period
 *  computation delay costs too much phase (gains vs PWM rate). The
 *  delay-compensated loop (mc_foc.h) overshoots a current step by about 1 %
 *  up to bw dt = 0.3, then 14 % at 0.4 and 28 % at 0.5 (mcsim current-step,
 *  the D5065 on the 24 V ODrive, sim/README.md): above 0.3 it is no longer
 *  the first-order loop its gains are derived for. */
#define MC_PARAMS_BW_DT_MAX 0.3f
/** Largest dead time as a fraction of the PWM period. */
#define MC_PARAMS_DEAD_TIME_FRAC_MAX 0.1f

/**
 * What the drive runs from a parameter set. Parameters whose value 0 means
 * "derived" (their description says from what) are replaced by their
 * derivation, the others copied; the laws' gains (mc_gains_derive) come
 * with it. The formulas are mc_gains.c's (gains) and mc_params.c's (the
 * drive's supervision, braking and stop), one place for the images and the
 * simulator. i_limit_a (the current limit every reference is held to) is
 * the gains' i_limit_a: min(i_max_a, i_sense_max_a / 1.25, 0.8 v_max / r).
 */
typedef struct {
    mc_params_t p;      /**< the set with every derived value filled in */
    mc_gains_motor_t m; /**< its motor and board values */
    mc_gains_t g;       /**< the gains (and the derived limits: i_limit_a, ...) */
} mc_params_eff_t;

/** Resolve p into *e (see mc_params_eff_t). Returns MC_GAINS_OK or the
 *  MC_GAINS_ERR_* bits that refuse the motor and board values (no safe
 *  gains); *e is written in full either way, for the caller's messages. */
uint32_t mc_params_resolve(const mc_params_t *p, mc_params_eff_t *e);

/** The drive configuration of a resolved set (see mc_params_to_drive_cfg). */
void mc_params_eff_to_drive_cfg(const mc_params_eff_t *e, mc_drive_cfg_t *cfg);

/** Index of the parameter named name (mc_param_names), or -1. */
int32_t mc_param_find_name(const char *name);

/** Row of parameter id, or NULL; *p_idx (may be NULL) its table index. */
const mc_param_info_t *mc_param_find(uint32_t id, uint32_t *p_idx);

/** Raw 32 bits of a stored parameter's value in p (info not readonly). */
uint32_t mc_param_get_raw(const mc_params_t *p, const mc_param_info_t *info);

/** Type and range check of one raw value (no access check). */
mc_param_status_t mc_param_check_value(const mc_param_info_t *info, uint32_t raw);

/** Store a raw value into p (info not readonly; the caller checked it). */
void mc_param_set_raw(mc_params_t *p, const mc_param_info_t *info, uint32_t raw);

/** Every value in its range, plus the cross checks, plus the drive's init
 *  validation of the derived mc_drive_cfg_t. Returns MC_PARAMS_ERR_* bits. */
uint32_t mc_params_validate(const mc_params_t *p);

/** The drive configuration the parameters describe, resolved
 *  (mc_params_resolve): FOC gains from the current-loop bandwidth (kp = L
 *  bw, ki = R bw), dt = 1 / pwm_hz, the current limit i_limit, supervision,
 *  controlled stop, braking (the chopper only with brake_enable), MTPA and
 *  field weakening (fw_enable). Returns MC_PARAMS_OK, MC_PARAMS_ERR_NULL,
 *  _RANGE (pwm_hz 0) or _GAINS (no safe gains); not validated. */
uint32_t mc_params_to_drive_cfg(const mc_params_t *p, mc_drive_cfg_t *cfg);

/** encoder_type 1 (Hall sensors, mc_drive_hall.h). */
#define MC_PARAMS_ENCODER_HALL 1u

/** The Hall kernel's table from the hall_* parameters (dt_s = 1 / pwm_hz).
 *  @return MC_PARAMS_OK, MC_PARAMS_ERR_NULL, or MC_PARAMS_ERR_ENCODER when
 *  mc_hall_f32_validate refuses the table (*t written either way). */
uint32_t mc_params_hall_table(const mc_params_t *p, mc_hall_f32_cfg_t *t);

#ifdef __cplusplus
}
#endif

#endif /* MC_PARAMS_H */
