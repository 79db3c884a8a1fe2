/**
 * @file mc_commission.h
 * @brief Commissioning: the drive measures its own motor and sensors.
 *
 * A control-law plug-in (mc_drive_ctrl_t, CTRL mode, three-phase bridge,
 * encoder) that runs the whole sequence from the drive's fast step and
 * writes only duties; the drive keeps sampling, supervision and the fault
 * reaction. Nothing about the motor is needed: only the board (period,
 * dead time, shunts) and the test limits (current, voltage, speed). The
 * method, its limits and the measured accuracy: commission/README.md.
 *
 * Sequence (mc_comm_step_t):
 *   OFFSETS     bridge on at zero voltage (equal duties: at the sampling
 *               instant every low side conducts, as low-leg shunts need;
 *               no current flows in a motor at rest); each current channel
 *               averaged. An offset above offset_max_a: MC_COMM_ERR_OFFSET.
 *   L_ROUGH     square-wave voltage (+-v each period) along alpha, then
 *               beta, its amplitude doubled until the ripple reaches 10 % of
 *               i_test: a first inductance for the current loop, and the
 *               connection check (per-phase ripple over both tries, valid
 *               for Ld != Lq): nothing conducts -> NO_MOTOR; one phase
 *               silent -> OPEN_PHASE.
 *   HALL        (within ENCODER, with cfg.hall: Hall sensors) i_test along
 *               a forced angle swept a turn and two sectors up, then back;
 *               every code change recorded with the angle; the table
 *               (codes, six edges, band) from mc_comm_hall_table_f32
 *               (mc_comm_hall.h); refusals HALL_CODES, HALL_ORDER, RANGE
 *               (sector widths), ROTOR_BLOCKED (no change).
 *   ALIGN/SWEEP i_test along a commanded electrical angle (current loop
 *               kp = L bw, ki = kp bw / 4: stable whatever R), a quarter
 *               turn, then one electrical turn forward (direction and pole
 *               pairs from the encoder counts), back and forward again
 *               (the electrical offset averaged over both directions, which
 *               cancels friction and lag). After the align hold kp drops
 *               to the holding resistance (vd / i_test, an upper bound of
 *               R): the rotor's swing is then damped by its back-EMF. No
 *               encoder motion: the voltage that the rotating field needs
 *               tells a turning rotor (dead
 *               encoder, ENCODER_NO_MOTION) from a blocked one
 *               (ROTOR_BLOCKED).
 *   RESISTANCE  i_test / 2 and i_test along the (aligned) d axis:
 *               R = dV / dI (dead-time and switch drops cancel).
 *   INDUCTANCE  the d-axis DC voltage of i_test held, plus a square wave
 *               along d (Ld) and along q (Lq): the bias keeps every phase
 *               current on one side of the dead band, so the dead time
 *               adds a constant that the ripple does not see.
 *   FLUX        FOC on the identified values: iq = i_test / 2 until the
 *               back-EMF reaches bemf_frac of the limit (or the whole
 *               voltage 0.8 of it, the electrical speed 1.5 current-loop
 *               bandwidths, the speed cap),
 *               then zero current: the voltage the loop then applies is the
 *               back-EMF alone (fitted once the current has settled at
 *               zero), psi = |v| / omega_e (least squares). The
 *               spin-up and the coast-down give J and B. A rotor that does
 *               not move: ROTOR_BLOCKED; one that turns backwards:
 *               WRONG_DIRECTION. The step checks itself (mc_comm_check.h,
 *               README.md "Checks of the flux step"): the coast's first
 *               and second half (two speed bands) fitted apart give two
 *               fluxes, which must agree within the sum of their
 *               resolutions (the counts per turn over the band's time and
 *               the speed filter's, the dead time's voltage over the
 *               band's): else FLUX_SPEEDS; the coast's speed must be a
 *               line (its middle third on the chord of the outer two)
 *               within 5 % of its fall plus the viscous decay's bend
 *               and the counts' part (else MECH_FIT), and J from the
 *               spin-up's first half and from its second (each with the
 *               coast's B/J) within 2 % plus the counts' part (else
 *               MECH_SPIN_COAST: friction not viscous, a load). A refusal
 *               stores nothing, as every other.
 *   DONE        zero current until the application leaves CTRL mode.
 * Without an encoder (cfg.pole_pairs_given, README.md "Without an
 * encoder"): ENCODER is the alignment alone (no sweeps, the pole pairs
 * given), RESISTANCE and INDUCTANCE as above, FLUX an I-f spin (i_test
 * along an angle turning at omega, two holds at omega_hi and omega_hi / 2:
 * psi from the back-EMF in the spin's frame; IF_SYNC when the rotor does
 * not follow, FLUX_SPEEDS when the holds disagree), no J or B; DONE keeps
 * the spin at the lower speed until the application opens the bridge; the
 * result carries MC_COMM_SENSORLESS.
 * A failure returns the error bits from the fast step: the drive faults
 * (MC_DRIVE_FAULT_CONTROL, tm.ctrl_err = the bits), the bridge is off and
 * the result stays invalid (nothing to store).
 */
