/**
 * @file mc_csmc.h
 * @brief Continuous sliding-mode position control of the two-phase PM
 *        stepper with conditional integrators / servocompensators
 *        (paper 001, Seshagiri and Khalil), and the ideal SMC baseline.
 *
 * Plant in the rotor frame (paper eq. (2), see csmc/mc_stepper_dq.h):
 *     x1 = i_d, x2 = i_q, x3 = w, x4 = phi; u1 = v_d, u2 = v_q
 *     k1 = R/L, k2 = K_m/L, k3 = K_m/J, k4 = B/J, k5 = N_r, k6 = 1/L,
 *     d0 = tau_L/J;  theta = (k1, k2, k6) unknown (R, L uncertain).
 * Errors: e1 = i_d - I_dd, e2 = phi - phi_d (and e2', e2'').
 *
 * Sliding variables (eq. (3) / (10)); the "*" part is the ideal-SMC surface:
 *     s1 = K0^1 sigma1 + e1
 *     s2 = K0^2 sigma2 + k1^2 e2 + k2^2 e2' + e2''
 * sigma_i from a conditional integrator (4) or servocompensator (9)
 * (csmc/mc_csvc.h), or absent (order 0: s_i = s_i*).
 *
 * Laws (the switching function psi is sat(s/mu) or, for ideal SMC, sgn(s)):
 *   MC_CSMC_LAW_MODEL, eq. (5): u_i = (-F^_i - beta_i psi_i)/a^_ii with
 *     a^_11 = 1/L^, a^_22 = k3/L^, and (re-derived; see below)
 *       F^_1 = -(R^/L^) x1 + k5 x2 x3 - I_dd'
 *       F^_2 = G - k3 (R^/L^) x2 - k3 (K_m/L^) x3,
 *       G    = k1^2 e2' + k2^2 e2'' - phi_d''' - k4 (k3 x2 - k4 x3 - d0)
 *              - k3 k5 x1 x3
 *       beta_1 = [dR |x1| + dL |k5 x2 x3 - I_dd'| + q1] / L^
 *       beta_2 = [dR k3 |x2| + dL |G| + q2] / L^
 *     so that
 *       u1 = R^ x1 - L^ (k5 x2 x3 - I_dd') - (dR |x1| + dL |..| + q1) psi1
 *       u2 = R^ x2 + K_m x3 - (L^/k3) G - (dR |x2| + (dL/k3) |G| + q2/k3) psi2
 *   MC_CSMC_LAW_CONST, eqs. (7)/(11): u_i = -M_i psi_i (no model; e2', e2''
 *     may come from the high-gain observer, observer/mc_hgo.h).
 * Output clamp: each u_i is limited to [-v_limit_v, v_limit_v].
 *
 * Departures from the printed paper (re-derived; each checked in tests):
 * - rho_i: the paper writes sup |theta3^ Delta_i / theta3^|; the bound that
 *   makes s s' < 0 is sup |theta3^ Delta_i / theta3| (true theta3 = 1/L
 *   in the denominator). Working it out, theta3^ Delta_1/theta3 =
 *   [(R^ - R) x1 + (L - L^)(k5 x2 x3 - I_dd')]/L^ and
 *   theta3^ Delta_2/theta3 = [(L - L^) G - (R - R^) k3 x2]/L^ (K_m is
 *   known, its terms cancel).
 * - dR = max(R^M - R^, R^ - R^m), dL = max(L^M - L^, L^ - L^m): the paper's
 *   (R^M - R^) and (L^M - L^) are these only when the nominal value is the
 *   centre of the interval (as in its example: 20 in [19, 21], 35 in [30, 40]).
 * - The I_dd' and phi_d''' terms, zero in the paper's example (constant
 *   references, so the paper drops them from beta), are kept.
 * - q_i are given in the paper's form (beta_i = [.. + q_i]/L^): the paper
 *   takes q_i = 2.1 k0^i mu_i L^M, which covers the |k0 (-k0 sigma +
 *   mu sat)| <= 2 k0 mu term of s' that F^ does not cancel; q1 [V],
 *   q2 [rad H/s^3] (the units of L^ beta_2).
 *
 * Timing (sampled data): mc_csmc_f32_step() computes u from the inputs at
 * t_k and then advances sigma over one period with s held (mc_csvc.h).
 */
#ifndef MC_CSMC_H
#define MC_CSMC_H

