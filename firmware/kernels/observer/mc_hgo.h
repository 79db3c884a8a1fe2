/**
 * @file mc_hgo.h
 * @brief High-gain observer of paper 001, eq. (6): estimates the first and
 *        second derivative of a measured signal y (there: the position error
 *        e2), discretised exactly at the control period.
 *
 * Continuous observer (eq. (6)):
 *     z1' = z2 + (alpha1/eps)   (y - z1)
 *     z2' = z3 + (alpha2/eps^2) (y - z1)
 *     z3' =      (alpha3/eps^3) (y - z1)
 * alpha_i > 0 with lambda^3 + alpha1 lambda^2 + alpha2 lambda + alpha3
 * Hurwitz (alpha1 alpha2 > alpha3). Its poles are the roots of that
 * polynomial divided by eps: for the paper's alpha = (17, 80, 100) (roots
 * -2, -5, -10) and eps = 1e-4 they are -2e4, -5e4, -1e5 rad/s.
 *
 * Why not forward Euler: at dt = 1e-4 s the Euler map has eigenvalues
 * 1 + dt*lambda = -1, -4, -9, i.e. it diverges. This kernel integrates the
 * linear observer exactly over each period (matrix exponential, stable for
 * every dt > 0); what remains to choose is what y does between samples.
 *
 * Input model between samples (cfg.input_order), a departure from a plain
 * zero-order hold, and why: the observer differentiates y twice with time
 * constant eps. A held (staircase) y jumps by y' dt at every sample, which
 * the observer reads as real fast motion: at the sample instants z3 is
 * biased by about y' dt / eps^2 (a ramp of 3 rad/s with dt = 10 us and
 * eps = 1e-4 gives z3 ~ -2400 rad/s^2 instead of 0, and z2 7 % low;
 * measured in tests/unit/csmc), enough to destabilise the paper's loop.
 * So the kernel extrapolates y over the coming period with the Newton
 * backward polynomial of the last samples (s = tau/dt in [0, 1]):
 *     order 0: y(t_k + tau) = y[k]                               (ZOH)
 *     order 1: ... + (y[k] - y[k-1]) s                            (ramp)
 *     order 2: ... + (y[k] - 2 y[k-1] + y[k-2]) s (s + 1)/2       (parabola)
 * and integrates the observer exactly against that input. With order 2 the
 * discrete observer equals the continuous one at the sample instants for
 * any y that is a quadratic in time (constant acceleration); for smooth y
 * the error in z3 is of order (d3y/dt3) dt^3 / eps^2. Until enough samples
 * exist (the first steps after init/reset) the orders available are used.
 *
 * Scaling: the kernel integrates eta = (z1, eps z2, eps^2 z3), in which the
 * dynamics are eta' = (1/eps) (A0 eta + b0 y) with
 *     A0 = [-a1 1 0; -a2 0 1; -a3 0 0], b0 = (a1, a2, a3) = -A0 e1,
 * all entries of order one. Over one period, with v1 = dy + d2y/2 and
 * v2 = d2y (dy = y[k] - y[k-1], d2y = y[k] - 2 y[k-1] + y[k-2]: the
 * polynomial is y[k] + v1 s + v2 s^2/2):
 *     eta[k+1] = y[k] e1 + Phi (eta[k] - y[k] e1) + G1 v1 + G2 v2
 * with Phi = exp(A0 dt/eps); the held part's input matrix is (I - Phi) e1
 * because A0 e1 = -b0, so a constant y is an exact equilibrium whatever the
 * rounding of Phi. Phi, G1 and G2 come from one 6 x 6 matrix exponential of
 * the observer augmented with the input polynomial's chain of integrators,
 * computed at init.
 *
 * The step runs in z = D^-1 eta (D = diag(1, eps, eps^2)), the estimates
 * themselves, with D^-1 Phi D, D^-1 G1, D^-1 G2 formed at init (no output
 * scaling per step); once two past samples exist the input terms are
 * G1 v1 + G2 v2 = G1 dy + (G2 + G1/2) d2y for input_order 2 (G1 dy for 1,
 * none for 0), with the combined coefficients formed at init.
 *
 * Timing: mc_hgo_f32_step(y[k]) returns the estimate at t_k (from the
 * samples before y[k], as the continuous observer state at t_k), then
 * advances the state to t_{k+1}.
 *
 * Floating point: the outputs are z2 = eta2/eps and z3 = eta3/eps^2, so
 * rounding of y (relative 6e-8) appears in z3 amplified by ~alpha3/eps^2:
 * with y ~ 0.1 rad and eps = 1e-4, ~1 rad/s^2. Feed a small error signal
 * (e2 = phi - phi_d, not an absolute angle of many turns).
 */
#ifndef MC_HGO_H
#define MC_HGO_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MC_HGO_ERR_NONE  0u
#define MC_HGO_ERR_NULL  (1u << 0) /**< a required pointer is NULL */
#define MC_HGO_ERR_ALPHA (1u << 1) /**< alpha_i <= 0, not finite, or alpha1 alpha2 <= alpha3 */
#define MC_HGO_ERR_EPS   (1u << 2) /**< eps_s <= 0, not finite, or 1/eps^2 not finite */
#define MC_HGO_ERR_DT    (1u << 3) /**< dt_s <= 0 or not finite */
#define MC_HGO_ERR_DISCRETE \
    (1u << 4) /**< the matrix exponential could not be formed (dt/eps too large) */
