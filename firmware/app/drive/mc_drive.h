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
 *   CURRENT  dq current control to the id/iq references (torque mode);
 *            needs pwm3 and an encoder.
 *   CTRL     a control law plugged in with mc_drive_attach_ctrl() (speed
 *            loops, PI2D, sensorless FOC, the stepper's CSMC): each fast step
 *            the drive hands it the measurements (mc_drive_meas_t) and
 *            writes the duties it returns (mc_drive_out_t) to the bridge it
 *            names; the drive keeps sampling, supervision and the fault
 *            reaction. A law error (non-zero return) is
 *            MC_DRIVE_FAULT_CONTROL.
 *   FAULT    PWM off; entered on any fault; left only by
 *            mc_drive_clear_faults() once the cause is gone.
 *
 *   STOPPING controlled stop (mc_drive_stop(), a command timeout, a warning):
 *            decelerate to standstill at stop_decel_rad_s2, then open the
 *            bridge and go to IDLE. From CURRENT mode the drive ramps a
 *            speed reference from the measured speed to 0 at the
 *            deceleration and follows it with a P speed loop of its own
 *            (iq = stop_kp (omega_ramp - omega) - sign(omega_ramp) stop_iq_ff,
 *            |iq| <= i_max_a, id = 0; with stop_iq_ff = J decel / kt the
 *            rotor follows the ramp closely, without it it lags by about
 *            J decel / (kt stop_kp));
 *            from CTRL mode the law's stop op decelerates (a law without
 *            one: the bridge opens at once). Standstill: the ramp at 0 and
 *            |omega| <= stop_rest_rad_s (checked in the slow step), or,
 *            with an encoder, the encoder speed crossing zero against the
 *            direction the stop began in (checked in every fast step: a
 *            stop never drives the rotor backwards); the bridge opens anyway after
 *            2 |omega_0| / decel + 0.1 s. stop_decel_rad_s2 = 0: no
 *            controlled stop (the bridge opens at once, as IDLE).
 *            Critical faults (every MC_DRIVE_FAULT_*: over-current, gate
 *            fault, ...) still open the bridge at once, in STOPPING too.
 *
 * Fault reaction: the first fault disables the PWM outputs through the HAL
 * (safe torque off) in the same fast step (and, if the PWM driver cannot
 * confirm that, fires the gate kill), sets mode FAULT and records the sticky
 * fault bit, the first fault's bit and the tick of detection. A hardware
 * fault status that cannot be read counts as MC_DRIVE_FAULT_HW_INPUT.
 *
 * Active short circuit (cfg.asc_enable, off by default): above the speed at
 * which the motor's line-to-line back-EMF peak sqrt(3) p flux |omega_m|
 * exceeds the measured bus voltage, opening the bridge lets the rotor
 * pump current through the free-wheeling diodes into the bus (a supply
 * that cannot sink it, no brake resistor: the bus rises past its trip,
 * braking torque uncontrolled). With asc_enable, a fault of
 * MC_DRIVE_ASC_FAULTS at such a speed instead turns the three low-side
 * switches on (duties 0 with the bridge enabled: hal/pwm3.h): the phases
 * are shorted, no current reaches the bus, the windings carry the
 * short-circuit current (towards flux / Ld at high speed) and the rotor
 * feels a braking torque (largest near omega_e = R / L, small at high
 * speed). The drive is in FAULT with asc_active set; it opens the bridge
 * when the back-EMF falls below MC_DRIVE_ASC_EXIT_FRAC of the bus (the
 * encoder's speed; without a valid encoder the short stays until
 * mc_drive_clear_faults), or at once when a fault outside
 * MC_DRIVE_ASC_FAULTS joins (over-current, gate driver, PWM refusal, a
 * current reading the drive cannot trust: the bridge or its supervision
 * cannot be relied on). mc_drive_set_mode(IDLE) in FAULT keeps the short;
 * mc_drive_clear_faults ends it. init refuses asc_enable unless the steady
 * short-circuit current flux / Ld is below i_trip_a (MC_DRIVE_CFG_ERR_ASC);
 * the transient from the operating point overshoots flux / Ld by up to
 * |v_dq| / (omega_e Ld), and if it crosses i_trip_a the over-current rule
 * opens the bridge after all (app README: size the trip for ~2 flux / Ld).
 */
#ifndef MC_DRIVE_H
#define MC_DRIVE_H

#include <stdbool.h>
#include <stdint.h>

#include "foc/mc_foc.h"
#include "fw/mc_fw.h"
#include "mc_drive_bus.h"
#include "mc_drive_cog.h"
#include "mc_drive_hallobs.h"
#include "observer/mc_enctrack.h"
#include "hal/hal.h"
#include "mc_drive_thermal.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    MC_DRIVE_MODE_IDLE = 0,
    MC_DRIVE_MODE_CURRENT = 1,
    MC_DRIVE_MODE_FAULT = 2,
    MC_DRIVE_MODE_CTRL = 3,
    MC_DRIVE_MODE_STOPPING = 4,
} mc_drive_mode_t;

/* Warnings (mc_drive_t.warnings): non-critical conditions that bring the
 * drive to a controlled stop (MC_DRIVE_MODE_STOPPING), then IDLE; CURRENT
 * and CTRL are refused while one is set (cleared by mc_drive_clear_faults
 * once the condition is gone). */
#define MC_DRIVE_WARN_NONE 0u

/** A count wider than this electrical angle [rad] (2.9 deg: i_d up to 2.5 %
 *  of i_q from the count's half width alone) is interpolated by the
 *  tracking loop for commutation (mc_drive_t.enc_interp); finer encoders
 *  commutate on the count, which has no estimator lag. Every encoder of
 *  8192 counts on up to 64 pole pairs is fine (at most 0.049 rad); a
 *  90-count Hall-class sensor on 15 pole pairs is 1.05 rad. */
