/**
 * @file mc_csvc.h
 * @brief Conditional servocompensator of paper 001, eqs. (9)-(10), and the
 *        conditional integrator (4) as its first-order case.
 *
 * Continuous law (paper eq. (9)):
 *     sigma' = (S - J K0) sigma + mu J sat(s/mu),     s = K0 sigma + s*
 * with S an n x n companion matrix whose last row is c = (c0 .. c_{n-1}),
 * J = e_n, and K0 such that S - J K0 is Hurwitz. Inside the boundary layer
 * (|s| <= mu) this is sigma' = S sigma + J s*, an internal model with the
 * eigenvalues of S (integral action for S = 0, n = 1; sinusoids for the
 * paper's S1, S2); outside it sigma decays with the poles of S - J K0 and
 * stays O(mu).
 *   - Conditional integrator, eq. (4): n = 1, c0 = 0, K0 = k0:
 *     sigma' = -k0 sigma + mu sat(s/mu), s = k0 sigma + s*.
 *   - S1 (d axis, paper Sec. V): n = 5, c = (0, -4 w0^4, 0, -5 w0^2, 0)
 *     (the matrix printed in the paper is right; its text "c3 = -5 w0^6"
 *     is a typo: the characteristic polynomial must be
 *     lambda (lambda^2 + w0^2)(lambda^2 + 4 w0^2)).
 *   - S2 (q axis): n = 3, c = (0, -w0^2, 0).
 *
 * Discretisation (departure from a plain discretisation of (9), stated):
 * the update is written as
 *     sigma[k+1] = Phi sigma[k] + Gam (mu sat(s[k]/mu) - K0 sigma[k])
 * with Phi = exp(S dt), Gam = int_0^dt exp(S tau) J dtau (exact ZOH of the
 * internal model S). Inside the boundary layer mu sat(s/mu) - K0 sigma = s*,
 * so the discrete internal model is exact (eigenvalues exactly
 * exp(lambda(S) dt)) and a constant / sampled sinusoidal s* is rejected
 * with no residual error from the discretisation. Outside, the update is
 * Phi - Gam K0 = exp((S - J K0) dt) + O(dt^2 |K0| |S|); init requires
 * dt * ||S - J K0||_inf <= 0.1 so that this stays a small perturbation of
 * the stable continuous decay (for the paper's values the product is at
 * most 0.01).
 *
 * Realisation (chosen at init, st->real): when S has the eigenvalues 0 and
 * +-j w_k only, all simple (odd n, c_i = 0 for even i, and
 * lambda^n - sum c_i lambda^i = lambda q(lambda^2) with distinct negative
 * roots of q: the paper's S1, S2 and the conditional integrator), the state
 * is kept in modal coordinates xi (sigma = T xi, T formed at init from the
 * eigenvectors (1, lambda, .., lambda^(n-1)) of S): x0 += v for the
 * eigenvalue 0, and per pair x <- x - e y + v, y <- y + e x with
 * e = 2 sin(w dt/2), a rotation by exactly w dt with determinant exactly 1
 * (2 multiplications; no growth or decay from rounded coefficients); the
 * term is h . xi with h = K0 T. Init checks Phi T = T A and Gam = T g to
 * 1e-4 and otherwise keeps the dense update (as for every other S).
 * mc_csvc_f32_sigma() returns sigma in either case.
 *
 * Pole placement: with S companion and J = e_n, S - J K0 is the companion
 * matrix with last row c - K0, whose characteristic polynomial is
 * lambda^n + sum_i (K0_i - c_i) lambda^i. To place the roots of
 * p(lambda) = lambda^n + sum p_i lambda^i: K0_i = c_i + p_i
 * (mc_csvc_f32_place).
 */
#ifndef MC_CSVC_H
#define MC_CSVC_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MC_CSVC_MAX_ORDER 5u

#define MC_CSVC_ERR_NONE        0u
#define MC_CSVC_ERR_NULL        (1u << 0) /**< a required pointer is NULL */
#define MC_CSVC_ERR_ORDER       (1u << 1) /**< order not in 1..MC_CSVC_MAX_ORDER */
#define MC_CSVC_ERR_MODEL       (1u << 2) /**< a c_i or K0_i not finite */
#define MC_CSVC_ERR_NOT_HURWITZ (1u << 3) /**< S - J K0 not Hurwitz */
#define MC_CSVC_ERR_MU          (1u << 4) /**< mu <= 0 or not finite */
#define MC_CSVC_ERR_DT          (1u << 5) /**< dt_s <= 0, not finite, or dt ||S - J K0|| > 0.1 */
#define MC_CSVC_ERR_POLES \
    (1u << 6) /**< place: pole list invalid or not in the open left half-plane */
