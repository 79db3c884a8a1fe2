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

#ifdef __cplusplus
}
#endif

#endif /* MC_GAINS_H */
