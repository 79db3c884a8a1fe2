/**
 * @file mc_pi2d.h
 * @brief Output-feedback PI^2D speed-tracking controller for the non-salient
 *        PMSM (float32), after Loria, Espinosa-Perez, Avila-Becerril, "A
 *        simple PI^2D output feedback controller for the PMSM" (paper 000),
 *        eqs. (6), (8)-(12), (14), (35), in physical units; plus a gain
 *        certificate (the proof's sufficient conditions (34), (38)).
 *
 * Measured: dq currents and the rotor position. Not measured: the speed
 * (replaced by the dirty derivative theta_f of the position error) and the
 * load torque (estimated by the adaptive term nu).
 *
 * Plant (physical units; x1 = i_d, x2 = i_q [A], x3 = omega_m [rad/s],
 * x4 = theta_m [rad], mechanical speed and angle, p pole pairs):
 *     L dx1/dt = -R x1 + p L x2 x3 + u1
 *     L dx2/dt = -R x2 - p L x1 x3 - ke x3 + u2
 *     J dx3/dt = kt x2 - tau_L
 *       dx4/dt = x3
 * ke = back-EMF constant [V s/rad] (p * flux for the dq model), kt = torque
 * constant [N m/A] (1.5 p flux, amplitude-invariant dq). With R = L = p =
 * J = 1 this is exactly the paper's (1)-(4) with gamma = ke, sigma = kt and
 * the paper's tau_L = tau_L / J.
 *
 * The law (re-derived; sigma := kt/J, e_i = x_i - x_i*):
 *     e4      = theta_m - theta_ref               (theta_ref: the integrated
 *                                                  reference position, input)
 *     theta_f = b s/(s+a) e4                      (11)-(12), mc_ddiff
 *     v3      = -kp e4 - kd theta_f               (9)
 *     dnu/dt  = -J ki (e4 - theta_f)              (10), nu in N m (nu/J is
 *                                                  the paper's nu)
 *     x2*     = (nu + J (alpha_ref + v3)) / kt    (8)
 *     rho     = (dnu/dt + J jerk_ref + J a kd theta_f) / kt
 *     v2      = -eps sigma (e4 - theta_f)         (35)
 *     u1 = R x1* + L d(x1*)/dt - p L x2 omega_ref - (L k1 - R) e1          (6)
 *     u2 = ke omega_ref + p L x1 omega_ref + R x2* + L (rho + v2)
 *          - (L k2 - R) e2                                              (14)
 * k1, k2 [1/s] are the CLOSED-LOOP current-error rates (the paper's
 * k1 = k1' + 1, k2 = k2' + 1 in normalised units: the gains it prints,
 * "k1 = 4, k2 = 75", are these). With R = L = p = J = 1 every line reduces
 * to the paper's normalised equation.
 *
 * Closed-loop errors (re-derived; z = nu~/J - (ki/eps) e4, kp' = kp - ki/eps,
 * nu~ = nu - tau_L):
 *     de1/dt = -k1 e1 + p x2 e3                                     (20)
 *     de2/dt = -k2 e2 + Delta e3 + v2                               (21)
 *     de3/dt = sigma e2 - kp' e4 - kd theta_f + z                   (22)
 *     de4/dt = e3                                                   (23)
 *     dtheta_f/dt = -a theta_f + b e3                               (24)
 *     dz/dt  = -ki (e4 - theta_f) - (ki/eps) e3                     (25)
 *     Delta  = (kp + b kd)/sigma - ke/L - p x1
 * DEPARTURE from the printed paper: its Delta = (kp + b kd)/sigma +
 * (gamma - x1) has a sign slip on gamma; expanding (2) with (14) gives
 * -gamma (the back-EMF of the speed error opposes e2). The controller does
 * not use Delta; tests/unit/pi2d checks (21) with the corrected sign.
 *
 * Units: a [1/s], b [1], kp [1/s^2], kd [1/s^2], ki [1/s^3], eps [1/s];
 * theta_f is in rad ((a/b) theta_f ~ speed error). The paper's rule
 * 0 < ki < eps << 1 is stated in its normalised time, whose base is
 * T = L/R (it sets R = L = 1). In physical units it reads
 * 0 < ki T^2 < eps (identical to the paper's when L = R = 1); init
 * enforces that, and kp' = kp - ki/eps > 0 (needed by the proof's V2).
 *
 * Limits and anti-windup (the paper has none; a drive needs them):
 * - x2* is clamped to +-iq_max_a; while clamped, rho (the derivative of the
 *   unclamped x2*) is replaced by 0, the derivative of the clamped value;
 * - the voltage vector (u1, u2) is scaled down to |u| <= v_max_v;
 * - nu integrates only when neither limit acted in this step (conditional
 *   integration), and is clamped to +-nu_max_nm.
 * With limits that do not act the law is exactly the one above.
 *
 * Discretisation: the kernel is sampled at dt_s; theta_f by Tustin
 * (mc_ddiff); nu by forward Euler (the nu used in step k is nu[k], and
 * dnu/dt[k] enters rho at once, as in the continuous law). The nu sum is
 * compensated (Kahan): with the paper's ki the increment per step is of
 * order 1e-7 against nu ~ 1e-2 (ulp 2e-9), so a plain float sum rounds
 * away about 1 % of each increment; over 1e5 steps that
 * bias dominated the error against the continuous law (measured 3e-5 on
 * nu at 10 kHz, 6e-5 at 20 kHz; with the compensation it follows 1/rate).
 * Needs -ffp-contract=off and no -ffast-math (the project's flags).
 *
 * Precision of e4: theta_m and theta_ref enter only as their difference;
 * pass them with a common offset removed (whole turns), so that their float
 * rounding (ulp of their size) stays far below the encoder resolution.
 *
 * No heap, no globals, no I/O.
 */
