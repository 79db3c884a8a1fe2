/**
 * @file mc_gains.h
 * @brief Controller gains derived from the motor's values: the one place
 *        the formulas live, called by the simulator's scenario set-up
 *        (sim/cli/drive_setup.cpp) and by the drive when commissioning
 *        stages what it measured (commission/mc_comm_can.c).
 *
 * In double, as the scenarios always computed them: the results the
 * scenarios get are bit-identical to the C++ they replace. The current-loop
 * PI is mc_foc_f32_gains_from_bandwidth (kernels/foc): kp = L bw, ki = R bw.
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
#define MC_GAINS_ERR_SALIENT       (1u << 8) /**< sensorless, PI2D: Ld, Lq differ by > 5 % */

/** Largest back-EMF coupling kt ke / (J L k2) PI2D accepts [rad/s] (empirical:
 *  see sim/cli/drive_setup.hpp). */
#define MC_GAINS_PI2D_COUPLING_MAX 300.0

/** The motor and board values the gains come from (SI units, as the
 *  parameter table and the simulator's motor files name them). */
typedef struct {
    double r_ohm, ld_h, lq_h, flux_wb, pole_pairs, j_kgm2, b_nm_s_rad;
    double i_max_a, i_rated_a, speed_max_rad_s, speed_rated_rad_s;
    double vbus_v, pwm_hz, dead_time_s, i_sense_max_a;
    double delay_periods; /**< PWM periods between sampling and the duties' effect */
} mc_gains_motor_t;

/** Every derived gain (formulas in mc_gains.c; the table of them in
 *  sim/cli/drive_setup.hpp). In an input `fix` of mc_gains_derive a field
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
} mc_gains_t;

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

/** Speed slew of the sensorless law, 0.5 torque_rated / J [rad/s^2]. */
double mc_gains_sls_slew_rad_s2(const mc_gains_motor_t *m, const mc_gains_t *g);

#ifdef __cplusplus
}
#endif

#endif /* MC_GAINS_H */
