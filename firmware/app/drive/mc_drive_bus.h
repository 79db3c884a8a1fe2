/**
 * @file mc_drive_bus.h
 * @brief DC-bus current and power limits of the drive's current loop.
 *
 * The current the bridge draws from the DC bus, estimated from what the
 * current loop already has (no bus-current sensor):
 *
 *   i_bus = p / vbus,  p = 3/2 (vd id + vq iq)
 *
 * (amplitude-invariant Park: the power into the motor's terminals). It
 * ignores the bridge's conduction and switching losses, the dead-time error
 * between the commanded and the applied voltage, the bus capacitor's ripple
 * current and the board's own supply (gate drive, logic): on a real board
 * the supply current is that much higher while motoring and lower while
 * braking. Positive: drawn from the bus; negative: pushed into it.
 *
 * Limits (mc_drive_bus_cfg_t; each 0 = off): the motoring current
 * i_bus_max_a and power p_bus_max_w, the regenerative current
 * i_bus_regen_max_a and power p_bus_regen_max_w. In force at the bus
 * voltage vbus: p in [-P_r, P_m] with
 *   P_m = min(i_bus_max_a vbus, p_bus_max_w),
 *   P_r = min(i_bus_regen_max_a vbus, p_bus_regen_max_w).
 *
 * Applied to the current references before the FOC step, in the rotor's
 * frame, from the steady-state voltage equations with the drive's motor
 * model (R, Ld, Lq, psi of the current loop's configuration) at the
 * electrical speed w:
 *   p(iq) = 3/2 (R iq^2 + w psi_eff iq + R id^2) + c,
 *   psi_eff = psi + (Ld - Lq) id,
 * where c is the estimate's correction: the estimated power (above) minus
 * the model's at the measured currents, low-passed over
 * MC_DRIVE_BUS_CORR_TAU_LOOPS current-loop time constants (it takes up
 * what the model misses in steady state: a wrong R, a load the model does
 * not know). Each limit has its own c, which follows the estimate within
 * MC_DRIVE_BUS_CORR_FAST_LOOPS where the model says less than it about
 * that limit (the motoring limit's c when the estimate draws more, the
 * regenerative one's when it returns more) and slowly the other way: the
 * model lags a fast deceleration (with one slow c the hub motor's
 * regenerative stop passed its limit; BusLimits/hub_6p5in_15pp). The q reference is moved to the nearest value with
 * p(iq) in [-P_r, P_m] (a quadratic in iq, solved exactly); a reference
 * already inside is unchanged. When even iq = 0 draws more than P_m (the d
 * current's copper loss alone), iq becomes 0.
 *
 * The steady state leaves out the current loop's own transient, the
 * winding's 3/2 Lq iq diq/dt while the current moves at the loop's
 * bandwidth: on paper 002's 40 kW motor (0.655 mH, 8 kHz) a step from rest
 * drew five times the motoring limit through the first milliseconds. So
 * the q reference is then bounded by the power of the period its voltage
 * acts in (one period late: the computation delay): the current predicted
 * from the last step's measurement and voltage, the loop's proportional
 * action on this step's error, the winding's rise over the period, a
 * quadratic in the reference held within [-P_r, P_m] the same way
 * (mc_drive_bus.c, limit_slew, with the derivation). That bound only
 * slows a step or asks less current of the same sign, never more current
 * than asked (tests/unit/app/test_app_bus.cpp,
 * DriveBusLimit.TransientOfAStepFromRestWithinTheLimit; every library
 * motor's bus-limits run, test_library_scenarios_sil). In a frame that is not the
 * rotor's (the alignment, the index search) the model is the copper loss
 * 3/2 R |i|^2 + c and both references are scaled together.
 *
 * The DC link's regenerative limit by the bus voltage (mc_drive.h,
 * "Regenerative braking") runs first: the tighter of the two wins.
 * The references then still go through the current limit i_max_a.
 */
#ifndef MC_DRIVE_BUS_H
#define MC_DRIVE_BUS_H

#include <stdbool.h>
#include <stdint.h>

#include "foc/mc_foc.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The estimate's correction filter: this many current-loop time
 *  constants Lq / kp_q (long against the loop's own transients, whose
 *  1/2 L di/dt power the steady-state model does not carry). */