#define MC_DRIVE_ENC_INTERP_E_RAD 0.05f
/** Consecutive slow steps a fitted temperature sensor may be without a
 *  reading before OVERTEMP trips: the STM32F405 board converts one
 *  thermistor per slow step, so both have one after 2 steps from boot; 8
 *  (8 ms at the 1 kHz slow rate) rides through that start and a single
 *  disturbed conversion, far inside any thermal time constant. */
#define MC_DRIVE_TEMP_INVALID_STEPS 8u

#define MC_DRIVE_WARN_TEMP     (1u << 0) /**< power stage or motor above temp_warn_c */
#define MC_DRIVE_WARN_VBUS_SAG (1u << 1) /**< DC bus below vbus_sag_v */
#define MC_DRIVE_WARN_CAN_BUS \
    (1u << 2) /**< the CAN controller is error-passive or bus-off (raised by
                   the application, mc_drive_warning_cause) */

/* Why the last controlled stop began (mc_drive_t.stop_cause). */
#define MC_DRIVE_STOP_NONE    0u
#define MC_DRIVE_STOP_CMD     1u /**< mc_drive_stop(): a stop command or a command timeout */
#define MC_DRIVE_STOP_WARNING 2u /**< a warning (MC_DRIVE_WARN_*) */

/* Sticky fault bits (mc_drive_t.faults). */
#define MC_DRIVE_FAULT_NONE        0u
#define MC_DRIVE_FAULT_ADC         (1u << 0) /**< ADC read failed or sample invalid/stale */
#define MC_DRIVE_FAULT_MEAS_NAN    (1u << 1) /**< NaN/inf in a measurement */
#define MC_DRIVE_FAULT_OVERCURRENT (1u << 2) /**< |phase current| above i_trip_a */
#define MC_DRIVE_FAULT_VBUS_LOW    (1u << 3) /**< DC bus below vbus_min_v */
#define MC_DRIVE_FAULT_VBUS_HIGH   (1u << 4) /**< DC bus above vbus_max_v */
#define MC_DRIVE_FAULT_ENCODER     (1u << 5) /**< encoder read failed or not valid */
#define MC_DRIVE_FAULT_CONTROL \
    (1u << 6)                        /**< the FOC or field-weakening kernel, or
                                                   the plugged control law, reported an
                                                   error */
#define MC_DRIVE_FAULT_PWM (1u << 7) /**< the PWM driver refused the duties */
#define MC_DRIVE_FAULT_HW_INPUT \
    (1u << 8)                              /**< gate-driver fault / over-current comparator,
                                                   or its status unreadable */
#define MC_DRIVE_FAULT_OVERSPEED (1u << 9) /**< |omega_m| above omega_max_rad_s */
#define MC_DRIVE_FAULT_OVERTEMP \
    (1u << 10) /**< power stage or motor above its limit,
                                                   or the reading invalid/unreadable */
#define MC_DRIVE_FAULT_OVERRUN \
    (1u << 11) /**< fast step finished later than one period
                                                   after its ADC trigger (control deadline) */
#define MC_DRIVE_FAULT_STALL \
    (1u << 12) /**< CURRENT mode: |iq| >= stall fraction of
                                                   i_max while |omega_m| < stall speed, for
                                                   longer than stall_time_s */
#define MC_DRIVE_FAULT_EXTERNAL \
    (1u << 13) /**< raised by the application through
                                                   mc_drive_raise_fault (no firmware module
                                                   raises it; a CAN command timeout is a
                                                   controlled stop) */
#define MC_DRIVE_FAULT_UNBALANCED \
    (1u << 14) /**< three measured phase currents do not sum
                                                   to zero: a stuck, offset or failed
                                                   current sensor (needs three shunts) */
#define MC_DRIVE_FAULT_OPEN_PHASE \
    (1u << 15) /**< CURRENT mode: a phase carries no current
                                                   while its commanded current is large
                                                   (broken conductor or connector, a leg
                                                   that never switches); see open_phase_* */

/* Configuration errors returned by mc_drive_init (bit set). */
#define MC_DRIVE_CFG_OK          0u
#define MC_DRIVE_CFG_ERR_NULL    (1u << 0) /**< NULL drive, config or HAL */
#define MC_DRIVE_CFG_ERR_HAL     (1u << 1) /**< HAL lacks adc, or has neither pwm3 nor pwm2 */
#define MC_DRIVE_CFG_ERR_FOC     (1u << 2) /**< FOC config rejected (see foc_err) */
#define MC_DRIVE_CFG_ERR_POLES   (1u << 3) /**< pole_pairs == 0 */
#define MC_DRIVE_CFG_ERR_DIV     (1u << 4) /**< slow_loop_div == 0 */
#define MC_DRIVE_CFG_ERR_CURRENT (1u << 5) /**< i_max_a <= 0, i_trip_a < i_max_a, not finite */
#define MC_DRIVE_CFG_ERR_VBUS    (1u << 6) /**< vbus_min_v <= 0, window empty, or not finite */
#define MC_DRIVE_CFG_ERR_SPEED_PLL \
    (1u << 7) /**< speed_pll_bw_rad_s <= 0, not finite, or 3 bw dt > 1 */
#define MC_DRIVE_CFG_ERR_OFFSET \
    (1u << 8) /**< encoder_offset_rad or an i_offset_a not finite, or
                   encoder_latency_s outside [0, 1 ms] */
#define MC_DRIVE_CFG_ERR_SUPERVISION \
    (1u << 9) /**< omega_max, temp_max, a stall
                                                    parameter or i_unbalance_max
                                                    negative or not finite, or
                                                    stall_current_frac > 1 */
#define MC_DRIVE_CFG_ERR_OPEN_PHASE \
    (1u << 10) /**< open_phase_i_min_a or open_phase_time_s
                                                    negative or not finite, only one of
                                                    them 0, i_min above i_max_a, or the
                                                    time shorter than one period or
                                                    longer than 2^24 periods */