#include <stdint.h>

#include "csmc/mc_csvc.h"
#include "observer/mc_hgo.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_CSMC_ERR_NONE 0u
#define MC_CSMC_ERR_NULL (1u << 0) /**< a required pointer is NULL */
#define MC_CSMC_ERR_LAW  (1u << 1) /**< unknown law or switching function */
#define MC_CSMC_ERR_SURFACE \
    (1u << 2) /**< k1^2, k2^2 <= 0 or not finite (x^2 + k2 x + k1 not Hurwitz) */
#define MC_CSMC_ERR_MU      (1u << 3) /**< mu_1 or mu_2 <= 0 or not finite */
#define MC_CSMC_ERR_SIGMA_1 (1u << 4) /**< d-axis integrator/servocompensator rejected */
#define MC_CSMC_ERR_SIGMA_2 (1u << 5) /**< q-axis integrator/servocompensator rejected */
#define MC_CSMC_ERR_GAIN_M  (1u << 6) /**< LAW_CONST: M_i <= 0 or not finite */
#define MC_CSMC_ERR_MODEL   (1u << 7) /**< model: K_m, J <= 0, B < 0, N_r = 0, tau_L not finite */
#define MC_CSMC_ERR_BOUNDS \
    (1u << 8) /**< model: not 0 < R^m <= R^ <= R^M, same for L, or q_i <= 0 */
#define MC_CSMC_ERR_VLIMIT (1u << 9)  /**< v_limit_v <= 0 or not finite */
#define MC_CSMC_ERR_DT     (1u << 10) /**< dt_s <= 0 or not finite */
#define MC_CSMC_ERR_NAN_INPUT \
    (1u << 11) /**< sticky: a step got a non-finite input and was refused */
#define MC_CSMC_ERR_HGO \
    (1u << 12) /**< combined step: observer config rejected, or its dt_s != the law's */

typedef enum {
    MC_CSMC_LAW_MODEL = 0, /**< eq. (5): nominal F^ and beta functions */
    MC_CSMC_LAW_CONST = 1  /**< eq. (7)/(11): u = -M psi */
} mc_csmc_law_t;

typedef enum {
    MC_CSMC_SW_SAT = 0, /**< continuous SMC: sat(s/mu) */
    MC_CSMC_SW_SGN = 1  /**< ideal SMC: sgn(s) (sgn(0) = 0) */
} mc_csmc_sw_t;

/** Motor constants and parameter bounds (law MODEL, and e2'' from states). */
typedef struct {
    float km_nm_a;        /**< torque / back-EMF constant K_m [N m/A] = [V s/rad], > 0 */
    float j_kgm2;         /**< inertia [kg m^2], > 0 */
    float b_nms_rad;      /**< viscous friction [N m s/rad], >= 0 */
    uint32_t rotor_teeth; /**< N_r, >= 1 */
    float tau_load_nm;    /**< load torque known to the law [N m] */
    float r_nom_ohm;      /**< R^ */
    float r_min_ohm;      /**< R^m, > 0 */
    float r_max_ohm;      /**< R^M */
    float l_nom_h;        /**< L^ */
    float l_min_h;        /**< L^m, > 0 */
    float l_max_h;        /**< L^M */
    float q1_v;           /**< q1 [V], > 0 (paper: 2.1 k0^1 mu1 L^M) */
    float q2_radh_s3;     /**< q2 [rad H/s^3], > 0 (paper: 2.1 k0^2 mu2 L^M) */
} mc_csmc_f32_model_t;

typedef struct {
    mc_csmc_law_t law;
    mc_csmc_sw_t sw;
    float k1_per_s2;            /**< k1^2 [1/s^2], > 0 */
    float k2_per_s;             /**< k2^2 [1/s], > 0 */
    float mu1_a;                /**< boundary layer of s1 [A], > 0 */
    float mu2_rad_s2;           /**< boundary layer of s2 [rad/s^2], > 0 */
    mc_csvc_f32_model_t sigma1; /**< d axis: order 0 = none, else integrator/servocompensator */
    mc_csvc_f32_model_t sigma2; /**< q axis: as sigma1 */
    float m1_v;                 /**< LAW_CONST: M1 [V] */
    float m2_v;                 /**< LAW_CONST: M2 [V] */
    mc_csmc_f32_model_t model;  /**< LAW_MODEL only */
    float v_limit_v;            /**< output clamp |u_i| <= v_limit_v [V], > 0 */
    float dt_s;                 /**< control period [s], > 0 */
} mc_csmc_f32_cfg_t;

