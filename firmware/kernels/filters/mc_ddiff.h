/**
 * @file mc_ddiff.h
 * @brief Dirty-derivative filter (float32): the velocity surrogate of the
 *        PI^2D speed controller, Loria / Espinosa-Perez / Avila-Becerril,
 *        eqs. (11)-(12):
 *
 *     dq_c/dt = -a (q_c + b y),      theta_f = q_c + b y,     a, b > 0
 *
 * i.e. the transfer function from the input y to theta_f
 *
 *     H(s) = b s / (s + a),
 *
 * a high-passed derivative: for frequencies well below a, theta_f is
 * (b/a) dy/dt; at high frequency its gain tends to b. a is a rate [1/s],
 * b is dimensionless, theta_f has the unit of y (for y a position error in
 * rad, theta_f is in rad and (a/b) theta_f approximates the speed error).
 *
 * Discretisation: Tustin (trapezoidal) of H(s), realised on theta_f itself:
 *
 *     theta_f[k] = c_q theta_f[k-1] + g (y[k] - y[k-1]),
 *     c_q = (1 - a dt/2) / (1 + a dt/2),   g = b / (1 + a dt/2),
 *
 * which is exactly the trapezoidal rule applied to the paper's q_c
 * equation (q[k] = c_q q[k-1] - (a b dt/2)/(1 + a dt/2) (y[k] + y[k-1]),
 * theta_f = q + b y: same transfer function, same output), but with a
 * different state. DEPARTURE from the printed state choice, for float
 * precision: q_c ~ -b y is large whenever y is, and theta_f = q_c + b y is a
 * small difference of two large numbers, so the rounding of q_c (ulp of
 * b y, accumulated over ~1/(a dt) steps by the slow pole) swamps theta_f;
 * with theta_f as the state, y enters only through its increment. q_c is
 * still available (mc_ddiff_f32_get_q(st) = theta_f - b y) for telemetry.
 *
 * The filter needs no exponential (no libm), is stable for every a dt > 0,
 * and its frequency response is exactly that of H(s) at the pre-warped
 * frequency (2/dt) tan(w dt/2): H_d(e^{jw dt}) = H(j (2/dt) tan(w dt / 2)).
 * It also differentiates a ramp exactly: for y = v k dt, theta_f settles at
 * (b/a) v with no discretisation error.
 *
 * First step after init or reset: q takes the preset value and no
 * integration happens (there is no previous sample yet), so the output is
 * q0 + b y[0], the continuous filter's output at the start. That step uses
 * the same formula as every other one, with the coefficients a reset
 * leaves (theta_f = q0, c_q -> 1, g -> b, y[-1] = 0: q0 1 + b (y - 0) is
 * q0 + b y exactly), so the step has no first-sample branch.
 *
 * Non-finite input: the step is refused (state unchanged, the last output
 * written) and returns MC_DDIFF_ERR_NAN_INPUT, also made sticky in
 * st->flags; reset clears it.
 * No heap, no globals, no I/O.
 */
#ifndef MC_DDIFF_H
#define MC_DDIFF_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MC_DDIFF_ERR_NONE      0u
#define MC_DDIFF_ERR_NULL      (1u << 0) /**< a required pointer is NULL */
#define MC_DDIFF_ERR_A         (1u << 1) /**< a_per_s <= 0 or not finite */
#define MC_DDIFF_ERR_B         (1u << 2) /**< b <= 0 or not finite */
#define MC_DDIFF_ERR_DT        (1u << 3) /**< dt_s <= 0 or not finite */
#define MC_DDIFF_ERR_NAN_INPUT (1u << 4) /**< sticky: a step got a non-finite input */

/** Configuration. */
typedef struct {
    float a_per_s; /**< filter pole a [1/s], > 0 */
    float b;       /**< high-frequency gain b [1], > 0 */
    float dt_s;    /**< sample period [s], > 0 */
} mc_ddiff_f32_cfg_t;

/** State (read-only for callers except through the functions below). */
typedef struct {
    float a_per_s; /**< copy of the config */
    float b;
    float dt_s;
    float c_q;      /**< (1 - a dt/2) / (1 + a dt/2), derived at init */
    float g;        /**< b / (1 + a dt/2), derived at init */
    float out;      /**< last output theta_f [unit of y] (q0 after init/reset) */
    float c_k;      /**< coefficient of out in the next step: c_q, 1 after init/reset */
    float g_k;      /**< coefficient of y - y_prev in the next step: g, b after init/reset */
    float y_prev;   /**< input of the last accepted step (0 after init/reset) */
    uint32_t flags; /**< sticky MC_DDIFF_ERR_NAN_INPUT */
} mc_ddiff_f32_t;

/** Validate cfg, initialise st with q_c = 0. Returns MC_DDIFF_ERR_* bits;
 *  on error st is not written. */
uint32_t mc_ddiff_f32_init(mc_ddiff_f32_t *st, const mc_ddiff_f32_cfg_t *cfg);

/** Preset q_c (the next step starts from it without integrating) and clear
 *  the sticky flags. A non-finite preset is refused (MC_DDIFF_ERR_NAN_INPUT
 *  returned, st not written). */
uint32_t mc_ddiff_f32_reset(mc_ddiff_f32_t *st, float q0);

/** One sample: theta_f[k] [unit of y] for the input y[k] in *p_theta_f.
 *  Returns MC_DDIFF_ERR_NONE, MC_DDIFF_ERR_NAN_INPUT (y not finite: refused,
 *  *p_theta_f the last output) or MC_DDIFF_ERR_NULL (st or p_theta_f NULL:
 *  nothing written). */
uint32_t mc_ddiff_f32_step(mc_ddiff_f32_t *st, float y, float *p_theta_f);

/** theta_f[k] for a finite y[k] without writing st: the arithmetic of
 *  mc_ddiff_f32_step (bit for bit). For a caller that decides only later
 *  whether the sample is accepted (then mc_ddiff_f32_commit). */
static inline float mc_ddiff_f32_next(const mc_ddiff_f32_t *st, float y)
{
    /* c_q theta_f[k-1] + g (y - y[k-1]); right after init/reset
     * q0 1 + b (y - 0) = q_c(0) + b y(0), (12) */
    return (st->out * st->c_k) + (st->g_k * (y - st->y_prev));
}

/** Accept the sample y whose output was th = mc_ddiff_f32_next(st, y). */
static inline void mc_ddiff_f32_commit(mc_ddiff_f32_t *st, float y, float th)
{
    st->out = th;
    st->y_prev = y;
    st->c_k = st->c_q;
    st->g_k = st->g;
}

/** q_c = theta_f - b y of the last step (q0 after init/reset). */
static inline float mc_ddiff_f32_get_q(const mc_ddiff_f32_t *st)
{
    return st->out - (st->b * st->y_prev);
}

#ifdef __cplusplus
}
#endif

#endif /* MC_DDIFF_H */