#define MC_DRIVE_CFG_ERR_THERMAL \
    (1u << 19) /**< cfg.thermal refused by mc_drive_thermal_init (see there) */
#define MC_DRIVE_CFG_ERR_FW \
    (1u << 13) /**< fw_enable with a cfg.fw mc_fw_f32_init
                                                   refuses, or fw.dt_s != foc.dt_s */
#define MC_DRIVE_CFG_ERR_ASC \
    (1u << 14) /**< asc_enable without a 3-phase motor model: flux_wb or ld_h
                                                   not > 0, or flux / Ld not below i_trip_a */
#define MC_DRIVE_CFG_ERR_ANGLE_REF (1u << 15) /**< angle_ref not one of MC_DRIVE_ANGLE_REF_* */
#define MC_DRIVE_CFG_ERR_DEAD_TIME \
    (1u << 16) /**< dead_time_comp with dead_time_s outside [0, dt/2) or
                    dead_band_a negative, or either not finite */
#define MC_DRIVE_CFG_ERR_BUS_POWER \
    (1u << 12) /**< regen limit or brake chopper thresholds:
                                                   not finite, only one of a pair 0, or not
                                                   vbus_min_v < start < end <= vbus_max_v;
                                                   or a DC-bus limit (cfg.bus) negative
                                                   or not finite */

/* Faults that may engage the active short circuit (cfg.asc_enable): those
 * that leave the bridge and the current measurement trustworthy. */
#define MC_DRIVE_ASC_FAULTS                                                        \
    (MC_DRIVE_FAULT_VBUS_LOW | MC_DRIVE_FAULT_VBUS_HIGH | MC_DRIVE_FAULT_ENCODER | \
     MC_DRIVE_FAULT_CONTROL | MC_DRIVE_FAULT_OVERSPEED | MC_DRIVE_FAULT_OVERTEMP | \
     MC_DRIVE_FAULT_OVERRUN | MC_DRIVE_FAULT_STALL | MC_DRIVE_FAULT_EXTERNAL |     \
     MC_DRIVE_FAULT_OPEN_PHASE)
/* The short ends when the back-EMF peak falls below this fraction of the bus. */
#define MC_DRIVE_ASC_EXIT_FRAC 0.9f

/*
 * Open-phase check (CURRENT mode, fast step; MC_DRIVE_FAULT_OPEN_PHASE).
 * With one phase conductor broken, that phase's current is zero whatever
 * the drive commands; the other two carry one series current. The drive
 * turns its dq references into phase references at the angle of the step
 * and, for each phase x whose reference |i_x_ref| is at least
 * open_phase_i_min_a, counts up a step without conduction
 * (|i_x| < MC_DRIVE_OPEN_PHASE_CONDUCTION_RATIO |i_x_ref|) and counts down
 * (to 0) a step with conduction. Steps with |i_x_ref| below i_min carry no
 * evidence (a healthy phase is near zero there too: the fault cannot be seen
 * while the commanded current in the broken phase is small; on a turning
 * machine each phase gets its turn every half electrical period). Neither do
 * steps at the voltage limit (|v_dq| at MC_DRIVE_OPEN_PHASE_VSAT_FRAC of the
 * controller's limit or beyond, or the modulator cutting the vector): at
 * high speed and in field weakening a healthy current may legitimately fall
 * far short of its reference. A phase whose count reaches
 * open_phase_time_s / dt (rounded) trips; its bit is set in
 * mc_drive_t.open_phase_mask (bit 0 = a).
 *
 * Choosing the values: i_min well above the current noise divided by the
 * ratio (a broken phase reads noise), and at most i_max_a. The time must
 * exceed what the loop needs to bring a phase current across +-ratio of a
 * reversing reference (about 0.5/bw plus the computation delay for the
 * first-order loop of mc_foc_f32_gains_from_bandwidth, 0.3/bw for a step
 * from zero) and stay below the time the PIs need to wind up to the voltage
 * limit on the error a broken phase leaves (v_max / (ki i_min)): after that
 * the steps are at the limit and count nothing. Latency with the broken
 * phase's reference above i_min throughout: the time, plus one period; on a
 * turning machine, at most the time plus the part of a half electrical
 * period where that reference is below i_min.
 * The check runs in CURRENT mode only (a plugged law owns its references).
 */
#define MC_DRIVE_OPEN_PHASE_CONDUCTION_RATIO 0.25f
#define MC_DRIVE_OPEN_PHASE_VSAT_FRAC        0.99f

/*
 * Regenerative braking (CURRENT mode, fast step). While the q-current
 * reference brakes the rotor (iq_ref and the measured speed of opposite
 * signs: the machine generates and the bridge pushes current into the bus),
 * the drive scales it by
 *   k = clamp((vbus_regen_end_v - v) / (vbus_regen_end_v - vbus_regen_start_v), 0, 1)
 * where v is the bus the current loop will have brought when it follows
 * a cut: the reading plus its rise over the lead time,
 *   v = vbus + t_lead dvbus/dt,  t_lead = Lq / kp_q + 1.5 dt
 * (the current loop's closed-loop time constant and the computation and
 * PWM delay), the rate from a first-order lag of time constant t_lead of
 * every valid bus sample (v = 2 vbus - lag; equal to vbus on a steady
 * bus). A small bus capacitor rises through the band faster than the q
 * current can follow a cut taken on the bus alone (firmware/app/README.md,
 * "Regenerative limit"), so the bus settles where the braking power equals what the bus can take
 * (source sinking, brake resistor, losses) instead of rising to the
 * over-voltage trip. A supply that cannot sink current and no brake
 * resistor leave only the motor's and the bridge's losses: the rotor then
 * stops more slowly than the reference asks (the outer loop sees the
 * scaled reference in tm.iq_ref_a and tm.regen_scale and should track it).
 * With regen_id_a > 0 the drive then burns the energy in the windings: it
 * adds a d current -(1 - k) regen_id_a (bounded so |i_dq| <= i_max_a, and
 * only when the d reference itself is not more negative), so braking goes
 * on at the rate the copper losses 3/2 R id^2 allow (a low-R motor on a
 * supply that cannot sink and no resistor would otherwise coast). A
 * negative id only weakens the field (no demagnetisation risk while
 * regen_id_a < flux/Ld).
 * Motoring currents are never scaled. Plugged laws (CTRL) own their
 * references and are not limited here.
 *
 * Brake chopper (every fast step, any mode, when the board has
 * mc_hal_t.brake and the thresholds are set): duty
 *   clamp((vbus - brake_on_v) / (brake_full_v - brake_on_v), 0, 1),
 * a proportional bus-voltage regulator; put brake_full_v below
 * vbus_regen_start_v so the resistor takes the braking energy before the
 * current is cut.
 */