/** Inputs at one sample. */
typedef struct {
    float e1_a;            /**< i_d - I_dd [A] */
    float e2_rad;          /**< phi - phi_d [rad] */
    float de2_rad_s;       /**< e2' (measured or HGO z2) [rad/s] */
    float dde2_rad_s2;     /**< e2'' (from states or HGO z3) [rad/s^2] */
    float i_d_a;           /**< x1 (LAW_MODEL only) [A] */
    float i_q_a;           /**< x2 (LAW_MODEL only) [A] */
    float omega_m_rad_s;   /**< x3 (LAW_MODEL only) [rad/s] */
    float di_dd_a_s;       /**< I_dd' (LAW_MODEL only) [A/s] */
    float dddphi_d_rad_s3; /**< phi_d''' (LAW_MODEL only) [rad/s^3] */
} mc_csmc_f32_in_t;

typedef struct {
    float v_d_v;     /**< u1 [V] */
    float v_q_v;     /**< u2 [V] */
    float s1_a;      /**< s1 [A] */
    float s2_rad_s2; /**< s2 [rad/s^2] */
} mc_csmc_f32_out_t;

typedef struct {
    mc_csmc_law_t law;
    mc_csmc_sw_t sw;
    float k1_per_s2, k2_per_s, mu1_a, mu2_rad_s2, m1_v, m2_v, v_limit_v;
    mc_csmc_f32_model_t model;
    /* derived (LAW_MODEL): */
    float k3, k4, d0, dr_ohm, dl_h, inv_k3;
    /* derived (all laws): */
    float inv_mu1, inv_mu2;               /**< 1/mu_i */
    float neg_m1_per_mu1, neg_m2_per_mu2; /**< -M_i/mu_i (LAW_CONST) */
    uint32_t const_sat;                   /**< LAW_CONST with SW_SAT (the step's straight path) */
    uint32_t fast_kind2;                  /**< mc_csmc_hgo_f32_step: kind2 on its fast path
                                                 (const_sat, no clamp), 5: the general law */
    uint32_t kind1, kind2;                /**< 0: no sigma, else 1 + sigma_i.real */
    uint32_t may_clamp;                   /**< 0: |u_i| <= M_i <= v_limit, no clamp needed */
    uint32_t have_sigma1, have_sigma2;
    mc_csvc_f32_t sigma1, sigma2;
    mc_csmc_f32_out_t out; /**< last output */
    uint32_t flags;        /**< sticky MC_CSMC_ERR_NAN_INPUT */
} mc_csmc_f32_t;

/** Validate cfg (only the fields the law uses) and initialise st (sigma = 0,
 *  last output 0). Returns the OR of the broken rules; on error st is not written. */
uint32_t mc_csmc_f32_init(mc_csmc_f32_t *st, const mc_csmc_f32_cfg_t *cfg);

/** sigma = 0, last output 0, sticky flags cleared. Returns MC_CSMC_ERR_NONE,
 *  or MC_CSMC_ERR_NULL for a NULL st. */
uint32_t mc_csmc_f32_reset(mc_csmc_f32_t *st);

/**
 * One control step: sliding variables, law, clamp; then sigma advanced over
 * one period; the outputs in *p_out. Returns MC_CSMC_ERR_NONE,
 * MC_CSMC_ERR_NULL (st, in or p_out NULL: nothing written) or
 * MC_CSMC_ERR_NAN_INPUT: a non-finite input is refused, state unchanged,
 * *p_out the last output, the bit also made sticky in st->flags. The test is one sum,
 * s1 + s2 + the five other inputs, which a non-finite input makes
 * non-finite (so do finite values whose sum overflows, |x| ~ 1e38: also
 * refused). psi = sat(s/mu) is formed as (1/mu) sat(s), and -M sat(s/mu) as
 * (-M/mu) (mu sat(s/mu)), the constants precomputed.
 */
uint32_t mc_csmc_f32_step(mc_csmc_f32_t *st, const mc_csmc_f32_in_t *in, mc_csmc_f32_out_t *p_out);

