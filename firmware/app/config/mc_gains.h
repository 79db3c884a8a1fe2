/**
 * @file mc_gains.h
 * @brief Controller gains derived from the motor's values: the one place
 *        the formulas live, called by the parameter table's resolution
 *        (mc_params_resolve: the images and every simulated scenario) and by
 *        the drive when commissioning stages what it measured
 *        (commission/mc_comm_can.c).
 *
 * In double. The current-loop PI is mc_foc_f32_gains_from_bandwidth
 * (kernels/foc): kp = L bw, ki = R bw.
 *
 * The formulas (mc_gains_derive; each settable gain given instead when its
 * parameter is not 0, the later ones then derived from it). T = 1/pwm_hz,
 * kt = 3/2 p flux, ke = p flux, v_max = 0.95 vbus / sqrt 3 (the SVPWM
 * circle), L = min(Ld, Lq) where a bound needs the smaller one.
 *
 *   cur_bw_rad_s       = 0.08 / T. The current PI kp = L bw, ki = R bw
 *                        cancels the winding's pole: the loop is first order
 *                        with bandwidth bw; with the one-period computation
 *                        delay it stays first-order-like (10-90 % rise
 *                        ln 9 / bw within 25 %) while bw T <= 0.08.
 *   i_limit_a          = min(i_max_a, i_sense_max_a / 1.25, 0.8 v_max / R):
 *                        inside the sensor's range with margin, and a
 *                        current the bus can push through R at standstill.
 *   i_rated_eff_a      = min(i_rated_a, i_limit_a); torque_rated = kt i_rated_eff.
 *   speed_limit_rad_s  = min(speed_max_rad_s, 0.9 w_v, 0.9 w_d):
 *                        w_v = speed_voltage_rad_s, the speed at which rated
 *                        current (id = 0) needs v_max (R, Lq, ke);
 *                        w_d = speed_delay_rad_s = MC_GAINS_WE_T_MAX / (p T),
 *                        the speed at which the current loop's electrical
 *                        angle advances 0.6 rad a period: with its
 *                        computation-delay compensation (mc_foc.h) the loop
 *                        keeps its rise time and stability up to there
 *                        (tests/sil/foc/test_delay_comp_sil.cpp), not beyond.
 *                        `mcsim describe SCENARIO --motor M --board B` says
 *                        which of the three sets the limit.
 *   speed_rated_eff    = min(speed_rated_rad_s, speed_limit_rad_s).
 *   enc_pll_bw_rad_s   = min(1000, 0.1 / max(T, latency), bw_q): the drive's
 *                        encoder tracking loop; its sample period or the
 *                        encoder's latency (encoder_latency_s: an SPI
 *                        frame's, one period for the AS5047P) costs it at
 *                        most 0.1 rad of phase at its bandwidth; bw_q
 *                        (mc_gains_enc_bw_quant_rad_s)
 *                        bounds it by the encoder's resolution: a step of
 *                        one count q = 2 pi / cpr moves the loop's speed by
 *                        3 bw q at once, which the speed PI (kp = J wc / kt,
 *                        wc = bw / 4) turns into 3 kp bw q of current; bw_q
 *                        keeps that at half the rated current,
 *                        sqrt(4 0.5 i_rated kt / (3 J q)). With 8192 counts
 *                        the other bounds hold on the library's motors with
 *                        their boards; a 90-count (Hall-class) sensor on the
 *                        hub motor gets tens of rad/s (ODrive's hoverboard
 *                        guide sets 100 by hand).
 *   speed_wc_rad_s     = min(cur_bw / 10, enc_pll_bw / 4): crossover of the
 *                        sensored speed PI on the plant kt / (J s):
 *                        kp = J wc / kt, ki = kp wc / 4 (zero at wc / 4).
 *   speed_accel_rad_s2 = 0.5 kt i_limit / J: the reference slews so that
 *                        half the current limit accelerates the rotor.
 *   obs_crit_rad_s     = 0.02 speed_rated_eff: flux observer critical speed,
 *                        gamma = 4 p w_crit / flux^2 (in the observer).
 *   pll_bw_rad_s       = min(300, 0.04 / T): observer PLL (paper 002).
 *   sls_wc_rad_s       = min(pll_bw / 3, cur_bw / 10): sensorless speed PI
 *                        crossover, same formula as the sensored one.
 *   handover_rad_s     = 0.1 speed_rated_eff (5x the critical speed).
 *   if_current_a       = min(i_limit, 0.8 i_rated_eff): holds 30 % rated load
 *                        at a load angle of about 22 deg plus the ramp.
 *   if_accel_rad_s2    = 0.15 torque_rated / J.
 *   align_time_s       = clamp(2 sqrt(0.2 J / (p 0.3 torque_rated)),
 *                        10 / cur_bw, 0.05): short enough that a 30 %
 *                        rated load cannot turn the rotor 0.2 rad (electrical)
 *                        while the current ramps up, long enough for the
 *                        current loop.
 *   pos_kp_per_s       = speed_wc / 6: position P gain (the position pole
 *                        below the velocity PI's zero at speed_wc / 4, so the
 *                        cascade does not overshoot); the velocity PI of the
 *                        position cascade is the sensored speed PI above.
 *   pos_v_max_rad_s    = 0.5 speed_rated_eff: trapezoid cruise speed.
 *   pos_a_max_rad_s2   = speed_accel_rad_s2 (half the current limit
 *                        accelerates the rotor; the other half is the loop's).
 *   pos_d_max_rad_s2   = speed_accel_rad_s2.
 *   pos_filter_bw_rad_s = pos_kp: input filter of streamed setpoints.
 *   stop_decel_rad_s2  = speed_accel_rad_s2: the drive's controlled stop.
 *   pi2d_wn_rad_s      = min(speed_wc / 3, 0.5 R / Lq): the PI^2D triple pole;
 *                        the R/L bound keeps the proof's ki (L/R)^2 < eps
 *                        with eps = 2 ki / kp (kp' = kp / 2).
 *   pi2d_a_per_s       = min(enc_pll_bw, 0.1 / T, 2 cur_bw sigma / (3 wn)),
 *                        sigma = kt / J: dirty-derivative pole (b = 1); the
 *                        last bound keeps the law's coupling of the speed
 *                        error into the q-current error (Delta ~ 3 wn a / sigma)
 *                        below 2 k2 (k2 = cur_bw).
 *   pi2d_coupling      = kt ke / (J Lq k2) [rad/s]. The PI^2D builder
 *                        (mc_law_cfg.h) refuses a < 3 wn (the filter would be
 *                        slower than the loop: MC_GAINS_ERR_PI2D_FILTER) and a
 *                        coupling above MC_GAINS_PI2D_COUPLING_MAX, an
 *                        empirical bound (the simulator's gimbal motor, 453,
 *                        limit-cycles to over-current with any wn, a tried;
 *                        the others are at 7 to 186 and settle).
 *
 * Refused (MC_GAINS_ERR_* bits below; the simulator names the file values
 * behind each, sim/cli/app_params.cpp): L/R shorter than two PWM periods;
 * a PWM ripple vbus T / (4 L) (peak to peak, half-bridge at 50 % duty: an
 * upper bound) above i_max_a; an i_limit below 10 % of i_max_a (sensor or
 * bus too small for the motor); an i_limit above i_sense_max_a / 1.1; a bus
 * that cannot drive rated current at any speed.
 */