/*
 * The angle reference after a power-up (cfg.angle_ref): what makes
 * encoder_offset_rad true for the count the encoder reports.
 *   STORED  the stored offset holds from power-up: an absolute encoder
 *           (AS5047P, MA732), Hall sensors, or a bench that starts every
 *           run from the angle at which the offset was measured;
 *   INDEX   the offset is relative to the index: true from the first
 *           encoder sample with MC_HAL_ENCODER_FLAG_INDEX (the HAL then
 *           reports the count relative to the index: the drive re-bases its
 *           speed tracking in that sample, and does not take the count's
 *           jump for an encoder fault); the index search
 *           (ctrl/mc_ctrl_align.h) finds it;
 *   ALIGN   an incremental encoder without index: the stored offset is
 *           stale after every power-up; true once an alignment has measured
 *           it (mc_drive_set_encoder_offset); lost at every mc_drive_init.
 * Until the angle is known (mc_drive_angle_state), CURRENT mode and every
 * law that needs the encoder are refused with -EACCES, except a law that
 * finds the angle itself (mc_drive_ctrl_t.finds_angle: the alignment and
 * the index search). Never a stale offset.
 */
#define MC_DRIVE_ANGLE_REF_STORED 0u
#define MC_DRIVE_ANGLE_REF_INDEX  1u
#define MC_DRIVE_ANGLE_REF_ALIGN  2u

/** mc_drive_angle_state(): the angle is known, or what it waits for. */
#define MC_DRIVE_ANGLE_KNOWN      0u
#define MC_DRIVE_ANGLE_NEED_INDEX 1u /**< INDEX: no index seen since power-up */
#define MC_DRIVE_ANGLE_NEED_ALIGN 2u /**< ALIGN: no alignment since power-up */