#define MC_DRIVE_BUS_CORR_TAU_LOOPS 20.0f
/** The correction's time constant, in the same loops, on the side where
 *  the model says less than the estimate about the limit it guards: more
 *  drawn power for the motoring limit, more returned for the regenerative
 *  one (the model lags a fast deceleration, misses the current's own
 *  transients). */
#define MC_DRIVE_BUS_CORR_FAST_LOOPS 2.0f

/** The limits; each 0 = off, else > 0 and finite. */
typedef struct {
    float i_bus_max_a;       /**< motoring bus current drawn [A] */
    float i_bus_regen_max_a; /**< regenerative bus current pushed back, magnitude [A] */
    float p_bus_max_w;       /**< motoring bus power [W] */
    float p_bus_regen_max_w; /**< regenerative bus power, magnitude [W] */
} mc_drive_bus_cfg_t;

/** State and what the last step saw. */
typedef struct {
    float corr_w;          /**< the estimate's correction c for the motoring limit [W] */
    float corr_r_w;        /**< the same for the regenerative limit [W] */
    float corr_alpha;      /**< their filter's factor per step, slow side */
    float corr_fast_alpha; /**< the fast side's (MC_DRIVE_BUS_CORR_FAST_LOOPS) */
    float p_bus_est_w;     /**< estimated bus power of the last step [W] */
    float vbus_v;          /**< the bus of that step [V] */
    float i_mot_lim_a;     /**< motoring limit in force, P_m / vbus [A] (0: off) */
    float i_regen_lim_a;   /**< regenerative limit in force, P_r / vbus [A] (0: off) */
    bool limiting;         /**< the last step moved a reference */
    uint32_t last_count;   /**< fast count of the last step (a gap restarts c) */
    bool have_last;
} mc_drive_bus_t;

/** What the limiter needs of the step. */
typedef struct {
    float vbus_v;        /**< the bus sample [V] */
    float omega_e_rad_s; /**< the frame's electrical speed [rad/s] */
    bool rotor_frame;    /**< the frame is the rotor's */
    uint32_t fast_count; /**< the drive's fast-step counter */
    /* the last FOC step: measured currents and commanded voltages */
    float id_a, iq_a, vd_v, vq_v;
} mc_drive_bus_in_t;

/** 0 for a valid configuration, else non-zero (a value negative, NaN or
 *  infinite). */
uint32_t mc_drive_bus_check(const mc_drive_bus_cfg_t *cfg);

/** The estimate i_bus = 3/2 (vd id + vq iq) / vbus [A]; 0 for vbus <= 0
 *  or a value that is not finite. */
float mc_drive_bus_estimate_a(float vd_v, float vq_v, float id_a, float iq_a, float vbus_v);

/** True when any of the four limits is set (the drive calls
 *  mc_drive_bus_limit only then: the default configuration pays nothing
 *  in the fast interrupt). */
bool mc_drive_bus_any(const mc_drive_bus_cfg_t *cfg);

/** The state after the limits were switched off: nothing limiting, no
 *  limit in force, the correction restarts when a limit is set again. */
void mc_drive_bus_off(mc_drive_bus_t *s);

/** Fresh state for the current loop's configuration foc. */
void mc_drive_bus_init(mc_drive_bus_t *s, const mc_foc_f32_cfg_t *foc);

/** Limit (*p_id_a, *p_iq_a) so that the estimated bus power stays in
 *  [-P_r, P_m]; updates the estimate and the correction. With every limit
 *  off it only forgets the correction (mc_drive_bus_off). */
void mc_drive_bus_limit(mc_drive_bus_t *s, const mc_drive_bus_cfg_t *cfg,
                        const mc_foc_f32_cfg_t *foc, const mc_drive_bus_in_t *in, float *p_id_a,
                        float *p_iq_a);

/** The q current range [*p_lo, *p_hi] that keeps p(iq) <= p_max_w for the
 *  model p(iq) = a iq^2 + b iq + c0 (a >= 0); false when none does. */
bool mc_drive_bus_motor_range(float a, float b, float c0, float p_max_w, float *p_lo, float *p_hi);

/** The q reference moved out of the band where p(iq) < -p_regen_w, to
 *  its edge nearer to zero (a >= 0). */
float mc_drive_bus_regen_clamp(float a, float b, float c0, float p_regen_w, float iq_a);

#ifdef __cplusplus
}
#endif

#endif /* MC_DRIVE_BUS_H */