#ifndef MC_COMMISSION_H
#define MC_COMMISSION_H

#include <stdbool.h>
#include <stdint.h>

#include "commission/mc_comm_check.h"
#include "commission/mc_comm_hall.h"
#include "foc/mc_foc.h"
#include "hal/hall.h"
#include "ident/mc_ident.h"
#include "mc_drive.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Error bits (the named reasons a sequence stops). */
#define MC_COMM_ERR_NONE              0u
#define MC_COMM_ERR_OFFSET            (1u << 0) /**< a current-sensor offset implausible */
#define MC_COMM_ERR_NO_MOTOR          (1u << 1) /**< no current on any axis */
#define MC_COMM_ERR_OPEN_PHASE        (1u << 2) /**< one phase carries no current */
#define MC_COMM_ERR_ENCODER_NO_MOTION (1u << 3) /**< the rotor turned, the encoder did not */
#define MC_COMM_ERR_ROTOR_BLOCKED     (1u << 4) /**< the rotor did not turn */
#define MC_COMM_ERR_WRONG_DIRECTION   (1u << 5) /**< the rotor turned against the torque */
#define MC_COMM_ERR_ENCODER_BAD \
    (1u << 6)                              /**< counts inconsistent: no integer pole
                                                      pairs, back and forth disagree */
#define MC_COMM_ERR_OVERCURRENT (1u << 7)  /**< a phase above 1.5 i_test */
#define MC_COMM_ERR_VOLTAGE     (1u << 8)  /**< the test needs more than v_test_max */
#define MC_COMM_ERR_RANGE       (1u << 9)  /**< an identified value not plausible */
#define MC_COMM_ERR_MEAS        (1u << 10) /**< no encoder sample or a non-finite one */
#define MC_COMM_ERR_ABORTED     (1u << 11) /**< mc_comm_abort() */
#define MC_COMM_ERR_HOST_LOST   (1u << 12) /**< the host's keep-alive stopped (CAN) */
#define MC_COMM_ERR_ENCODER_COARSE \
    (1u << 13) /**< fewer than MC_COMM_COUNTS_PER_E_TURN_MIN counts per electrical turn:
                    the flux step cannot measure the speed (refused before it) */
#define MC_COMM_ERR_HALL_CODES \
    (1u << 14) /**< Hall table: a code 000 or 111 read, or fewer than six distinct
                    codes (a sensor stuck, unpowered or disconnected) */
#define MC_COMM_ERR_HALL_ORDER \
    (1u << 15) /**< Hall table: the codes do not change one sensor at a time round
                    one cycle of six (wiring), or not the order the table in force
                    allows (the drive's ENCODER fault during the sweep) */
/* The flux step's own checks (mc_comm_check.h, README.md "Checks of the
 * flux step"): bits above the status frame's 16; over CAN the frame's
 * error field carries MC_COMM_ERR_RANGE for them and its detail field the
 * reason (mc_comm_err_frame). */
#define MC_COMM_ERR_FLUX_SPEEDS \
    (1u << 16) /**< the coast's two speed bands (its first and second half) give
                    fluxes further apart than their resolution allows */
#define MC_COMM_ERR_MECH_FIT \
    (1u << 17) /**< the coast's speed is not the viscous model's line (a load that
                    changes, a speed that jumps), or its records are too short */
#define MC_COMM_ERR_MECH_SPIN_COAST \
    (1u << 18) /**< J from the spin-up's two halves (each with the coast's B/J)
                    disagree: friction not viscous (Coulomb, a load) */