/** Drive configuration (copied at init). */
typedef struct {
    mc_foc_f32_cfg_t foc;     /**< current loop; foc.dt_s is the PWM period [s] */
    uint32_t pole_pairs;      /**< electrical turns per mechanical turn, >= 1 */
    float encoder_offset_rad; /**< electrical angle of the d axis at encoder count 0 [rad] */
    uint32_t angle_ref;       /**< MC_DRIVE_ANGLE_REF_* (0: STORED) */
    float encoder_latency_s;  /**< the encoder's latency [s], [0, 1 ms]: a sample is the
                                     rotor's angle this long before the period's sample
                                     (an absolute SPI encoder's frame); the electrical
                                     angle is advanced by omega_e times it (0: none) */
    bool encoder_reversed;    /**< the encoder counts down when the rotor turns positive
                                     (commissioning's encoder_direction = -1): the drive
                                     uses cpr - count */
    bool enc_steps_checked;   /**< the position source checks its own steps (Hall
                                     sensors, mc_drive_hall.h: the kernel's SEQUENCE;
                                     its angle moves up to a sector at an edge): no
                                     encoder-jump check */
    float i_offset_a[3];      /**< current-sensor offsets subtracted from each phase
                                     reading (a, b, c) before any use [A] (commissioning
                                     measures them; 0 on a board whose HAL removes them) */
    float speed_pll_bw_rad_s; /**< bandwidth of the encoder tracking loop that
                                     estimates speed [rad/s] (three poles at
                                     -bw), > 0, with 3 * bw * dt <= 1 */
    uint32_t slow_loop_div;   /**< slow loop every this many fast steps, >= 1 */
    float i_max_a;            /**< largest |id_ref|, |iq_ref| accepted [A] */
    float i_trip_a;           /**< instantaneous over-current trip on any phase [A], >= i_max_a */
    float vbus_min_v;         /**< under-voltage trip [V] */
    float vbus_max_v;         /**< over-voltage trip [V] */
    /* Optional supervision: a value of 0 disables that check (documented as
     * a choice of the integrator, never a default to forget: the parameter
     * table sets each from its parameter, a default or a derivation each
     * (mc_params_to_drive_cfg: the one builder of the images and the
     * simulator). */
    float omega_max_rad_s;    /**< over-speed trip, mechanical [rad/s]; also bounds
                                     the plausible encoder step (2x margin) */
    float temp_max_c;         /**< over-temperature trip for power stage and motor [deg C]:
                                     a reading above it trips at once; a fitted
                                     sensor without a reading (open, short, ADC
                                     stuck) trips after MC_DRIVE_TEMP_INVALID_STEPS
                                     slow steps; a sensor the board does not have
                                     (HAL absent_mask) is not required, but a
                                     board with none trips (limit unenforceable) */
    float stall_current_frac; /**< stall: |iq| >= this * i_max_a ... (0, 1] */
    float stall_speed_rad_s;  /**< ... while |omega_m| < this ... */
    float stall_time_s;       /**< ... for longer than this [s] */
    float i_unbalance_max_a;  /**< largest |ia + ib + ic| with three shunts [A] */
    float open_phase_i_min_a; /**< open-phase check: phase reference magnitude above
                                     which the phase must conduct [A], <= i_max_a ... */
    float open_phase_time_s;  /**< ... net time without conduction that trips [s],
                                     >= one period; both 0: check off */
    /* Controlled stop (MODE_STOPPING); 0 disables each. */
    float stop_decel_rad_s2; /**< deceleration of a controlled stop [rad/s^2]
                                     (0: the bridge opens at once) */
    float stop_rest_rad_s;   /**< |omega_m| at or below which the rotor is at rest [rad/s] */
    float stop_kp_a_s_rad;   /**< P gain of the CURRENT-mode stop's speed loop [A/(rad/s)] */
    float stop_iq_ff_a;      /**< q current that decelerates the load at stop_decel
                                     (J decel / kt) [A]: feed-forward of that loop while
                                     the ramp runs, against the direction of motion */
    float temp_warn_c;       /**< over-temperature warning: controlled stop [deg C]
                                     (below temp_max_c, the trip) */
    float vbus_sag_v;        /**< bus-sag warning: controlled stop below this [V]
                                     (above vbus_min_v, the trip) */
    /* Bus-voltage handling while braking (see "Regenerative braking" above
     * mc_drive_cfg_t); each pair both 0: off. */
    float vbus_regen_start_v; /**< regen current limit: full regenerative q current
                                     below this bus voltage [V] ... */
    float vbus_regen_end_v;   /**< ... none at and above this one [V], <= vbus_max_v */
    float regen_id_a;         /**< d current injected while the regen limit cuts
                                     the q current: (1 - k) * this, >= 0, <= i_max_a;
                                     0: none */
    float brake_on_v;         /**< brake chopper: duty 0 at and below this [V] ... */
    float brake_full_v;       /**< ... duty 1 at and above this one [V], <= vbus_max_v */
    /* Speed reference shaping (the speed laws, mc_drive_ctrl_t.uses_speed_ref):
     * the target of mc_drive_set_speed_ref() slewed at this rate [rad/s^2];
     * 0: no slew (a step). */
    float speed_accel_rad_s2;
    /* Dead-time compensation of the current loop (CURRENT mode and the laws
     * that give current references): each leg's duty plus
     * sat(i_x / dead_band_a) dead_time_s / dt, from the step's sample. */
    bool dead_time_comp;
    float dead_time_s; /**< the bridge's dead time [s], [0, dt/2) */
    float dead_band_a; /**< current over which the error reverses (linear inside) [A], >= 0 */
    /* MTPA and field weakening (CURRENT mode, and the laws that give current
     * references in the rotor's frame; kernels/fw/mc_fw.h). With
     * fw_enable, iq_ref_a is the signed current command: the kernel turns it
     * into (id, iq) on the MTPA curve, weakened by the voltage loop, inside
     * the circle fw.i_max_a; the d reference is then min(id_ref_a, kernel's).
     * fw.dt_s must be foc.dt_s. Off: references as set. */
    bool fw_enable;
    mc_fw_f32_cfg_t fw;
    /** Anticogging (runtime): a law with cogging_ff adds the attached map's
     *  current (mc_drive_attach_cog) to its q reference; no effect without
     *  a map. */
    bool anticogging;
    /** Active short circuit on a fault above the speed where the back-EMF
     *  exceeds the bus (see "Active short circuit" above); needs foc.flux_wb,
     *  foc.ld_h > 0 and foc.flux_wb / foc.ld_h < i_trip_a. */
    bool asc_enable;
    /** DC-bus current and power limits (mc_drive_bus.h); 0 = off each. */
    mc_drive_bus_cfg_t bus;
    /** Thermal derating and the winding estimate (mc_drive_thermal.h): the
     *  current limit in force is i_max_a times its factor. */
    mc_drive_thermal_cfg_t thermal;
} mc_drive_cfg_t;

/** Bridges a control law can drive (mc_drive_ctrl_t.outputs). */
#define MC_DRIVE_OUT_PWM3 1u /**< 3-phase inverter: duty_a..c in [0, 1] */
#define MC_DRIVE_OUT_PWM2 2u /**< dual H-bridge (stepper): duty2_a, duty2_b in [-1, 1] */
/** Current references on the 3-phase inverter: the drive's current loop
 *  runs them (MTPA / field weakening and the regenerative limit in the
 *  rotor's frame, the current limit, the FOC step, dead-time compensation),
 *  the same loop as CURRENT mode: see "Laws that give current references". */
#define MC_DRIVE_OUT_CURRENT 4u

/** Measurements handed to a plugged control law, once per fast step. */
typedef struct {
    float ia_a, ib_a;       /**< phase (or winding) currents [A] */
    float ic_a;             /**< third phase [A]: measured, or -(ia + ib) */
    float vbus_v;           /**< DC bus [V] */
    bool have_encoder;      /**< the fields below are valid */
    float theta_m_rad;      /**< encoder mechanical angle, [0, 2 pi) */
    float theta_e_rad;      /**< pole_pairs * theta_m + offset, [0, 2 pi); with the Hall +
                                 observer hand-over attached, its blend */
    float omega_m_rad_s;    /**< encoder tracking-loop speed [rad/s] */
    uint32_t enc_count;     /**< count in the rotor's positive direction (encoder_reversed
                              applied, as theta_m_rad), 0 .. enc_cpr - 1: what a law
                              that counts turns counts */
    uint32_t enc_raw_count; /**< the encoder's own count, 0 .. enc_cpr - 1 (commissioning
                                 identifies the direction from it) */
    uint32_t enc_cpr;       /**< counts per mechanical revolution */
    float dt_s;             /**< fast-loop period [s] */
    uint32_t fast_count;    /**< fast steps since init (wraps) */
    /* the drive's shaped speed reference (a law with uses_speed_ref) */
    bool have_speed_ref;    /**< the two below are valid */
    float omega_ref_rad_s;  /**< speed reference of this step [rad/s] */
    float alpha_ref_rad_s2; /**< its acceleration over the step [rad/s^2] */
    /* the current loop (MC_DRIVE_OUT_CURRENT laws) */
    float i_max_a;        /**< the current limit in force [A]: saturate there */
    float iq_applied_a;   /**< q reference the loop applied last step (after the
                                  limit, field weakening, the regen limit) [A] */
    float regen_scale;    /**< the regenerative limit's factor of last step, [0, 1] */
    float v_alpha_prev_v; /**< alpha-beta voltage the loop commanded last step [V] */
    float v_beta_prev_v;
} mc_drive_meas_t;