#define MC_HGO_ERR_NAN_INPUT (1u << 5) /**< sticky: a step got a non-finite y and was refused */
#define MC_HGO_ERR_ORDER     (1u << 6) /**< input_order > 2 */

typedef struct {
    float alpha1;         /**< [-], > 0 */
    float alpha2;         /**< [-], > 0 */
    float alpha3;         /**< [-], > 0, < alpha1 alpha2 */
    float eps_s;          /**< observer time scale eps [s], > 0 */
    float dt_s;           /**< control period [s], > 0 */
    uint32_t input_order; /**< y between samples: 0 held, 1 ramp, 2 parabola (see above) */
} mc_hgo_f32_cfg_t;

typedef struct {
    float phi[9];   /**< exp(A0 dt/eps), row-major */
    float g1[3];    /**< response to the ramp coefficient v1 */
    float g2[3];    /**< response to the parabola coefficient v2 */
    float inv_eps;  /**< 1/eps [1/s] */
    float inv_eps2; /**< 1/eps^2 [1/s^2] */
    float eps_s;
    uint32_t input_order;
    uint32_t n_hist; /**< past samples available (0..2) */
    float y1;        /**< y[k-1] */
    float y2;        /**< y[k-2] */
    float pz[9];     /**< Phi in the coordinates z: D^-1 Phi D, D = diag(1, eps, eps^2) */
    float g1z[3];    /**< D^-1 G1 */
    float g2z[3];    /**< D^-1 G2 */
    float gdy[3];    /**< with two past samples: coefficient of dy = y[k] - y[k-1] */
    float gd2y[3];   /**< ... and of d2y = y[k] - 2 y[k-1] + y[k-2] (per input_order) */
    float z[3];      /**< the state, (z1, z2, z3) = D^-1 eta */
    uint32_t flags;  /**< sticky MC_HGO_ERR_NAN_INPUT */
} mc_hgo_f32_t;

/** Estimates at one sample, in the units of y: y, y/s, y/s^2. */
typedef struct {
    float z1; /**< estimate of y */
    float z2; /**< estimate of dy/dt */
    float z3; /**< estimate of d2y/dt2 */
} mc_hgo_f32_est_t;

/** Validate cfg, form Phi, G1, G2, zero the state. On error st is not written. */
uint32_t mc_hgo_f32_init(mc_hgo_f32_t *st, const mc_hgo_f32_cfg_t *cfg);

/** Set the estimates (z1, z2, z3), forget the past samples, clear the sticky
 *  flag. A non-finite value is refused (MC_HGO_ERR_NAN_INPUT returned, st
 *  unchanged). */
uint32_t mc_hgo_f32_reset(mc_hgo_f32_t *st, float z1, float z2, float z3);

/**
 * Write the estimate at this sample to *p_est, then advance one period.
 * Returns MC_HGO_ERR_NONE; MC_HGO_ERR_NAN_INPUT for a non-finite y (the
 * state is not advanced, *p_est is the current estimate, the bit is also
 * made sticky); MC_HGO_ERR_NULL when st or p_est is NULL (nothing written).
 */
uint32_t mc_hgo_f32_step(mc_hgo_f32_t *st, float y, mc_hgo_f32_est_t *p_est);

/** The first steps after init/reset (fewer than two past samples) of
 *  mc_hgo_f32_advance: the input polynomial of the order the history allows. */
void mc_hgo_f32_advance_start(mc_hgo_f32_t *st, float y);

/**
 * Advance the state one period with the sample y, which the caller has
 * checked to be finite (no check here; the estimate at this sample is
 * st->z before the call). mc_hgo_f32_step is this plus its check, so both
 * give the same bits; for a caller that runs the observer inside its own
 * step (mc_csmc_hgo_f32_step).
 */
static inline void mc_hgo_f32_advance_run(mc_hgo_f32_t *st, float y);

static inline void mc_hgo_f32_advance(mc_hgo_f32_t *st, float y)
{
    if (__builtin_expect(st->n_hist < 2u, 0)) {
        mc_hgo_f32_advance_start(st, y);
        return;
    }
    mc_hgo_f32_advance_run(st, y);
}

/** mc_hgo_f32_advance once st->n_hist >= 2 (two past samples), which the
 *  caller knows. */
static inline void mc_hgo_f32_advance_run(mc_hgo_f32_t *st, float y)
{
    /* z <- y e1 + Pz (z - y e1) + gdy dy + gd2y d2y */
    const float y1 = st->y1;
    const float dy = y - y1;
    const float d2y = (dy - y1) + st->y2;
    const float d0 = st->z[0] - y;
    const float z1 = st->z[1];
    const float z2 = st->z[2];
    const float *p = st->pz;
    st->z[0] = (y + (((p[0] * d0) + (p[1] * z1)) + (p[2] * z2))) +
               ((st->gdy[0] * dy) + (st->gd2y[0] * d2y));
    st->z[1] =
        (((p[3] * d0) + (p[4] * z1)) + (p[5] * z2)) + ((st->gdy[1] * dy) + (st->gd2y[1] * d2y));
    st->z[2] =
        (((p[6] * d0) + (p[7] * z1)) + (p[8] * z2)) + ((st->gdy[2] * dy) + (st->gd2y[2] * d2y));
    st->y2 = y1;
    st->y1 = y;
}

#ifdef __cplusplus
}
#endif

#endif /* MC_HGO_H */