#define MC_COMM_ERR_IF_SYNC \
    (1u << 19) /**< without an encoder: the rotor did not follow the I-f spin (its
                    back-EMF too small, turning in the spin's frame, or more than
                    60 degrees el. off the current): stalled or out of step */
#define MC_COMM_ERR_WIDE_MASK 0xFFFF0000u /**< the bits the status frame has no room for */

/* COMMISSION_STATUS.detail: the reason a bit of MC_COMM_ERR_WIDE_MASK names
 * (the lowest set), 0 none. */
#define MC_COMM_DETAIL_NONE            0u
#define MC_COMM_DETAIL_FLUX_SPEEDS     1u
#define MC_COMM_DETAIL_MECH_FIT        2u
#define MC_COMM_DETAIL_MECH_SPIN_COAST 3u
#define MC_COMM_DETAIL_IF_SYNC         4u

/** The status frame's error field (the 16 low bits, MC_COMM_ERR_RANGE added
 *  when a wider bit is set) and its detail code from the error word. */
static inline uint32_t mc_comm_err_frame(uint32_t err, uint32_t *p_detail)
{
    *p_detail = ((err & MC_COMM_ERR_FLUX_SPEEDS) != 0u)       ? MC_COMM_DETAIL_FLUX_SPEEDS
                : ((err & MC_COMM_ERR_MECH_FIT) != 0u)        ? MC_COMM_DETAIL_MECH_FIT
                : ((err & MC_COMM_ERR_MECH_SPIN_COAST) != 0u) ? MC_COMM_DETAIL_MECH_SPIN_COAST
                : ((err & MC_COMM_ERR_IF_SYNC) != 0u)         ? MC_COMM_DETAIL_IF_SYNC
                                                              : MC_COMM_DETAIL_NONE;
    return (err & 0xFFFFu) | (((err & MC_COMM_ERR_WIDE_MASK) != 0u) ? MC_COMM_ERR_RANGE : 0u);
}

/* The Hall table's other refusals use the bits that already name them (the
 * status frame's error field has 16 bits): a sector width outside 30..90
 * degrees el. or a band of half a sector: MC_COMM_ERR_RANGE; no change
 * over the sweep or an edge seen one way only (the rotor did not follow
 * the vector): MC_COMM_ERR_ROTOR_BLOCKED. */

/** The fewest encoder counts per electrical turn the flux step measures
 *  with: its speed comes from the counts, and at 6 (a Hall-class 90-count
 *  sensor on 15 pole pairs) the coast's fit read the hub motor's flux tens
 *  of percent low; at 12 within the library's 3 % (tests/sil/commission,
 *  the hub motor at 90 and 180 counts). */
#define MC_COMM_COUNTS_PER_E_TURN_MIN 12u

/** The Hall table's sweep (README.md "Hall table"): each way a turn and two
 *  sectors, MC_COMM_HALL_T_RAMP_S up to speed, MC_COMM_HALL_T_CONST_S at it
 *  (1.5 s: 0.9 turn a second), MC_COMM_HALL_T_RAMP_S down; with the align
 *  ramp and the three holds (0.1 s each) the step takes MC_COMM_HALL_STEP_S. */
#define MC_COMM_HALL_T_RAMP_S  0.25f
#define MC_COMM_HALL_T_CONST_S 1.5f
#define MC_COMM_HALL_STEP_S    (0.4f + 2.0f * (2.0f * MC_COMM_HALL_T_RAMP_S + MC_COMM_HALL_T_CONST_S))

/* Configuration errors of mc_comm_init. */
#define MC_COMM_CFG_OK        0u
#define MC_COMM_CFG_ERR_NULL  (1u << 0)
#define MC_COMM_CFG_ERR_VALUE (1u << 1) /**< a field <= 0, not finite, or out of range */

typedef enum {
    MC_COMM_STEP_IDLE = 0,
    MC_COMM_STEP_OFFSETS = 1,
    MC_COMM_STEP_L_ROUGH = 2,
    MC_COMM_STEP_ENCODER = 3,
    MC_COMM_STEP_RESISTANCE = 4,
    MC_COMM_STEP_INDUCTANCE = 5,
    MC_COMM_STEP_FLUX = 6,
    MC_COMM_STEP_DONE = 7,
    MC_COMM_STEP_FAILED = 8,
} mc_comm_step_t;