/** What a control law asks the bridge to do this period. */
typedef struct {
    float duty_a, duty_b, duty_c; /**< MC_DRIVE_OUT_PWM3 */
    float duty2_a, duty2_b;       /**< MC_DRIVE_OUT_PWM2 */
    /* MC_DRIVE_OUT_CURRENT */
    float id_ref_a, iq_ref_a; /**< current references in the frame theta_e_rad [A] */
    float theta_e_rad;        /**< the frame's electrical angle [rad] */
    float omega_e_rad_s;      /**< the frame's electrical speed (decoupling) [rad/s] */
    bool rotor_frame;         /**< the frame is the rotor's (field weakening, regen
                                   limit and open-phase check apply) */
    bool reframe;             /**< the frame jumped: the current PIs are preset so
                                   that the voltage vector stays where it was */
} mc_drive_out_t;

/**
 * A control law plugged into the drive. The drive calls reset() when CTRL
 * mode is entered, fast() every fast step (from the ADC interrupt: bounded
 * time, no blocking) and slow() every slow step; a non-zero return from any
 * of them is a control fault (the drive goes to FAULT, outputs off). The
 * table and ctx must outlive the drive's use of them.
 */
typedef struct {
    uint32_t outputs;             /**< MC_DRIVE_OUT_PWM3, _PWM2 or _CURRENT */
    bool needs_encoder;           /**< refuse to attach without an encoder */
    uint32_t (*reset)(void *ctx); /**< may be NULL */
    uint32_t (*fast)(void *ctx, const mc_drive_meas_t *m, mc_drive_out_t *out);
    uint32_t (*slow)(void *ctx); /**< may be NULL */
    void *ctx;
    /** Controlled stop (MC_DRIVE_MODE_STOPPING): decelerate to standstill at
     *  decel_rad_s2 [rad/s^2] and hold; fast() keeps running. NULL: the law
     *  cannot stop itself and the drive opens the bridge at once. */
    uint32_t (*stop)(void *ctx, float decel_rad_s2);
    /** A speed law: the drive shapes its reference (mc_drive_set_speed_ref,
     *  mc_drive_meas_t.omega_ref_rad_s) and stops it by ramping that to 0
     *  (stop is then not used). */
    bool uses_speed_ref;
    /** Measures the angle reference itself (alignment, index search,
     *  commissioning): runs before the angle is known (MC_DRIVE_ANGLE_REF_*).
     *  After the fields every law sets, so that a table written in order
     *  leaves it false (and set_r_scale NULL). */
    bool finds_angle;
    /** The phase resistance in force is the configured one times r_scale
     *  (a warm winding, mc_drive_thermal_r_scale): the drive calls it from
     *  the slow step while the law runs, with the winding model on and
     *  winding_r_follow. May be NULL (the law's R stays). A non-zero return
     *  is a control fault. */
    uint32_t (*set_r_scale)(void *ctx, float r_scale);
    /** A speed or position law giving current references: with a map
     *  attached (mc_drive_attach_cog) and the encoder read, the drive adds
     *  the anticogging feed-forward at the mechanical angle to its q
     *  reference, before the current limit. false for CURRENT's own loop,
     *  commissioning and the angle finders (a table that does not name it). */
    bool cogging_ff;
} mc_drive_ctrl_t;

/** What the last fast step saw and did (telemetry snapshot). */
typedef struct {
    float ia_a, ib_a, ic_a, vbus_v;
    float theta_m_rad;   /**< mechanical angle from the encoder, [0, 2 pi) */
    float theta_e_rad;   /**< electrical angle used by the FOC [rad] */
    float omega_m_rad_s; /**< estimated mechanical speed (encoder PLL) [rad/s] */
    float id_ref_a, iq_ref_a;
    mc_foc_f32_out_t foc;    /**< currents, voltages and duties of the FOC step */
    mc_drive_out_t ctrl_out; /**< last output of the plugged control law */
    uint32_t ctrl_err;       /**< last non-zero error code of the control law */
    float regen_scale;       /**< factor applied to a braking iq reference, [0, 1] */
    float brake_duty;        /**< brake chopper duty written, [0, 1] */
    mc_fw_f32_out_t fw;      /**< last MTPA/FW step (fw_enable) */
    float cog_ff_a;          /**< anticogging feed-forward added to the q reference
                                  before the limit [A] (0: none this step) */
} mc_drive_telemetry_t;

