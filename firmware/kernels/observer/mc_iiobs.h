/**
 * @file mc_iiobs.h
 * @brief Immersion-and-invariance observer of speed and load torque from a
 *        measured angle and a known motor torque (paper 002, Section IV,
 *        Prop. 5, eq. (30)), with the dynamic scaling r. float32.
 *
 * Mechanics (the paper's (23), n_P = 1: theta is the shaft angle):
 *     theta' = omega,   J omega' = tau - f omega - tau_L,  tau_L constant.
 * Outputs h = [sin theta, cos theta] (24), unknown eta = [omega, tau_L/J].
 *
 * Observer (30), state (h_hat, xi, r):
 *     h_hat' = [h2, -h1]^T eta1_hat - rho1(r) (h_hat - h)
 *     xi'    = [tau/J - (f/J) eta1_hat - eta2_hat, 0]^T
 *              + (eta1_hat (1 - h^T h_hat) + rho1(r) rho2) delta
 *     r'     = -(k1/4)(r - 1) + (k2 k5^2 / (2 k1)) r (1 - h^T h_hat)^2,  r(0) >= 1
 *     eta_hat = xi + rho2 delta,   rho2 = h1 h_hat2 - h_hat1 h2
 *     rho1(r) = k4 + (1/2)(k2 k5^2 / k1 + k3^2) r^2
 * Constants (26), (28), (29), computed by init:
 *     k1 = (a1 - sqrt(a1^2 - 4 a2))/2,  delta = [a1 - f/J, -a2],  k2 = |delta|^2,
 *     T diagonalises A* = [[-a1, -1], [a2, 0]] (columns of T^-1: unit
 *     eigenvectors), k3 = ||T^-1||, k5 = ||T|| ||T^-1|| (2-norms).
 * Error dynamics: z = xi - eta + beta, z' = A* z + (Delta Psi) z (38), so the
 * estimate converges like exp(-k1 t) once h_hat has locked (exponential,
 * global on the cylinder S x R).
 *
 * Departures from the printed paper (re-derived; see mc_iiobs.c):
 * 1. eta2 is tau_L/J (the paper prints tau/J in the definition of eta and
 *    in Prop. 5); with tau/J, (25) does not follow from (23).
 * 2. k5^2 and k3^2 where the paper writes k5 (in r' and rho1) and k3 (in
 *    rho1): the bounds ||T Delta Psi T^-1||^2 <= k2 k5^2 (1 - h^T h_hat)^2 and
 *    ||Psi T^-1||^2 <= k3^2 need the squares (k5 >= 1, so this only makes
 *    the scaling more conservative).
 * 3. (27) a1 > max{2 sqrt(a2), 4} does not give k1 > 2, which the proof
 *    uses after (42) (e.g. a1 = 10, a2 = 1 gives k1 = 0.10). k1 > 2 holds
 *    iff a2 > 2 a1 - 4 (with a1 > 4); init checks (27) and this separately
 *    (MC_IIOBS_ERR_GAINS and MC_IIOBS_ERR_K1). With 2 sqrt(a2) < a1 the
 *    admissible band is 2 a1 - 4 < a2 < a1^2 / 4 (e.g. a1 = 6, a2 = 8.5).
 * 4. Time unit. The conditions (27) and k1 > 2 come from Young's
 *    inequalities with unit weights and are not dimensionless (k2 adds
 *    1/s^2 to 1/s^4). The kernel therefore runs (30) in the scaled time
 *    s = t / t_unit_s: a1, a2, k4 are per t_unit (omega_s = omega t_unit,
 *    tau/J -> tau t_unit^2 / J, f/J -> f t_unit / J). The estimation poles
 *    are then at lambda_i / t_unit_s in real time: t_unit_s sets the speed
 *    of the observer, a1 and a2 its shape.
 * 5. Discretisation: h_hat by backward Euler (rho1 is large: rho1 / k1 is
 *    about 2000 for a1 = 6, a2 = 8.5, so h_hat is stiff); in xi the term
 *    -grad_h_hat(beta) h_hat' is replaced by the exact increment of beta
 *    due to the h_hat update, so the invariance of the manifold z = 0 does
 *    not depend on the stiff h_hat step; the rest by forward Euler (init
 *    requires |lambda_max| dt / t_unit <= 0.1 and f dt / J <= 0.1).
 *
 * Non-finite input: refused, sticky MC_IIOBS_ERR_NAN_INPUT. r is clamped
 * to r_max; reaching it raises the sticky MC_IIOBS_ERR_R_MAX (the angle or
 * torque input is inconsistent with the model). No heap, no globals, no I/O.
 */