#ifndef MC_PI2D_H
#define MC_PI2D_H

#include <stdbool.h>
#include <stdint.h>

#include "filters/mc_ddiff.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_PI2D_ERR_NONE   0u
#define MC_PI2D_ERR_NULL   (1u << 0) /**< a required pointer is NULL */
#define MC_PI2D_ERR_PLANT  (1u << 1) /**< R, L, kt, J <= 0, ke < 0, pole_pairs 0, or not finite */
#define MC_PI2D_ERR_K12    (1u << 2) /**< k1 or k2 <= 0 or not finite */
#define MC_PI2D_ERR_KPKD   (1u << 3) /**< kp or kd <= 0 or not finite */
#define MC_PI2D_ERR_FILTER (1u << 4) /**< a or b <= 0 or not finite */
#define MC_PI2D_ERR_KI_EPS \
    (1u << 5) /**< ki <= 0, eps <= 0, or ki (L/R)^2 >= eps (paper: 0 < ki < eps) */
#define MC_PI2D_ERR_KP_PRIME (1u << 6) /**< kp' = kp - ki/eps <= 0 */
#define MC_PI2D_ERR_DT       (1u << 7) /**< dt_s <= 0 or not finite */
#define MC_PI2D_ERR_LIMITS   (1u << 8) /**< iq_max_a, v_max_v or nu_max_nm <= 0 or not finite */
#define MC_PI2D_ERR_NAN_INPUT \
    (1u << 9) /**< sticky: a step got a non-finite input (zero voltage out) */
#define MC_PI2D_ERR_ENVELOPE \
    (1u << 10) /**< certificate: envelope bounds out of order / not finite */

/** Configuration: plant constants, gains, limits, sample period. */
typedef struct {
    float r_ohm;         /**< stator resistance R [ohm], > 0 */
    float l_h;           /**< stator inductance L (Ld = Lq) [H], > 0 */
    uint32_t pole_pairs; /**< p, >= 1 */
    float ke_v_s_rad;    /**< back-EMF constant [V/(rad/s) mech.], >= 0 */
    float kt_nm_a;       /**< torque constant [N m/A], > 0 */
    float j_kgm2;        /**< inertia [kg m^2], > 0 */
    float k1_per_s;      /**< closed-loop d-current error rate k1 [1/s], > 0 */
    float k2_per_s;      /**< closed-loop q-current error rate k2 [1/s], > 0 */
    float kp_per_s2;     /**< position gain kp [1/s^2], > 0 */
    float kd_per_s2;     /**< theta_f gain kd [1/s^2], > 0 */
    float ki_per_s3;     /**< load-adaptation gain ki [1/s^3], 0 < ki (L/R)^2 < eps */
    float a_per_s;       /**< dirty-derivative pole a [1/s], > 0 */
    float b;             /**< dirty-derivative gain b [1], > 0 */
    float eps_per_s;     /**< epsilon [1/s] of the proof and of v2, > 0 */
    float dt_s;          /**< sample period [s], > 0 */
    float iq_max_a;      /**< clamp of x2* [A], > 0 */
    float v_max_v;       /**< clamp of |(u1, u2)| [V], > 0 */
    float nu_max_nm;     /**< clamp of nu [N m], > 0 */
} mc_pi2d_f32_cfg_t;