/** The drive instance (statically allocated by the caller). */
typedef struct {
    mc_drive_cfg_t cfg;
    const mc_hal_t *hal;
    mc_foc_f32_t foc;
    mc_fw_f32_t fw; /**< MTPA / field weakening (cfg.fw_enable) */
    mc_drive_mode_t mode;
    float id_ref_a, iq_ref_a;     /**< accepted references [A] */
    mc_enctrack_f32_t enc_trk;    /**< encoder tracking loop: mechanical angle, speed, accel. */
    uint32_t fast_count;          /**< fast steps since init (wraps) */
    uint32_t slow_phase;          /**< fast steps since the last slow step */
    uint32_t faults;              /**< sticky MC_DRIVE_FAULT_* */
    uint32_t first_fault;         /**< the bit that tripped first */
    uint32_t fault_tick;          /**< HAL tick when the first fault was detected */
    uint32_t foc_err;             /**< last FOC error bits (init or step) */
    uint32_t deadline_ticks;      /**< one PWM period in HAL ticks (0: no tick source) */
    uint32_t last_count_raw;      /**< encoder count of the previous step */
    uint32_t enc_count;           /**< the last count, encoder_reversed applied */
    uint32_t enc_cpr_cached;      /**< counts per rev the two below are for (0: none yet) */
    float enc_rad_per_count;      /**< 2 pi / cpr (computed once per cpr, not per step) */
    float enc_max_step_counts;    /**< encoder-jump threshold per step [counts] */
    bool enc_interp;              /**< commutate on the tracking loop's angle: one count
                                       is more than MC_DRIVE_ENC_INTERP_E_RAD electrical */
    float stall_time_acc_s;       /**< time spent in the stall condition [s] */
    uint32_t temp_invalid_steps;  /**< consecutive slow steps without a reading of
                                       every fitted temperature sensor */
    uint32_t open_phase_trip;     /**< steps without conduction that trip (0: check off) */
    uint32_t open_phase_count[3]; /**< per phase: net steps without conduction */
    uint32_t open_phase_mask;     /**< phases found open (bit 0 = a), with the fault */
    const mc_drive_ctrl_t *ctrl;  /**< attached control law, or NULL */
    mc_drive_telemetry_t tm;
    uint32_t warnings;          /**< MC_DRIVE_WARN_* (sticky until clear_faults) */
    uint32_t warn_causes;       /**< application warnings whose cause is present */
    uint32_t stop_cause;        /**< MC_DRIVE_STOP_* of the last controlled stop */
    bool stop_from_ctrl;        /**< STOPPING: the law decelerates (else the drive) */
    float stop_omega_ref_rad_s; /**< STOPPING from CURRENT: the speed ramp [rad/s] */
    float stop_time_s;          /**< time in STOPPING [s] */
    float stop_time_max_s;      /**< STOPPING: open the bridge after this [s] */
    float stop_dir;             /**< STOPPING: sign of the encoder speed the stop began
                                     at (+1, -1; 0: at rest or no encoder): the stop
                                     ends when the speed crosses zero */
    bool asc_active;            /**< FAULT with the low-side switches on (asc_enable) */
    /* speed reference shaping (uses_speed_ref laws) */
    float speed_target_rad_s; /**< mc_drive_set_speed_ref's target [rad/s] */
    float speed_ref_rad_s;    /**< the shaped reference [rad/s] */
    float speed_alpha_rad_s2; /**< its acceleration of the last step [rad/s^2] */
    /* the current loop's last step, handed to the law (mc_drive_meas_t) */
    float v_ab_prev_v[2]; /**< alpha-beta voltage commanded [V] */
    mc_drive_meas_t meas; /**< the record handed to a CTRL law this step */
    bool index_seen;      /**< the last encoder sample had MC_HAL_ENCODER_FLAG_INDEX */
    bool aligned;         /**< ALIGN: mc_drive_set_encoder_offset since init */
    /* the regenerative limit's lead (see "Regenerative braking") */
    float vbus_lag_v;       /**< the bus reading low-passed at the lead time [V] (0: none yet) */
    float regen_lead_alpha; /**< that filter's factor per fast step, dt / (t_lead + dt) */
    mc_drive_bus_t bus;     /**< the DC-bus limits' state and estimate (mc_drive_bus.h) */
    bool bus_on;            /**< a DC-bus limit is set (cfg.bus): the limiter runs */
    mc_drive_thermal_t thermal;      /**< derating factor, winding estimate (mc_drive_thermal.h) */
    mc_drive_hallobs_t *hallobs;     /**< Hall + observer (mc_drive_hallobs.h), or NULL: the
                                      encoder's angle as it is */
    const mc_cog_map_t *cog;         /**< anticogging map (mc_drive_cog.h), or NULL: none */
    mc_cog_series_t cog_ser;         /**< its kept orders' series (count 0: interpolate the
                                      map), derived when it is attached */
    const mc_cog_map_t *cog_ser_map; /**< the map cog_ser was derived from (NULL: none) */
    uint32_t cog_ser_crc;            /**< and that map's CRC then */
    float cog_ord_rms;               /**< that map's RMS order (mc_cog_map_order_rms): the
                                      bins path fades at it */
    float cog_lead_a; /**< this step's feed-forward less the current it asks to flow [A]: the
                           q reference's part that only lifts the loop's lag (0: none) */
    bool cog_on;      /**< the feed-forward ran this step: the dead-time compensation takes
                           its currents from the references */
} mc_drive_t;

/** Validate cfg and the HAL, initialise d (IDLE, PWM disabled). Returns
 *  MC_DRIVE_CFG_* bits; on error d is not changed. */
uint32_t mc_drive_init(mc_drive_t *d, const mc_drive_cfg_t *cfg, const mc_hal_t *hal);

/** The configuration checks of mc_drive_init alone (no HAL, no side
 *  effect): MC_DRIVE_CFG_* bits, MC_DRIVE_CFG_ERR_HAL never. The parameter
 *  store validates a whole new configuration with it before applying it. */
uint32_t mc_drive_check_cfg(const mc_drive_cfg_t *cfg);

/** Fast loop body (ADC interrupt). Returns true when the slow loop is due. */
bool mc_drive_fast_step(mc_drive_t *d);

/** The DC-bus current of the last current-loop step, 3/2 (vd id + vq iq)
 *  / vbus from its commanded voltages and measured currents [A], positive
 *  drawn (mc_drive_bus.h); 0 before the first. Computed here, for the
 *  telemetry, off the fast step: the limiter forms the same product only
 *  when a bus limit is set. */
float mc_drive_bus_current_a(const mc_drive_t *d);

/** Slow loop body (supervision). */
void mc_drive_slow_step(mc_drive_t *d);

/** Change mode. IDLE always accepted; CURRENT and CTRL only from IDLE (or
 *  the same mode) with no fault. Returns 0, -EINVAL (unknown mode, or the
 *  law's reset refused), -ENODEV (CURRENT without pwm3 or encoder, CTRL with
 *  no law attached), -EACCES (CURRENT, or a law that needs the encoder and
 *  does not find the angle itself, before the angle reference is known:
 *  mc_drive_angle_state() names what it waits for) or -EBUSY (in fault, or
 *  the bridge could not be enabled); on error nothing changes and the
 *  outputs stay off. */