#define MC_CSVC_ERR_NAN_INPUT (1u << 7) /**< sticky: an update got a non-finite s and was refused */

/** Internal model and gain: S (companion, last row c), K0. */
typedef struct {
    uint32_t order;              /**< n, 1..MC_CSVC_MAX_ORDER */
    float c[MC_CSVC_MAX_ORDER];  /**< last row of S [1/s^(n-i)] */
    float k0[MC_CSVC_MAX_ORDER]; /**< K0 [units of s per unit of sigma_i] */
} mc_csvc_f32_model_t;

typedef struct {
    mc_csvc_f32_model_t model;
    float mu;   /**< boundary-layer width, units of s, > 0 */
    float dt_s; /**< control period [s], > 0 */
} mc_csvc_f32_cfg_t;

/** How the state is advanced (chosen at init, see mc_csvc_f32_init). */
#define MC_CSVC_REAL_DENSE  0u /**< sigma itself, dense Phi (any model) */
#define MC_CSVC_REAL_MODAL0 1u /**< modal: eigenvalue 0 only (integrator) */
#define MC_CSVC_REAL_MODAL1 2u /**< modal: 0 and one pair +-j w */
#define MC_CSVC_REAL_MODAL2 3u /**< modal: 0 and two pairs +-j w1, +-j w2 */

typedef struct {
    uint32_t n;
    float mu;
    float k0[MC_CSVC_MAX_ORDER];
    float phi[MC_CSVC_MAX_ORDER * MC_CSVC_MAX_ORDER]; /**< exp(S dt), row-major n x n */
    float gam[MC_CSVC_MAX_ORDER];                     /**< int exp(S tau) J dtau */
    float sigma[MC_CSVC_MAX_ORDER];                   /**< the state (MC_CSVC_REAL_DENSE only;
                                                            read it with mc_csvc_f32_sigma) */
    uint32_t real;                                    /**< MC_CSVC_REAL_* */
    float xi[MC_CSVC_MAX_ORDER];                      /**< modal state: x0, (x, y) per pair */
    float xi_lo[MC_CSVC_MAX_ORDER]; /**< rounding error of each xi's running sum (compensated
                                         summation, see MC_CSVC_ACC_F32): xi + xi_lo is the
                                         state to about 2^-48 of its size */
    float h[MC_CSVC_MAX_ORDER];     /**< K0 T: term = h . xi */
    float e[2];                     /**< 2 sin(w dt / 2) per pair */
    float t[MC_CSVC_MAX_ORDER * MC_CSVC_MAX_ORDER]; /**< sigma = T xi, row-major n x n */
    uint32_t flags;                                 /**< sticky MC_CSVC_ERR_NAN_INPUT */
} mc_csvc_f32_t;

/** The conditional integrator (4): order 1, c = 0, K0 = k0_per_s. Returns
 *  MC_CSVC_ERR_MODEL for k0 <= 0 or not finite (p_model not written). */
uint32_t mc_csvc_f32_integrator(float k0_per_s, mc_csvc_f32_model_t *p_model);

/**
 * Internal model with last row c (order n) and K0 placing the eigenvalues
 * of S - J K0 at the n given roots (re, im); a complex root must be followed
 * by its conjugate. Returns MC_CSVC_ERR_ORDER, _MODEL (c not finite) or
 * _POLES (bad list or a root with re >= 0); p_model not written on error.
 */
uint32_t mc_csvc_f32_place(uint32_t order, const float *p_c, const float *p_pole_re,
                           const float *p_pole_im, mc_csvc_f32_model_t *p_model);

/** Validate cfg, compute Phi and Gam, zero sigma. On error st is not written. */
uint32_t mc_csvc_f32_init(mc_csvc_f32_t *st, const mc_csvc_f32_cfg_t *cfg);

/** sigma = 0, sticky flag cleared. Returns MC_CSVC_ERR_NONE, or
 *  MC_CSVC_ERR_NULL for a NULL st. */
uint32_t mc_csvc_f32_reset(mc_csvc_f32_t *st);

/** K0 sigma: the compensator's share of the sliding variable s. */
float mc_csvc_f32_term(const mc_csvc_f32_t *st);

