/**
 * @file mc_ctrl_sensorless_q31.h
 * @brief q31 twin of the sensorless FOC speed control law
 *        (mc_ctrl_sensorless.h): the same structure, phases, hand-over and
 *        fallback rules, with the q31 kernels in the loop: flux observer
 *        (mc_fluxobs_q31), PLL (mc_spdpll_q31), current loop
 *        (mc_foc_q31: Clarke, Park, two PIs with decoupling, circle limit,
 *        inverse Park, SVPWM) and the speed PI (mc_pi_q31).
 *
 * Config: the f32 plug-in's config (validated exactly as mc_ctrl_sls_init
 * does, with the same error bits) plus one base value per signal:
 *   i_base_a            currents (phase, alpha-beta, dq, references);
 *   v_base_v            voltages and the DC bus;
 *   omega_base_e_rad_s  electrical speed. Mechanical speeds use the base
 *                       omega_base_e / pole_pairs, so a speed has the same
 *                       q31 number read either way (omega_hat_m and
 *                       omega_hat_e, the speed PI's error and the FOC's
 *                       decoupling speed need no conversion);
 *   flux_base_wb        observer fluxes.
 * Angles are q31 normalised turns (mc_q31.h): the I-f angle wraps exactly.
 * init rejects (MC_CTRL_SLS_ERR_SCALE) a base <= 0 or not finite, and
 * bases too small for the config: v_base_v < vbus_max_v, i_base_a <=
 * 1.25 iq_max_a or <= if_current_a (the largest current reference, see the
 * fallback), omega_base_e <= the PLL's limit 2 speed_max pole_pairs; a q31
 * kernel that refuses its derived config adds its component bit (_OBSERVER,
 * _PLL, _CURRENT, _SPEED) to _SCALE.
 *
 * The fast step is integer-only except at its boundary: the drive hands
 * the measurements as float (converted once, by a precomputed 1/base) and
 * takes float duties; on an MCU without FPU an ADC driver would hand the
 * q31 values directly. Times are counted in fast steps (the f32 plug-in
 * accumulates dt in float: a phase may end one step apart). Slews, the
 * I-f angle, the dead-time compensation, the hand-over rotation and the PI
 * presets are q31 / Q46 (mc_q46.h) with gains formed once at init. The
 * duty-side dead-time correction (cfg dead_comp_duty) is f32 only: init
 * refuses it with MC_CTRL_SLS_ERR_TIMING.
 *
 * Telemetry is kept in per unit (mc_ctrl_sls_q31_tm_t);
 * mc_ctrl_sls_q31_get_tm_f32 converts it to the f32 plug-in's telemetry
 * struct for logging (not in the fast step).
 *
 * Errors as the f32 plug-in: a non-finite measurement returns
 * MC_CTRL_SLS_ERR_MEAS (nothing changes), observer divergence _DIVERGED,
 * start-up timeout _NO_LOCK, a refused current step _FOC; the drive faults
 * on any of them. Trajectories against the f32 plug-in: tests/sil/q31.
 */
#ifndef MC_CTRL_SENSORLESS_Q31_H
#define MC_CTRL_SENSORLESS_Q31_H

#include <stdbool.h>
#include <stdint.h>

#include "foc/mc_foc_q31.h"
#include "math/mc_q46.h"
#include "mc_ctrl_sensorless.h"
#include "mc_drive.h"
#include "observer/mc_fluxobs_q31.h"
#include "observer/mc_spdpll_q31.h"
#include "pi/mc_pi.h"
#include "pi/mc_pi_q31.h"