#ifndef MC_GAINS_H
#define MC_GAINS_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Errors of mc_gains_speed_pi. */
#define MC_GAINS_OK        0u
#define MC_GAINS_ERR_VALUE (1u << 0) /**< an input <= 0 or not finite */

/** Torque constant of a PMSM, 1.5 p psi [N m / A]. */
double mc_gains_kt_nm_a(double pole_pairs, double flux_wb);

/** Crossover of the sensored speed PI: a tenth of the current loop's
 *  bandwidth and a quarter of the encoder tracking loop's, the lower. */
double mc_gains_speed_wc_rad_s(double cur_bw_rad_s, double enc_pll_bw_rad_s);

/**
 * Speed PI from the inertia: kp = J wc / kt [A s/rad], the PI zero at
 * wc / 4 (ki = kp wc / 4 [A/rad], computed from the float kp). Returns
 * MC_GAINS_ERR_VALUE (outputs unchanged) for an input <= 0 or not finite.
 */
uint32_t mc_gains_speed_pi(double j_kgm2, double kt_nm_a, double wc_rad_s, float *p_kp_a_s_rad,
                           float *p_ki_a_rad);

/* ------------------------------------------------ the laws' gains (issue 19) */

/* Refusals of mc_gains_derive (bits): no gains make these safe. */
#define MC_GAINS_ERR_LR_SHORT    (1u << 1) /**< min(Ld, Lq) / R shorter than two PWM periods */
#define MC_GAINS_ERR_RIPPLE      (1u << 2) /**< PWM ripple vbus T / (4 L) above i_max_a */
#define MC_GAINS_ERR_I_LIMIT     (1u << 3) /**< usable current below 10 % of i_max_a */
#define MC_GAINS_ERR_SENSE       (1u << 4) /**< i_limit_a above i_sense_max_a / 1.1 */
#define MC_GAINS_ERR_SPEED_LIMIT (1u << 5) /**< the bus drives rated current at no speed */
/* Refusals of the law builders (bits). */
#define MC_GAINS_ERR_PI2D_FILTER   (1u << 6) /**< PI2D: a < 3 wn (filter slower than the loop) */
#define MC_GAINS_ERR_PI2D_COUPLING (1u << 7) /**< PI2D: kt ke / (J L k2) > 300 rad/s */
#define MC_GAINS_ERR_SALIENT       (1u << 8) /**< PI2D: Ld, Lq differ by > 5 % (its model has one L) */