typedef struct {
    float dt_s;                /**< PWM period [s], > 0 */
    float i_test_a;            /**< test current (every step stays below 1.5x) [A], > 0 */
    float v_test_max_v;        /**< largest voltage vector of any step [V], > 0 */
    float offset_max_a;        /**< largest plausible current-sensor offset [A], > 0 */
    float dead_time_s;         /**< bridge dead time [s], >= 0, < dt_s / 4 */
    float cur_bw_rad_s;        /**< current-loop bandwidth during the tests [rad/s],
                                   0 < bw dt <= 0.2 */
    float speed_max_m_rad_s;   /**< cap of the flux spin-up, mechanical [rad/s], > 0 */
    float bemf_frac;           /**< spin-up ends at this fraction of v_test_max, (0, 1) */
    uint32_t pole_pairs_max;   /**< largest pole-pair count accepted, 1..64 */
    bool three_shunts;         /**< ic is measured (else -(ia + ib)) */
    float speed_tau_s;         /**< time constant of the speed from the counts [s],
                                   0 (the encoders': 2 ms) or (0, 0.1]; Hall sensors
                                   (encoder_type 1): MC_COMM_HALL_SPEED_TAU_S */
    const mc_hal_hall_t *hall; /**< the Hall sensors whose table the sequence measures
                                    first (README.md "Hall table"); NULL: none */
    uint32_t pole_pairs_given; /**< 0: the encoder measures the pole pairs; else no
                                    encoder (README.md "Without an encoder"): these
                                    pole pairs (the user's), the flux from an I-f
                                    spin, no offset, no J or B; 1..pole_pairs_max */
} mc_comm_cfg_t;

/** The count speed's time constant with Hall sensors: their angle moves by
 *  up to a sector (60 degrees el.) in one sample below the interpolation's
 *  speed, which over 2 ms reads as a speed far above the rotor's (15 pole
 *  pairs: 35 rad/s mech.) and ended the flux step's spin-up at once; over
 *  20 ms a tenth of it, and the coast's speed (a decay of seconds) lags by
 *  under 1 %. */
#define MC_COMM_HALL_SPEED_TAU_S 0.02f

/* Result bits (mc_comm_result_t.valid). */
#define MC_COMM_HAVE_OFFSETS (1u << 0)
#define MC_COMM_HAVE_R       (1u << 1)
#define MC_COMM_HAVE_L       (1u << 2)
#define MC_COMM_HAVE_ENCODER (1u << 3)
#define MC_COMM_HAVE_FLUX    (1u << 4)
#define MC_COMM_HAVE_MECH    (1u << 5)
#define MC_COMM_HAVE_ALL     0x3Fu
/** Measured without an encoder (cfg.pole_pairs_given): R, L and flux; the
 *  pole pairs given, no encoder offset or direction, no J or B (their speed
 *  comes from the counts). Not part of HAVE_ALL: a flag, not a value. */
#define MC_COMM_SENSORLESS (1u << 6)

/**
 * What commissioning found: one field per parameter of the table (issue 17
 * names: adc offsets, r_ohm, ld_h, lq_h, flux_wb, pole_pairs,
 * encoder_offset_rad, encoder_direction; j_kgm2 and b_nm_s_rad besides).
 * adc_offset_a are relative to the offsets the drive already subtracted
 * (mc_comm_apply adds them).
 */
typedef struct {
    float adc_offset_a[3];
    float r_ohm;
    float ld_h;
    float lq_h;
    float flux_wb;
    uint32_t pole_pairs;
    float encoder_offset_rad;  /**< electrical angle of the d axis at count 0, [0, 2 pi) */
    int32_t encoder_direction; /**< +1: counts up for positive rotation; -1: down */
    float dead_time_v;         /**< inverter voltage error per phase (dead time, drops) [V] */
    float j_kgm2;
    float b_nm_s_rad;
    uint32_t valid;            /**< MC_COMM_HAVE_* */
    mc_comm_hall_table_t hall; /**< the Hall table measured (have_hall) */
    bool have_hall;            /**< cfg.hall was swept and its table derived */
} mc_comm_result_t;

