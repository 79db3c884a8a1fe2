/**
 * @file mc_comm_check.h
 * @brief Commissioning's own consistency checks of the flux step (flux from
 *        two speed bands, J and B from the spin-up and the coast-down):
 *        a result its own data show to be wrong is refused by name
 *        (commission/README.md "Checks of the flux step").
 *
 * Pure f32 functions on the step's accumulators; no state of their own.
 *
 * Block recorder: a signal sampled every dt, kept as the means of up to
 * MC_COMM_BLK_N equal blocks; when the blocks are full, neighbours merge
 * pairwise and the block length doubles, so a record of unknown length
 * (the spin-up ends on a condition) of MC_COMM_BLK_N samples or more ends
 * with MC_COMM_BLK_N / 2 to
 * MC_COMM_BLK_N full blocks spread over all of it (the samples of the
 * block being filled at the end are left out).
 */
#ifndef MC_COMM_CHECK_H
#define MC_COMM_CHECK_H

#include <stdbool.h>
#include <stdint.h>

#include "ident/mc_ident.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_COMM_BLK_N 16u

typedef struct {
    float mean[MC_COMM_BLK_N]; /**< mean of each full block */
    uint32_t nb;               /**< full blocks */
    uint32_t len;              /**< samples per block (1, 2, 4, ...) */
    uint32_t k;                /**< samples in the block being filled */
    float acc;                 /**< their sum */
} mc_comm_blk_t;

void mc_comm_blk_reset(mc_comm_blk_t *b);
void mc_comm_blk_step(mc_comm_blk_t *b, float y);

/** The mean of the means of blocks [j0, j1), j0 < j1 <= nb. */
float mc_comm_blk_mean(const mc_comm_blk_t *b, uint32_t j0, uint32_t j1);

/* ------------------------------------------------------------ flux */
/** The two flux estimates of the coast (through-origin fits of |v| on
 *  omega_e over its first half, the higher speeds, and its second) and
 *  what limits their agreement. */
typedef struct {
    float psi_hi_wb; /**< first half of the fit window */
    float psi_lo_wb; /**< second half */
    float dev;       /**< |psi_hi - psi_lo| / mean of the two */
    float tol;       /**< the agreement the resolution allows (sum of both bands') */
} mc_comm_flux_chk_t;

/** Resolution of one band's flux, relative: the mean count speed over the
 *  band is the counts' angle over its time to one count at each end
 *  (2 q / T_band, q = 2 pi / cpr mechanical), squared through the fit the
 *  per-sample speed's count noise (q / tau over the mean speed)^2, and the
 *  voltage the dead time makes with the current's sign unknown at zero
 *  current (4/3 vbus T_dead / T along an axis) over the band's mean |v|. */
float mc_comm_flux_band_res_f32(uint32_t cpr, float t_band_s, float tau_s, float w_m_rad_s,
                                float v_dead_v, float v_mag_v);

/** MC_COMM_ERR_FLUX_SPEEDS (mc_commission.h) when the two bands' fits
 *  (hi, lo) give fluxes further apart than tol (relative), or either fit is
 *  empty or not positive; 0 when they agree. Fills *out either way. */
uint32_t mc_comm_flux_check_f32(const mc_ident_line_f32_t *hi, const mc_ident_line_f32_t *lo,
                                float tol, mc_comm_flux_chk_t *out);

/* ------------------------------------------------------- mechanics */
/** The tolerances of the J/B checks (README.md "Checks of the flux step"):
 *  the coast's middle third on the chord of its outer two within
 *  MC_COMM_MECH_FIT_TOL of its fall, and the spin-up's two halves'
 *  inertias within MC_COMM_MECH_J_TOL of each other (a viscous rotor gives
 *  the same; the library's within 1 %), each plus the viscous decay's own
 *  bend and the part the count resolution allows. */
#define MC_COMM_MECH_FIT_TOL 0.05f
#define MC_COMM_MECH_J_TOL   0.02f

typedef struct {
    float j_lo_kgm2; /**< J from the spin-up's first half (lower speeds) and the coast */
    float j_hi_kgm2; /**< ... second half */
    float j_dev;     /**< |j_lo - j_hi| / their mean */
    float j_tol;     /**< MC_COMM_MECH_J_TOL plus the count resolution's part */
    float fit_rms;   /**< the coast's middle third off the chord / its fall */
    float fit_tol;   /**< MC_COMM_MECH_FIT_TOL plus the bend's and the counts' part */
} mc_comm_mech_chk_t;

/** The J/B checks on the spin-up's (motor torque tq_nm) and the coast's
 *  speed records (mechanical rad/s, dt each; cpr counts a turn, the
 *  resolution). The spin-up's four quarters give two halves (their mean
 *  speeds and accelerations), the coast's three thirds its B/J (chord) and
 *  its straightness (the middle third against the chord).
 *  MC_COMM_ERR_MECH_FIT when the coast is not a line within fit_tol (a
 *  load that changes, a speed reading that jumps) or a record is too short
 *  (fewer than 8 spin-up or 6 coast blocks); MC_COMM_ERR_MECH_SPIN_COAST
 *  when J from the spin-up's first half and from its second (each with the
 *  coast's B/J) differ by more than j_tol: the friction is not viscous
 *  (Coulomb, a load) and the J and B of the viscous model would be off;
 *  0 when consistent. Fills *out either way. */
uint32_t mc_comm_mech_check_f32(const mc_comm_blk_t *spin, const mc_comm_blk_t *coast, float dt_s,
                                uint32_t cpr, float tq_nm, mc_comm_mech_chk_t *out);

#ifdef __cplusplus
}
#endif

#endif /* MC_COMM_CHECK_H */
