/**
 * @file mc_drive.h
 * @brief The drive application: mode state machine, fast/slow loop
 *        scheduler, fault reaction, on top of the HAL and the kernels.
 *
 * The same code runs on the STM32F405 (fast step in the ADC end-of-conversion
 * interrupt) and in the simulator (hal/host calls it as the interrupt would).
 * The drive reaches hardware only through the mc_hal_t it is given.
 *
 * Scheduling
 *   mc_drive_fast_step()  once per PWM period, from the ADC interrupt:
 *                         sample -> position -> FOC -> duties.
 *                         Returns true every slow_loop_div calls: the caller
 *                         then runs mc_drive_slow_step() at lower priority
 *                         (PendSV on the MCU; directly in the simulator).
 *   mc_drive_slow_step()  supervision at pwm_hz / slow_loop_div: DC-bus
 *                         window, temperatures, hardware fault input.
 *
 * Modes
 *   IDLE     PWM off (all switches open). Entering IDLE or FAULT, and
 *            clearing faults, zero the references, so a later CURRENT
 *            starts at no torque; references set while IDLE are kept.
 *   CURRENT  dq current control to the id/iq references (torque mode).
 *   FAULT    PWM off; entered on any fault; left only by
 *            mc_drive_clear_faults() once the cause is gone.
 *
 * Fault reaction: the first fault disables the PWM outputs through the HAL
 * (safe torque off) in the same fast step (and, if the PWM driver cannot
 * confirm that, fires the gate kill), sets mode FAULT and records the sticky
 * fault bit, the first fault's bit and the tick of detection. A hardware
 * fault status that cannot be read counts as MC_DRIVE_FAULT_HW_INPUT.
 */
#ifndef MC_DRIVE_H
#define MC_DRIVE_H

#include <stdbool.h>
#include <stdint.h>

#include "foc/mc_foc.h"
#include "hal/hal.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    MC_DRIVE_MODE_IDLE = 0,
    MC_DRIVE_MODE_CURRENT = 1,
    MC_DRIVE_MODE_FAULT = 2,
} mc_drive_mode_t;

/* Sticky fault bits (mc_drive_t.faults). */
#define MC_DRIVE_FAULT_NONE        0u
#define MC_DRIVE_FAULT_ADC         (1u << 0)  /**< ADC read failed or sample invalid/stale */
#define MC_DRIVE_FAULT_MEAS_NAN    (1u << 1)  /**< NaN/inf in a measurement */
#define MC_DRIVE_FAULT_OVERCURRENT (1u << 2)  /**< |phase current| above i_trip_a */
#define MC_DRIVE_FAULT_VBUS_LOW    (1u << 3)  /**< DC bus below vbus_min_v */
#define MC_DRIVE_FAULT_VBUS_HIGH   (1u << 4)  /**< DC bus above vbus_max_v */
#define MC_DRIVE_FAULT_ENCODER     (1u << 5)  /**< encoder read failed or not valid */
#define MC_DRIVE_FAULT_CONTROL     (1u << 6)  /**< the FOC kernel reported an error */
#define MC_DRIVE_FAULT_PWM         (1u << 7)  /**< the PWM driver refused the duties */
#define MC_DRIVE_FAULT_HW_INPUT    (1u << 8)  /**< gate-driver fault / over-current comparator,
                                                   or its status unreadable */

/* Configuration errors returned by mc_drive_init (bit set). */
#define MC_DRIVE_CFG_OK            0u
#define MC_DRIVE_CFG_ERR_NULL      (1u << 0)  /**< NULL drive, config or HAL */
#define MC_DRIVE_CFG_ERR_HAL       (1u << 1)  /**< HAL lacks adc, pwm3 or encoder */
#define MC_DRIVE_CFG_ERR_FOC       (1u << 2)  /**< FOC config rejected (see foc_err) */
#define MC_DRIVE_CFG_ERR_POLES     (1u << 3)  /**< pole_pairs == 0 */
#define MC_DRIVE_CFG_ERR_DIV       (1u << 4)  /**< slow_loop_div == 0 */
#define MC_DRIVE_CFG_ERR_CURRENT   (1u << 5)  /**< i_max_a <= 0, i_trip_a < i_max_a, not finite */
#define MC_DRIVE_CFG_ERR_VBUS      (1u << 6)  /**< vbus_min_v <= 0, window empty, or not finite */
#define MC_DRIVE_CFG_ERR_SPEED_PLL (1u << 7)  /**< speed_pll_bw_rad_s <= 0, not finite, or 3 bw dt > 1 */
#define MC_DRIVE_CFG_ERR_OFFSET    (1u << 8)  /**< encoder_offset_rad not finite */