/** Largest back-EMF coupling kt ke / (J L k2) PI2D accepts [rad/s] (empirical:
 *  see the file comment). */
#define MC_GAINS_PI2D_COUPLING_MAX 300.0

/** The motor and board values the gains come from (SI units, as the
 *  parameter table and the simulator's motor files name them). */
typedef struct {
    double r_ohm, ld_h, lq_h, flux_wb, pole_pairs, j_kgm2, b_nm_s_rad;
    double i_max_a, i_rated_a, speed_max_rad_s, speed_rated_rad_s;
    double vbus_v, pwm_hz, dead_time_s, i_sense_max_a;
    double delay_periods;     /**< PWM periods between sampling and the duties' effect */
    double vbus_max_v;        /**< the over-voltage trip as set; 0: derived (mc_gains_vbus_max_v) */
    double vbus_board_max_v;  /**< the board's bus limit (rating inside its divider's
                                  range); 0: none given */
    double encoder_cpr;       /**< encoder counts per mechanical turn; 0: none */
    double encoder_latency_s; /**< the encoder's latency (an SPI frame's) [s]; 0: none */
} mc_gains_motor_t;

/** Every derived gain (the formulas: the file comment; the code in
 *  mc_gains.c). In an input `fix` of mc_gains_derive a field
 *  that is not NaN is taken as given (and the later ones derived from it);
 *  the first block is settable, the second derived only. */
typedef struct {
    double cur_bw_rad_s, i_limit_a, enc_pll_bw_rad_s, speed_wc_rad_s, speed_accel_rad_s2;
    double speed_kp_a_s_rad, speed_ki_a_rad; /**< the sensored speed PI (mc_gains_speed_pi at
                                                  speed_wc; float values held in double) */
    double obs_crit_rad_s, pll_bw_rad_s, sls_wc_rad_s, handover_rad_s;
    double if_current_a, if_accel_rad_s2, align_time_s;
    double pi2d_wn_rad_s, pi2d_a_per_s;
    double pos_kp_per_s, pos_v_max_rad_s, pos_a_max_rad_s2, pos_d_max_rad_s2;
    double pos_filter_bw_rad_s, stop_decel_rad_s2;
    /* derived only */
    double kt_nm_a, v_max_v, i_rated_eff_a, torque_rated_nm;
    double speed_limit_rad_s, speed_rated_eff_rad_s, pi2d_coupling;
    double speed_voltage_rad_s, speed_delay_rad_s; /**< the bounds of speed_limit_rad_s */
} mc_gains_t;

/** The largest electrical angle per period, omega_e T [rad], the current
 *  loop is designed for (speed_limit_rad_s; 10 samples per electrical
 *  period). */
#define MC_GAINS_WE_T_MAX 0.6

/** The share of the rated current one encoder count may move through the
 *  tracking loop and the speed PI (enc_pll_bw_rad_s's resolution bound). */
#define MC_GAINS_ENC_NOISE_FRAC 0.5

/** The encoder tracking loop's bandwidth bound from the encoder's
 *  resolution (the file comment), from g's kt_nm_a and i_rated_eff_a;
 *  +inf without an encoder. */
double mc_gains_enc_bw_quant_rad_s(const mc_gains_motor_t *m, const mc_gains_t *g);

/** Square root of x >= 0, correctly rounded (IEEE 754 sqrt, bit for bit):
 *  the gains are computed once, in double, on targets without a libm. */
double mc_gains_sqrt(double x);

/** A fix with every field NaN (derive everything). */
void mc_gains_fix_none(mc_gains_t *fix);

/**
 * Derive the gains of m into *g (fields of fix not NaN are taken as given;
 * fix may be NULL). Returns 0 or MC_GAINS_ERR_* bits (ERR_VALUE for NULL
 * or a motor value <= 0 or not finite where it must be positive); *g is
 * written in full either way (for the caller's messages).
 */
uint32_t mc_gains_derive(const mc_gains_motor_t *m, const mc_gains_t *fix, mc_gains_t *g);

/**
 * The over-voltage trip the drive runs with (the vbus_max_v parameter, and
 * the sensorless law's static voltage limit): m->vbus_max_v when set, else
 * half the nominal bus above it, 1.5 vbus_v, but never above the board's
 * own limit m->vbus_board_max_v (when given):
 *   vbus_max = min(1.5 vbus_v, vbus_board_max_v).
 * The brake and regen thresholds are fractions of vbus_max - vbus_v
 * (mc_params.c), so they stay inside what the board reads too.
 */
double mc_gains_vbus_max_v(const mc_gains_motor_t *m);

/** Speed slew of the sensorless law, 0.5 torque_rated / J [rad/s^2]. */
double mc_gains_sls_slew_rad_s2(const mc_gains_motor_t *m, const mc_gains_t *g);

#ifdef __cplusplus
}
#endif

#endif /* MC_GAINS_H */