/**
 * Error vector from the full state (state feedback, paper Sec. III):
 *   e1 = i_d - I_dd, e2 = phi - phi_d, e2' = w - phi_d',
 *   e2'' = k3 i_q - k4 w - d0 - phi_d''  (needs K_m, J, B, tau_L).
 * Fills e1..dde2, i_d, i_q, w of *p_in (the other fields untouched).
 * Returns MC_CSMC_ERR_MODEL if K_m or J <= 0 or a value is not finite.
 */
uint32_t mc_csmc_f32_err_from_state(const mc_csmc_f32_model_t *model, float i_d_a, float i_q_a,
                                    float omega_m_rad_s, float theta_m_rad, float i_dd_a,
                                    float phi_d_rad, float dphi_d_rad_s, float ddphi_d_rad_s2,
                                    mc_csmc_f32_in_t *p_in);

/* ------------------------------------------------------------------------ */
/* Output feedback: the law and the high-gain observer in one step           */
/* ------------------------------------------------------------------------ */

/** The law with e2', e2'' from the high-gain observer on e2 (paper Sec. V),
 *  in one struct. */
typedef struct {
    mc_csmc_f32_t law; /**< law.out is not written by the combined step */
    mc_hgo_f32_t hgo;
    uint32_t fast; /**< law.fast_kind2 once the observer has two past
                                samples (its straight update), else 5: the
                                general path */
} mc_csmc_hgo_f32_t;

/** Validate both configs (law: mc_csmc_f32_init's bits; observer rejected
 *  or hgo->dt_s != law->dt_s: MC_CSMC_ERR_HGO) and initialise st (sigma 0,
 *  estimates 0). On error st is not written. */
uint32_t mc_csmc_hgo_f32_init(mc_csmc_hgo_f32_t *st, const mc_csmc_f32_cfg_t *law,
                              const mc_hgo_f32_cfg_t *hgo);

/** sigma = 0, estimates 0 with no past samples, sticky flags cleared.
 *  Returns MC_CSMC_ERR_NONE, or MC_CSMC_ERR_NULL for a NULL st. */
uint32_t mc_csmc_hgo_f32_reset(mc_csmc_hgo_f32_t *st);

/**
 * One output-feedback step: the estimates e2' = z2, e2'' = z3 at this
 * sample from the observer's state, the law on (e1, e2, e2', e2''), sigma
 * advanced, then the observer advanced with y = e2. Bit for bit the same as
 * mc_hgo_f32_step(&st->hgo, e2) followed by mc_csmc_f32_step(&st->law, ...)
 * with those estimates (tests/unit/csmc checks it).
 *
 * model: the LAW_MODEL inputs i_d, i_q, omega_m, I_dd', phi_d''' (its
 * e-fields are ignored); may be NULL for LAW_CONST (MC_CSMC_ERR_NULL for
 * LAW_MODEL).
 *
 * The estimates used are st->hgo.z[1], z[2] before the call (telemetry:
 * read them first). The outputs are written to *out only.
 *
 * Finiteness: one test, on s2 + e1, before any state is written. e2 enters
 * s2; the estimates are the observer's state, which only an accepted step
 * writes, from a finite e2 and a finite state (a state overflowed by a
 * finite but huge e2 makes the next s2 non-finite: that step and every
 * later one is refused until reset). With e1 and sigma finite, s1 = e1 +
 * K0 sigma cannot be NaN; the separate kernel refuses an e1 so close to
 * +-FLT_MAX that s1 overflows, here u1 saturates (the only inputs for which
 * the two differ). A refused step returns MC_CSMC_ERR_NAN_INPUT, changes
 * no state (neither the law nor the observer), sets the sticky law.flags
 * bit and writes zero v_d, v_q, s1, s2 to *out.
 *
 * Cost: LAW_CONST with SW_SAT and no clamp that can act (M_i <= v_limit)
 * runs a straight path, one dispatch per axis on the realisation of
 * sigma, from the third step after init/reset on (the observer's first
 * two steps use the samples they have); every other law goes through the
 * general step (mc_csmc_f32_step's
 * code, whose test also covers the model inputs). Returns
 * MC_CSMC_ERR_NONE, _NULL or _NAN_INPUT.
 */
uint32_t mc_csmc_hgo_f32_step(mc_csmc_hgo_f32_t *st, float e1_a, float e2_rad,
                              const mc_csmc_f32_in_t *model, mc_csmc_f32_out_t *out);

#ifdef __cplusplus
}
#endif

#endif /* MC_CSMC_H */