#ifdef __cplusplus
extern "C" {
#endif

/** q31 only: a base value invalid or too small for the config (see file comment). */
#define MC_CTRL_SLS_ERR_SCALE (1u << 15)

typedef struct {
    mc_ctrl_sls_cfg_t f;      /**< as the f32 plug-in */
    float i_base_a;           /**< current base [A] */
    float v_base_v;           /**< voltage base [V], >= f.vbus_max_v */
    float omega_base_e_rad_s; /**< electrical speed base [rad/s] */
    float flux_base_wb;       /**< flux base [Wb], > flux (1.5 (flux + L i_base) advised) */
} mc_ctrl_sls_q31_cfg_t;

/** Telemetry of the last fast step, per unit of the config's bases. */
typedef struct {
    mc_ctrl_sls_phase_t phase;
    q31_t theta_hat_e;             /**< observer angle (turn) */
    q31_t omega_hat;               /**< PLL speed (speed pu) */
    q31_t theta_ctrl_e;            /**< frame of the current loop (turn) */
    q31_t omega_ref;               /**< slewed reference (speed pu) */
    q31_t omega_if;                /**< I-f frame speed (speed pu) */
    q31_t i_alpha, i_beta;         /**< currents fed to the observer (current pu) */
    q31_t v_alpha_obs, v_beta_obs; /**< voltage fed to the observer (voltage pu) */
    q31_t id_ref, iq_ref;          /**< references in the control frame (current pu) */
    q31_t id, iq;                  /**< measured currents in the control frame (current pu) */
    q31_t obs_resid;               /**< observer residual |e|/flux - 1 (q31) */
    uint32_t handovers;
    uint32_t fallbacks;
} mc_ctrl_sls_q31_tm_t;

typedef struct {
    mc_ctrl_sls_q31_cfg_t cfg;
    float gamma; /**< observer gain (as the f32 plug-in) */
    mc_fluxobs_q31_t obs;
    mc_spdpll_q31_t pll;
    mc_foc_q31_t foc;
    mc_pi_q31_t speed_pi;
    /* constants formed at init (per unit) */
    float inv_i_base, inv_v_base; /**< measurement conversion (boundary) */
    q31_t if_cur;                 /**< I-f current */
    q31_t if_half;                /**< if_cur / 2 (damping limit) */
    q31_t blend_inc;              /**< id / I-f magnitude ramp per step */
    q31_t slew_inc;               /**< reference slew per step */
    q31_t if_acc_inc;             /**< I-f speed ramp per step */
    q31_t ho;                     /**< hand-over speed */
    q31_t ho_999;                 /**< 0.999 of it */
    q31_t lo;                     /**< fallback speed ho (1 - hyst) */
    q31_t lock_tol;               /**< q31 fraction */
    q31_t speed_max;              /**< largest |reference| */
    uint32_t align_steps;         /**< align_time / dt, rounded */
    uint32_t lock_timeout_steps;  /**< if_lock_timeout / dt, rounded */
    mc_q46_gain_t g_dtheta;       /**< speed pu -> q31 turn per step: omega_base_e dt / pi */
    mc_q46_gain_t g_damp;         /**< speed error pu -> current pu: kp omega_base_m / i_base */
    mc_q46_gain_t g_kp_cur;       /**< current PI kp i_base / v_base (PI presets) */
    mc_q46_gain_t g_dead_a;       /**< (dead_time / dt) 4/3 (alpha, see the .c) */
    mc_q46_gain_t g_dead_b;       /**< (dead_time / dt) 2/sqrt(3) (beta) */
    mc_q46_gain_t g_inv_band;     /**< i_base / dead_band (0: hard sign) */
    bool dead_on;                 /**< dead_time_s > 0 */
    bool band_on;                 /**< linear dead band (else a hard sign) */
    /* state */
    mc_ctrl_sls_phase_t phase;
    q31_t omega_cmd;     /**< requested speed (pu) */
    q31_t omega_ref;     /**< slewed reference (pu) */
    q31_t theta_if;      /**< I-f frame angle (turn) */
    q31_t omega_if;      /**< I-f frame speed (pu) */
    q31_t i_if;          /**< present I-f magnitude (pu) */
    uint32_t n_phase;    /**< fast steps in the present phase */
    uint32_t n_lockwait; /**< steps at the hand-over speed waiting for lock */
    q31_t id_ref, iq_ref;
    int32_t dir;                    /**< +1 / -1: direction of the I-f ramp */
    q31_t v_hist_a[4], v_hist_b[4]; /**< applied alpha-beta voltage, newest first (pu) */
    q31_t ia_prev, ib_prev;         /**< phase currents of the previous sample (pu) */
    uint32_t speed_count;
    uint32_t obs_err; /**< observer init error, if any */
    mc_ctrl_sls_q31_tm_t tm;
    mc_drive_ctrl_t ops; /**< the drive's plug-in table, bound to this instance */
} mc_ctrl_sls_q31_t;

/** Validate cfg (the f32 plug-in's rules and bits, plus _SCALE) and
 *  initialise. Returns MC_CTRL_SLS_ERR_* bits; on error c is not written. */
uint32_t mc_ctrl_sls_q31_init(mc_ctrl_sls_q31_t *c, const mc_ctrl_sls_q31_cfg_t *cfg);

/** The plug-in table for mc_drive_attach_ctrl() (PWM3, no encoder needed). */
const mc_drive_ctrl_t *mc_ctrl_sls_q31_ops(mc_ctrl_sls_q31_t *c);

/** Set the speed reference [rad/s, mechanical]; slewed inside. Returns 0 or
 *  MC_CTRL_SLS_ERR_REF (NaN/inf, |ref| > speed_max_rad_s; previous kept). */
uint32_t mc_ctrl_sls_q31_set_speed_ref(mc_ctrl_sls_q31_t *c, float omega_m_rad_s);

/** Plug-in functions (also callable directly). */
uint32_t mc_ctrl_sls_q31_reset(void *ctx);
/** As mc_ctrl_sls_set_r_scale (mc_fluxobs_q31_set_r_scale). */
uint32_t mc_ctrl_sls_q31_set_r_scale(void *ctx, float r_scale);
uint32_t mc_ctrl_sls_q31_fast(void *ctx, const mc_drive_meas_t *m, mc_drive_out_t *out);

/** The telemetry in engineering units (the f32 plug-in's struct). */
void mc_ctrl_sls_q31_get_tm_f32(const mc_ctrl_sls_q31_t *c, mc_ctrl_sls_tm_t *p_tm);

/** The observer's flux estimate [Wb] (telemetry). */
void mc_ctrl_sls_q31_get_flux_wb(const mc_ctrl_sls_q31_t *c, float *p_alpha_wb, float *p_beta_wb);

#ifdef __cplusplus
}
#endif

#endif /* MC_CTRL_SENSORLESS_Q31_H */