int mc_drive_set_mode(mc_drive_t *d, mc_drive_mode_t mode);

/** The angle reference (see MC_DRIVE_ANGLE_REF_*): MC_DRIVE_ANGLE_KNOWN,
 *  or MC_DRIVE_ANGLE_NEED_INDEX / _NEED_ALIGN, the reason the sensored
 *  modes are refused. */
uint32_t mc_drive_angle_state(const mc_drive_t *d);

/** Take an offset an alignment measured (the electrical angle of the d axis
 *  at encoder count 0, [0, 2 pi)) as encoder_offset_rad; the angle is then
 *  known (ALIGN). Not while CURRENT runs on the old one. Returns 0, -EINVAL
 *  (not finite or outside [0, 2 pi)) or -EBUSY (CURRENT or STOPPING); on
 *  error nothing changes. */
int mc_drive_set_encoder_offset(mc_drive_t *d, float offset_e_rad);

/** Attach (or, with NULL, detach) a control law for CTRL mode. Only while
 *  not running (IDLE or FAULT). Returns 0; -EBUSY while running; -EINVAL
 *  (no fast function, unknown outputs); -ENODEV (the board lacks the bridge
 *  the law drives, or the encoder it needs). On error nothing changes. */
int mc_drive_attach_ctrl(mc_drive_t *d, const mc_drive_ctrl_t *ctrl);

/** Attach (or, with NULL, detach) the Hall + observer hand-over
 *  (mc_drive_hallobs.h, initialised by the caller, outliving the drive's use
 *  of it): from then on, in every step in which the current loop drives the
 *  bridge (CURRENT, the drive's stop, a law giving current references that
 *  does not find the angle itself) the electrical angle is its blend of the
 *  encoder's (the Hall) angle and the flux observer's. Only while not
 *  running (IDLE or FAULT); an mc_drive_init detaches it. Returns 0, -EBUSY
 *  while running, -ENODEV without an encoder. */
int mc_drive_attach_hallobs(mc_drive_t *d, mc_drive_hallobs_t *h);

/** Attach (or, with NULL, detach) the anticogging map (mc_drive_cog.h),
 *  already validated by the caller against this drive's encoder
 *  (mc_cog_check), outliving the drive's use of it: from the next fast step,
 *  with cfg.anticogging, a law with cogging_ff adds the map's current at the
 *  mechanical angle to its q reference: its series (mc_cog_series_ff_adv_a)
 *  when the map has an order, else its bins (mc_cog_ff_adv_a).
 *  Allowed while running, from a context the fast step interrupts: a map
 *  other than the one whose series the drive holds (or the same one with
 *  another CRC) is detached first, its series derived (about 2 ms on the
 *  M4F: the slow context's, never the fast step's), then attached with one
 *  pointer store; re-attaching the same map costs nothing. The caller does
 *  not change a map while it is attached. An mc_drive_init detaches it.
 *  Returns 0, -ENODEV with a map and no encoder. */
int mc_drive_attach_cog(mc_drive_t *d, const mc_cog_map_t *map);

/** Controlled stop (STOPPING, see Modes) from CURRENT or CTRL; IDLE at
 *  once when stop_decel_rad_s2 is 0 or the law has no stop op. Returns 0
 *  (also when already stopping or stopped). */
int mc_drive_stop(mc_drive_t *d);

/** Set the speed target of a speed law (uses_speed_ref): the drive slews
 *  its reference to it at cfg.speed_accel_rad_s2 each fast step. Returns 0
 *  or -EINVAL (NaN, inf); the caller checks the speed limit. While the
 *  bridge is off the reference starts there at the next enable. */
int mc_drive_set_speed_ref(mc_drive_t *d, float omega_m_rad_s);

/** Set the dq current references. Returns 0 or -EINVAL (NaN, inf, or
 *  |ref| > i_max_a); on error the previous references stay. */
int mc_drive_set_current_ref(mc_drive_t *d, float id_ref_a, float iq_ref_a);

/** Take the limits that may change while the bridge is on (i_max_a,
 *  i_trip_a, the bus window, omega_max_rad_s, temp_max_c, the stall and
 *  unbalance supervision, the warnings, the controlled stop, the speed
 *  reference's slew, the regenerative limit and the brake chopper) from
 *  cfg, already validated as a whole by the caller (mc_params_validate,
 *  mc_drive_init's rules). A lower i_max_a takes effect at once: the present
 *  current references are clamped to it (sign kept), so the drive never
 *  runs a reference above the limit in force, and a law giving current
 *  references saturates at it from the next step (mc_drive_meas_t.i_max_a). */
void mc_drive_set_runtime_limits(mc_drive_t *d, const mc_drive_cfg_t *cfg);

/** Raise a fault from the application (e.g. the CAN command timeout):
 *  same reaction as a detected fault. bits must be MC_DRIVE_FAULT_EXTERNAL. */
void mc_drive_raise_fault(mc_drive_t *d, uint32_t bits);

/** A warning whose cause the application sees (bits: MC_DRIVE_WARN_CAN_BUS;
 *  others are ignored, the drive detects them itself). present: the warning
 *  is set (a running drive makes a controlled stop, as for its own
 *  warnings; CURRENT/CTRL are refused) and mc_drive_clear_faults is refused
 *  while the cause stays; !present: the cause is gone, the warning stays
 *  until mc_drive_clear_faults. */
void mc_drive_warning_cause(mc_drive_t *d, uint32_t bits, bool present);

/** Clear the faults and go to IDLE, if the causes are gone (DC bus inside
 *  its window, hardware fault input released, no application warning cause
 *  present). Returns 0 or -EBUSY. */
int mc_drive_clear_faults(mc_drive_t *d);

#ifdef __cplusplus
}
#endif

#endif /* MC_DRIVE_H */