/** Inputs of one step. The positions only enter as their difference, so the
 *  caller may subtract the same offset from both (e.g. whole turns) to keep
 *  them small. */
typedef struct {
    float id_a;             /**< measured x1 [A] */
    float iq_a;             /**< measured x2 [A] */
    float theta_m_rad;      /**< measured mechanical position x4 [rad] (unwrapped) */
    float theta_ref_rad;    /**< integrated reference position x4* [rad] */
    float omega_ref_rad_s;  /**< reference speed x3* [rad/s] */
    float alpha_ref_rad_s2; /**< d(x3*)/dt [rad/s^2] */
    float jerk_ref_rad_s3;  /**< d2(x3*)/dt2 [rad/s^3] */
    float id_ref_a;         /**< x1* [A] (0 for field orientation) */
    float did_ref_a_s;      /**< d(x1*)/dt [A/s] */
} mc_pi2d_f32_in_t;

/** Outputs of one step (also the telemetry of the law). */
typedef struct {
    float vd_v, vq_v;  /**< u1, u2 after the voltage limit [V] */
    float id_ref_a;    /**< x1* [A] */
    float iq_ref_a;    /**< x2* after its clamp [A] */
    float e4_rad;      /**< position error [rad] */
    float theta_f_rad; /**< dirty derivative of e4 [rad] */
    float nu_nm;       /**< load estimate used in this step [N m] */
    float dnu_nm_s;    /**< its rate in this step (0 when frozen) [N m/s] */
    float rho_a_s;     /**< implementable part of d(x2*)/dt [A/s] */
    float v2_a_s;      /**< stabilising term (35) [A/s] */
    bool iq_limited;   /**< x2* was clamped */
    bool v_limited;    /**< the voltage vector was scaled down */
} mc_pi2d_f32_out_t;

/** Controller instance. */
typedef struct {
    mc_pi2d_f32_cfg_t cfg; /**< copy of the validated config */
    float sigma;           /**< kt/J [N m/(A kg m^2)], derived */
    float r_minus_lk1;     /**< L k1 - R [V/A], derived */
    float r_minus_lk2;     /**< L k2 - R [V/A], derived */
    float pl;              /**< p L [H], derived */
    float l_k1;            /**< L k1 [V/A], derived */
    float l_k2;            /**< L k2 [V/A], derived */
    float inv_kt;          /**< 1/kt [A/(N m)], derived */
    float neg_j_ki;        /**< -(J ki) [N m/(rad s)], derived */
    float a_kd;            /**< a kd [1/s^3], derived */
    float neg_eps_sigma;   /**< -(eps sigma), derived: v2 = neg_eps_sigma (e4 - theta_f) */
    float v_lim_sq;        /**< the largest float m with sqrt(m) <= v_max_v:
                                  |u| > v_max_v exactly when u1^2 + u2^2 > v_lim_sq */
    mc_ddiff_f32_t dd;     /**< dirty-derivative filter of e4 */
    float nu_nm;           /**< load estimate nu [N m] */
    float nu_comp_nm;      /**< compensation of the nu sum (Kahan): the low
                                  part the float sum lost [N m] */
    uint32_t flags;        /**< sticky MC_PI2D_ERR_NAN_INPUT */
} mc_pi2d_f32_t;

/** Validate cfg and initialise st (q_c = 0, nu = 0). Returns the OR of the
 *  MC_PI2D_ERR_* rules broken; on error st is not written. */
uint32_t mc_pi2d_f32_init(mc_pi2d_f32_t *st, const mc_pi2d_f32_cfg_t *cfg);

/** Set q_c and nu (nu clamped to +-nu_max_nm) and clear the sticky flags.
 *  Non-finite values: MC_PI2D_ERR_NAN_INPUT returned, st not written. */
uint32_t mc_pi2d_f32_reset(mc_pi2d_f32_t *st, float qc0_rad, float nu0_nm);

/** Set the clamp of x2* (the q current the law asks for) at run time, e.g.
 *  to a current limit lowered while it runs. Returns 0, or
 *  MC_PI2D_ERR_LIMITS (nothing changes) for a value <= 0 or not finite. */
uint32_t mc_pi2d_f32_set_iq_max(mc_pi2d_f32_t *st, float iq_max_a);