/** Advance one period with s held: sigma <- Phi sigma + Gam (mu sat(s/mu) - K0 sigma).
 *  Non-finite s: refused, sticky MC_CSVC_ERR_NAN_INPUT. */
void mc_csvc_f32_update(mc_csvc_f32_t *st, float s);

/** Advance one period with the input v = mu sat(s/mu) - K0 sigma already
 *  formed (finite; no check): sigma <- Phi sigma + Gam v. */
void mc_csvc_f32_advance(mc_csvc_f32_t *st, float v);

/** The state sigma (n values, in the coordinates of S) into p_sigma. */
void mc_csvc_f32_sigma(const mc_csvc_f32_t *st, float *p_sigma);

/** Force the dense realisation (for tests comparing both); st must come
 *  from a successful mc_csvc_f32_init and be in reset (state zero). */
void mc_csvc_f32_force_dense(mc_csvc_f32_t *st);

/* ---- the step's arithmetic, inline for the CSMC step ------------------- */

/** K0 sigma in the modal realisations, one function per shape. */
static inline float mc_csvc_f32_term_m0(const mc_csvc_f32_t *st)
{
    return st->h[0] * st->xi[0];
}
static inline float mc_csvc_f32_term_m1(const mc_csvc_f32_t *st)
{
    return (st->h[0] * st->xi[0]) + ((st->h[1] * st->xi[1]) + (st->h[2] * st->xi[2]));
}
static inline float mc_csvc_f32_term_m2(const mc_csvc_f32_t *st)
{
    return ((st->h[0] * st->xi[0]) + ((st->h[1] * st->xi[1]) + (st->h[2] * st->xi[2]))) +
           ((st->h[3] * st->xi[3]) + (st->h[4] * st->xi[4]));
}

/*
 * Compensated accumulation hi + lo += d (Knuth's TwoSum): the sum is
 * rounded into hi and its exact rounding error kept in lo, which is added
 * back with the next increment. Why: at steady state the modal states carry
 * the internal model's sinusoids (their size set by what the loop must
 * reject), while each step adds w dt (5e-5 at 5 rad/s, 10 kHz) of their size
 * plus an input of the size of the tracking error; rounding each new sum to
 * float lost ulp(xi)/2 per step, a random walk of the internal model that
 * the loop sees as a disturbance (part of the float32 floor of the tracking
 * error: csmc README). With the error carried, the state is exact to the
 * rounding of the increments themselves. Exact in round-to-nearest binary
 * arithmetic without contraction (the kernels build with
 * -ffp-contract=off): bit-identical on host and target. A macro, not a
 * function: a helper of the advance functions below, not a kernel entry.
 */
#define MC_CSVC_ACC_F32(hi, lo, d)                             \
    do {                                                       \
        const float acc_y_ = (d) + (lo);                       \
        const float acc_s_ = (hi) + acc_y_;                    \
        const float acc_b_ = acc_s_ - (hi);                    \
        (lo) = ((hi) - (acc_s_ - acc_b_)) + (acc_y_ - acc_b_); \
        (hi) = acc_s_;                                         \
    } while (0)

/** Advance in the modal realisations: x0 += v (the eigenvalue 0 of S,
 *  exp(0 dt) = 1), and per pair the rotation by w dt as
 *  x <- x - e y + v, y <- y + e x (determinant exactly 1), each sum
 *  compensated (MC_CSVC_ACC_F32). */
static inline void mc_csvc_f32_advance_m0(mc_csvc_f32_t *st, float v)
{
    MC_CSVC_ACC_F32(st->xi[0], st->xi_lo[0], v);
}
static inline void mc_csvc_f32_advance_m1(mc_csvc_f32_t *st, float v)
{
    MC_CSVC_ACC_F32(st->xi[0], st->xi_lo[0], v);
    MC_CSVC_ACC_F32(st->xi[1], st->xi_lo[1], v - (st->e[0] * st->xi[2]));
    MC_CSVC_ACC_F32(st->xi[2], st->xi_lo[2], st->e[0] * st->xi[1]);
}
static inline void mc_csvc_f32_advance_m2(mc_csvc_f32_t *st, float v)
{
    mc_csvc_f32_advance_m1(st, v);
    MC_CSVC_ACC_F32(st->xi[3], st->xi_lo[3], v - (st->e[1] * st->xi[4]));
    MC_CSVC_ACC_F32(st->xi[4], st->xi_lo[4], st->e[1] * st->xi[3]);
}

#ifdef __cplusplus
}
#endif

#endif /* MC_CSVC_H */
