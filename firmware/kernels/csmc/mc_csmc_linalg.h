/**
 * @file mc_csmc_linalg.h
 * @brief Small dense linear algebra for the init functions of the csmc
 *        kernels: matrix exponential (exact discretisation of linear
 *        dynamics), Routh-Hurwitz test, polynomial from a pole list.
 *
 * Init-time only (never in a fast step). Float32, no libm, no heap:
 * matrices are row-major arrays of at most MC_LINALG_MAX_N^2 floats.
 */
#ifndef MC_CSMC_LINALG_H
#define MC_CSMC_LINALG_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Largest matrix order handled (5 states of a servocompensator + 1 input). */
#define MC_LINALG_MAX_N 6u

/**
 * exp(A) for an n x n matrix A (row-major), n in 1..MC_LINALG_MAX_N.
 *
 * Method: scaling and squaring. A is scaled by 2^-s so that its infinity
 * norm is <= 1/2, exp of the scaled matrix by its Taylor series to degree
 * 12 (truncation < 0.5^13/13! = 2e-14 relative, far below float rounding),
 * then squared s times. Each squaring can double a relative rounding error,
 * so the result has a relative error of about 2^s * 1e-7 in the worst case;
 * for the high-gain observer at dt = eps (norm 101, s = 8) the measured
 * error is ~1e-6 (tests/unit/csmc).
 * Returns false (p_out not written) for n out of range, a non-finite entry,
 * or a norm above 2^40 (the squaring would overflow float).
 */
bool mc_linalg_expm_f32(const float *p_a, uint32_t n, float *p_out);

/**
 * true if every root of the monic polynomial
 *     lambda^n + p[n-1] lambda^(n-1) + ... + p[1] lambda + p[0]
 * has a strictly negative real part (Routh array: first column > 0).
 * n in 1..MC_LINALG_MAX_N; p holds n coefficients, lowest order first.
 * A zero in the first column (root on the imaginary axis, or a symmetric
 * root pair) gives false. Non-finite coefficient: false.
 */
bool mc_linalg_hurwitz_f32(const float *p_p, uint32_t n);

/**
 * The monic polynomial with the given n roots: coefficients p[0..n-1] (lowest
 * first; the leading 1 is implied). Roots are (re[i], im[i]); a complex root
 * (im != 0) must be followed directly by its conjugate (re equal, im
 * negated, bit for bit). Returns false (p_p not written) otherwise, for n
 * out of 1..MC_LINALG_MAX_N, or for a non-finite value.
 */
bool mc_linalg_poly_from_roots_f32(const float *p_re, const float *p_im, uint32_t n, float *p_p);

#ifdef __cplusplus
}
#endif

#endif /* MC_CSMC_LINALG_H */