/** Drive configuration (copied at init). */
typedef struct {
    mc_foc_f32_cfg_t foc;       /**< current loop; foc.dt_s is the PWM period [s] */
    uint32_t pole_pairs;        /**< electrical turns per mechanical turn, >= 1 */
    float encoder_offset_rad;   /**< electrical angle of the d axis at encoder count 0 [rad] */
    float speed_pll_bw_rad_s;   /**< bandwidth of the encoder tracking loop that
                                     estimates speed [rad/s] (three poles at
                                     -bw), > 0, with 3 * bw * dt <= 1 */
    uint32_t slow_loop_div;     /**< slow loop every this many fast steps, >= 1 */
    float i_max_a;              /**< largest |id_ref|, |iq_ref| accepted [A] */
    float i_trip_a;             /**< instantaneous over-current trip on any phase [A], >= i_max_a */
    float vbus_min_v;           /**< under-voltage trip [V] */
    float vbus_max_v;           /**< over-voltage trip [V] */
} mc_drive_cfg_t;

/** What the last fast step saw and did (telemetry snapshot). */
typedef struct {
    float ia_a, ib_a, ic_a, vbus_v;
    float theta_m_rad;          /**< mechanical angle from the encoder, [0, 2 pi) */
    float theta_e_rad;          /**< electrical angle used by the FOC [rad] */
    float omega_m_rad_s;        /**< estimated mechanical speed (encoder PLL) [rad/s] */
    float id_ref_a, iq_ref_a;
    mc_foc_f32_out_t foc;       /**< currents, voltages and duties of the FOC step */
} mc_drive_telemetry_t;

/** The drive instance (statically allocated by the caller). */
typedef struct {
    mc_drive_cfg_t cfg;
    const mc_hal_t *hal;
    mc_foc_f32_t foc;
    mc_drive_mode_t mode;
    float id_ref_a, iq_ref_a;   /**< accepted references [A] */
    float pll_theta_m_rad;      /**< encoder PLL position estimate, [0, 2 pi) */
    float omega_m_rad_s;        /**< encoder PLL speed estimate [rad/s] */
    float alpha_m_rad_s2;       /**< encoder PLL acceleration estimate [rad/s^2] */
    float pll_k1_dt;            /**< 3 bw dt, derived at init */
    float pll_k2_dt;            /**< 3 bw^2 dt, derived at init */
    float pll_k3_dt;            /**< bw^3 dt, derived at init */
    bool have_count;
    uint32_t fast_count;        /**< fast steps since init (wraps) */
    uint32_t slow_phase;        /**< fast steps since the last slow step */
    uint32_t faults;            /**< sticky MC_DRIVE_FAULT_* */
    uint32_t first_fault;       /**< the bit that tripped first */
    uint32_t fault_tick;        /**< HAL tick when the first fault was detected */
    uint32_t foc_err;           /**< last FOC error bits (init or step) */
    mc_drive_telemetry_t tm;
} mc_drive_t;

/** Validate cfg and the HAL, initialise d (IDLE, PWM disabled). Returns
 *  MC_DRIVE_CFG_* bits; on error d is not changed. */
uint32_t mc_drive_init(mc_drive_t *d, const mc_drive_cfg_t *cfg, const mc_hal_t *hal);

/** Fast loop body (ADC interrupt). Returns true when the slow loop is due. */
bool mc_drive_fast_step(mc_drive_t *d);

/** Slow loop body (supervision). */
void mc_drive_slow_step(mc_drive_t *d);

/** Change mode. IDLE always accepted; CURRENT only from IDLE or CURRENT with
 *  no fault. Returns 0, -EINVAL (unknown mode) or -EBUSY (in fault, or the
 *  PWM could not be enabled); on error nothing changes. */
int mc_drive_set_mode(mc_drive_t *d, mc_drive_mode_t mode);

/** Set the dq current references. Returns 0 or -EINVAL (NaN, inf, or
 *  |ref| > i_max_a); on error the previous references stay. */
int mc_drive_set_current_ref(mc_drive_t *d, float id_ref_a, float iq_ref_a);

/** Clear the faults and go to IDLE, if the causes are gone (DC bus inside
 *  its window, hardware fault input released). Returns 0 or -EBUSY. */
int mc_drive_clear_faults(mc_drive_t *d);

#ifdef __cplusplus
}
#endif

#endif /* MC_DRIVE_H */