#ifndef MC_IIOBS_H
#define MC_IIOBS_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MC_IIOBS_ERR_NONE      0u
#define MC_IIOBS_ERR_NULL      (1u << 0) /**< a required pointer is NULL */
#define MC_IIOBS_ERR_MECH      (1u << 1) /**< J <= 0, f < 0 or not finite */
#define MC_IIOBS_ERR_GAINS     (1u << 2) /**< a1, a2 <= 0 / not finite, or (27) broken */
#define MC_IIOBS_ERR_K1        (1u << 3) /**< a2 <= 2 a1 - 4: k1 <= 2 (proof of (42) fails) */
#define MC_IIOBS_ERR_K4        (1u << 4) /**< k4 <= 0 or not finite */
#define MC_IIOBS_ERR_TIME      (1u << 5) /**< t_unit or dt <= 0 / not finite, or step too long */
#define MC_IIOBS_ERR_RMAX_CFG  (1u << 6) /**< r_max <= 1 or not finite */
#define MC_IIOBS_ERR_NAN_INPUT (1u << 7) /**< sticky: non-finite input refused */
#define MC_IIOBS_ERR_R_MAX     (1u << 8) /**< sticky: the scaling r reached r_max */

/** Largest |lambda_max| dt / t_unit and f dt / J accepted. */
#define MC_IIOBS_MAX_STEP 0.1f

typedef struct {
    float j_kgm2;    /**< inertia [kg m^2], > 0 */
    float f_nms_rad; /**< viscous friction [N m s/rad], >= 0 */
    float a1;        /**< pole-shape gain, per t_unit (dimensionless), see (27) */
    float a2;        /**< pole-shape gain, per t_unit^2 (dimensionless) */
    float k4;        /**< injection gain per t_unit (dimensionless), > 0; small = less noise */
    float t_unit_s;  /**< time unit of a1, a2, k4 [s], > 0 (poles at lambda_i / t_unit) */
    float dt_s;      /**< step period [s], > 0 */
    float r_max;     /**< clamp of the dynamic scaling, > 1 (e.g. 100) */
} mc_iiobs_f32_cfg_t;

/** Constants derived by init (scaled-time units). */
typedef struct {
    float k1, k2, k3, k5;   /**< (26), (29) */
    float lambda1, lambda2; /**< eigenvalues of A*, lambda2 < lambda1 = -k1 < 0 */
    float delta1, delta2;   /**< delta of (26) */
    float c_r;              /**< k2 k5^2 / (2 k1) */
    float c_rho;            /**< (k2 k5^2 / k1 + k3^2) / 2 */
} mc_iiobs_f32_const_t;

typedef struct {
    mc_iiobs_f32_cfg_t cfg;
    mc_iiobs_f32_const_t k;
    float dts;          /**< dt / t_unit */
    float f_s;          /**< f t_unit / J */
    float tau_s_per_nm; /**< t_unit^2 / J [1/(N m)] */
    float hh1, hh2;     /**< h_hat */
    float h1, h2;       /**< last measured h */
    float xi1, xi2;
    float r;          /**< dynamic scaling, [1, r_max] */
    float eta1, eta2; /**< eta_hat (scaled) */
    bool primed;      /**< an angle has been seen */
    uint32_t flags;   /**< sticky MC_IIOBS_ERR_* */
} mc_iiobs_f32_t;

/** Validate cfg, compute the constants, initialise (estimates 0, r = 1,
 *  h_hat set from the first angle). On error st is not written. */
uint32_t mc_iiobs_f32_init(mc_iiobs_f32_t *st, const mc_iiobs_f32_cfg_t *cfg);

/** Restart with h_hat = h(theta), eta_hat = (omega, tau_L/J), r = 1, flags
 *  cleared. Non-finite: MC_IIOBS_ERR_NAN_INPUT, nothing changed. */
uint32_t mc_iiobs_f32_reset(mc_iiobs_f32_t *st, float theta_m_rad, float omega_m_rad_s,
                            float tau_load_nm);

/** One step: theta_m the shaft angle sampled now [rad], tau_nm the motor
 *  torque over the period that just ended [N m]. Returns the bits raised. */
uint32_t mc_iiobs_f32_step(mc_iiobs_f32_t *st, float theta_m_rad, float tau_nm);

/** Speed estimate [rad/s]. */
float mc_iiobs_f32_get_omega_m_rad_s(const mc_iiobs_f32_t *st);

/** Load-torque estimate [N m] (opposing positive rotation). */
float mc_iiobs_f32_get_tau_load_nm(const mc_iiobs_f32_t *st);

#ifdef __cplusplus
}
#endif

#endif /* MC_IIOBS_H */