typedef struct {
    mc_comm_cfg_t cfg;
    mc_comm_step_t step;
    uint32_t sub; /**< phase within the step */
    uint32_t n;   /**< periods in the current phase */
    uint32_t err; /**< sticky MC_COMM_ERR_* */
    mc_comm_result_t res;
    mc_foc_f32_t foc;
    float l0_h; /**< rough inductance (current loop of the tests) */
    /* square wave */
    float vh_v;
    float sq_sign;
    float prev_i[3];
    mc_ident_avg_f32_t corr[3];
    float d_axis[2];     /**< ripple of the alpha and beta tries [A] */
    float d_phase[2][3]; /**< per-phase ripple per volt of the two tries [A/V] */
    /* encoder */
    float theta_cmd_rad;
    float theta0_rad;
    float i_cmd_a;
    uint32_t last_count;
    int32_t count_acc; /**< unwrapped counts since the sweep began */
    int32_t count_fwd;
    int32_t count_back;
    bool have_count;
    bool enc_coarse; /**< the encoder has < MC_COMM_COUNTS_PER_E_TURN_MIN counts per
                          electrical turn (set once the pole pairs are known) */
    mc_ident_circ_f32_t off_acc;
    mc_ident_avg_f32_t vq_acc;
    /* Hall table */
    mc_comm_hall_rec_t hall_rec;
    uint32_t hall_code; /**< the last code read (8: none yet) */
    /* resistance / inductance */
    mc_ident_avg_f32_t v_acc, i_acc;
    float v1_v, i1_a, v2_v, i2_a;
    float vdc_alpha_v, vdc_beta_v;
    /* flux and mechanics */
    mc_ident_line_f32_t acc_fit;
    mc_ident_line_f32_t fit_band[2]; /**< the flux fit's first and second half */
    mc_comm_blk_t spin_rec;          /**< the spin-up's speed (the J/B checks) */
    mc_comm_blk_t coast_rec;         /**< the coast's speed */
    mc_comm_flux_chk_t flux_chk;     /**< the flux check's figures (after the coast) */
    mc_comm_mech_chk_t mech_chk;     /**< the J/B checks' figures */
    float w_acc_mean, a_acc;
    float iq_spin_a;
    float t_s;
    float t_fit0_s;   /**< coast: when the flux fit began (< 0: not yet) */
    uint32_t quiet_n; /**< coast: periods the current has stayed near zero */
    float vbus_v;
    float w_m_rad_s;      /**< own speed estimate from the counts (forward > 0) */
    float w_if_rad_s;     /**< without an encoder: the I-f spin's electrical speed */
    float w_hi_rad_s;     /**< ... its higher speed (the ramp's end) */
    uint8_t progress_pct; /**< rough progress of the sequence, 0..100 */
    mc_drive_ctrl_t ops;  /**< the plug-in table (mc_comm_ops) */
} mc_comm_t;

/** Validate cfg and initialise c (step IDLE, no result). */
uint32_t mc_comm_init(mc_comm_t *c, const mc_comm_cfg_t *cfg);
/** Arm the sequence: it starts with the next reset (entering CTRL mode). */
void mc_comm_restart(mc_comm_t *c);
/** Stop: the next fast step returns MC_COMM_ERR_ABORTED (bridge off). */
void mc_comm_abort(mc_comm_t *c);
/** The plug-in to attach (outputs PWM3, needs the encoder). */
const mc_drive_ctrl_t *mc_comm_ops(mc_comm_t *c);

/** The run ended on the drive's own fault (the plug-in was not asked): when
 *  that was the ENCODER fault while the Hall table was swept, the Hall
 *  adapter refused a code or a change of the table in force, and the
 *  sensors, read now (the bridge is off, the rotor where it stopped), tell
 *  which: 000 or 111, MC_COMM_ERR_HALL_CODES, else MC_COMM_ERR_HALL_ORDER.
 *  0 otherwise. */
uint32_t mc_comm_hall_fault_reason(const mc_comm_t *c, uint32_t drive_faults);

static inline bool mc_comm_done(const mc_comm_t *c)
{
    return c->step == MC_COMM_STEP_DONE;
}

/**
 * Check the result and write it into the drive configuration: motor
 * values into foc (r, ld, lq, flux), current PI gains re-derived with
 * mc_foc_f32_gains_from_bandwidth at cur_bw_rad_s (the formula of
 * mc_params_to_drive_cfg), pole pairs, encoder offset and direction,
 * current offsets added. Returns MC_COMM_ERR_RANGE (and changes nothing)
 * for an incomplete or implausible result.
 */
uint32_t mc_comm_apply(const mc_comm_result_t *r, float cur_bw_rad_s, mc_drive_cfg_t *dc);

#ifdef __cplusplus
}
#endif

#endif /* MC_COMMISSION_H */