/** One control step. Returns 0, or MC_PI2D_ERR_NAN_INPUT when an input is not
 *  finite (or so large that x2*, rho or u1^2 + u2^2 overflows): then *out is
 *  all zero (zero voltage), the state is unchanged and the flag is sticky.
 *  out is the only place the outputs are written (the kernel keeps no copy);
 *  a NULL st, in or out gives MC_PI2D_ERR_NULL and nothing is written.
 *
 *  Cost: the step computes into locals and checks once, at the end, that
 *  x2* (before its clamp), rho (before it is zeroed) and u1^2 + u2^2 are
 *  finite; every input reaches one of them through a product with a
 *  non-zero constant or a sum (inf - inf and 0 inf are NaN), so a
 *  non-finite input is caught there. The voltage limit compares
 *  u1^2 + u2^2 with v_lim_sq (a square root only when it acts), the same
 *  decision as sqrt(u1^2 + u2^2) > v_max_v for every float. */
uint32_t mc_pi2d_f32_step(mc_pi2d_f32_t *st, const mc_pi2d_f32_in_t *in, mc_pi2d_f32_out_t *out);

/* ------------------------------------------------------------------------ */
/* Gain certificate                                                          */
/* ------------------------------------------------------------------------ */

/** Operating envelope over which the sufficient conditions are evaluated. */
typedef struct {
    float id_min_a;     /**< lower bound of x1 [A] */
    float id_max_a;     /**< upper bound of x1 [A], >= id_min_a */
    float iq_abs_max_a; /**< bound of |x2| [A], >= 0 */
} mc_pi2d_envelope_t;

/**
 * The proof's sufficient conditions, each as lhs >= rhs with
 * margin = lhs - rhs (holds iff margin >= 0), in SI units of the config
 * (V1 = (e1^2 + e2^2)/2 weighs A^2 against (rad/s)^2 with weight 1, as the
 * paper does in its units; with R = L = p = J = 1 this is the paper's V).
 *
 * c34: re-derived (34), the mechanical block N >= 0:
 *      kd a/b >= eps [2 kd + a^2/(b-1) + (kp' - kd)^2/kp'], needs b > 1.
 *      The paper prints a^2/b; the Schur complement of its own matrix gives
 *      a^2/b' with b' = b - 1 (slightly stronger). c34_printed keeps a^2/b.
 * c38: re-derived electrical condition. After (34) the derivative is
 *      dV/dt <= -k1 e1^2 - k2 e2^2 - (eps b'/2) e3^2 + p x2 e1 e3
 *               + (Delta + sigma) e2 e3 - ...
 *      (the paper's matrix puts x2 between e1 and e2, but the coupling is
 *      x2 e1 e3, and it counts eps b' e3^2 twice). Negative semidefinite iff
 *          2 eps b' >= (p x2)^2/k1 + (Delta + sigma)^2/k2,
 *      evaluated at the worst x1, x2 of the envelope (Delta is affine in x1,
 *      so the worst case is an end of [id_min, id_max]). lhs = 2 eps b',
 *      rhs = the sum; k2_min is the smallest k2 meeting it (FLT_MAX if
 *      none: 2 eps b' <= (p x2)^2/k1).
 * c38_printed: the printed (38) with the printed Delta (+gamma):
 *      k2 >= (Delta_p + sigma)^2/(eps b') + x2^2/k1; lhs = k2.
 */
typedef struct {
    float c34_lhs, c34_rhs, c34_margin;
    float c34_printed_rhs, c34_printed_margin;
    float c38_lhs, c38_rhs, c38_margin;
    float c38_k2_min_per_s;
    float c38_printed_rhs, c38_printed_margin;
    float delta_sigma_max; /**< max |Delta + sigma| over the envelope */
    float kp_prime_per_s2; /**< kp - ki/eps */
    bool holds;            /**< c34 and c38 (re-derived) both hold */
} mc_pi2d_cert_t;

/** Evaluate the certificate for cfg over env. Returns MC_PI2D_ERR_NONE, the
 *  init error bits of cfg, MC_PI2D_ERR_ENVELOPE, or MC_PI2D_ERR_NULL; *out
 *  is written only on success. */
uint32_t mc_pi2d_f32_certify(const mc_pi2d_f32_cfg_t *cfg, const mc_pi2d_envelope_t *env,
                             mc_pi2d_cert_t *out);

#ifdef __cplusplus
}
#endif

#endif /* MC_PI2D_H */
