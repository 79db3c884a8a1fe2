/**
 * @file mc_fluxobs.h
 * @brief Flux gradient observer of the rotor position of a PMSM (Ortega,
 *        Praly, Astolfi, Lee, Nam, IEEE TCST 2010, eqs. (4)-(9)), float32;
 *        salient (interior-magnet) machines in the active-flux form.
 *
 * Model (amplitude-invariant alpha-beta frame, theta_e electrical angle):
 *     x      = L i_ab + flux c(theta_e),  c = [cos, sin]^T          (4)
 *     dx/dt  = y12 := v_ab - R i_ab                                 (6), (7)
 *     |x - L i_ab|^2 = flux^2                 (the algebraic constraint)
 * Observer (a gradient search on the constraint):
 *     dxh/dt = y12 + (gamma/2) e (flux^2 - |e|^2),  e := xh - L i_ab   (9)
 *     theta_e_hat = atan2(e_beta, e_alpha)
 *
 * Salient machine (Ld != Lq), the active-flux form. The stator flux in
 * alpha-beta is Ld i_d d + Lq i_q q + flux d (d = c(theta), q its quarter
 * turn ahead) = Lq i_ab + psi_a c(theta) with the ACTIVE FLUX
 *     psi_a = flux + (Ld - Lq) i_d:
 * the model (4) with L := Lq (cfg.l_h) and the constant flux replaced by
 * psi_a (cfg.ld_minus_lq_h = Ld - Lq). dx/dt = v - R i is unchanged, so
 *     e := xh - Lq i_ab,   constraint |e|^2 = psi_a^2,
 *     dxh/dt = y12 + (gamma/2) e (psi_a^2 - |e|^2),  theta_hat = atan2(e).
 * i_d is not measurable without the angle: the step takes the new current
 * at the PREVIOUS estimate, i_d = c(theta_hat_prev) . i_ab (one step
 * behind: an error of about omega_e dt |i_q| in i_d; an angle error
 * dtheta moves i_d by about dtheta |i_q| and psi_a by (Ld - Lq) dtheta
 * |i_q|: an error of the circle's radius, which, like a flux error in the
 * surface-magnet observer, leaves an angle error that grows with the
 * speed; tests/unit/observer/test_fluxobs.cpp measures it). psi_a is floored at MC_FLUXOBS_PSI_A_MIN_FRAC flux (a wrong
 * estimate with a large i_d must not shrink the circle to a point).
 * cfg.ld_minus_lq_h = 0 is the surface-magnet observer, bit for bit (the
 * step uses the constants formed at init).
 * What of paper 002's proof carries over: the constraint is still a circle
 * of radius psi_a about the origin of the e plane, and for a CONSTANT
 * psi_a the error system (10)-(17) is the paper's with flux -> psi_a
 * (the derivation uses only |e| = radius and dx/dt = y12): Prop. 3 and 4
 * hold with psi_a. psi_a moves with i_d; the argument is kept for i_d
 * varying slowly against the observer's time scale 2 / (gamma psi_a^2)
 * (a quasi-static radius: at a steady operating point i_d is constant);
 * a fast i_d step moves the circle's radius by (Ld - Lq) di_d, which the
 * gradient pulls the estimate back to at that time scale. Not proved
 * here: convergence under a fast-varying psi_a.
 * The critical speed and the time scale below use psi_a for flux: the
 * critical speed gamma psi_a^2 / (4 n_P) is largest at the LARGEST psi_a
 * of the operating range and the time scale longest at the smallest. The
 * sensorless law chooses gamma at the largest psi_a its current range
 * gives (mc_ctrl_sensorless.h), so no operating point has a critical
 * speed above the configured one.
 *
 * Units of gamma: x is a flux [Wb = V s], so (gamma/2) e (flux^2 - |e|^2)
 * must be [V] = [Wb/s]: gamma is in 1 / (Wb^2 s).
 *
 * Choosing gamma (the only tuning gain). With chi the rotated, scaled error
 * of (10), the error obeys (11)/(17) in the time s = t gamma flux^2 / 2 with
 * the scaled speed Omega = -2 omega_e / (gamma flux^2):
 *   - time scale: one unit of s is T_obs = 2 / (gamma flux^2) seconds; near
 *     the origin the error decays like exp(-t/T_obs) (eigenvalues
 *     -1 +- sqrt(1 - Omega^2) of the linearisation, Prop. 3);
 *   - critical speed (Prop. 4): for |Omega| <= 1/2, i.e.
 *         |omega_m| <= omega_crit_m = gamma flux^2 / (4 n_P)   [rad/s]
 *     extra equilibria (a saddle and an unstable focus) appear and at
 *     omega = 0 a whole circle of wrong angles is stable; above it the
 *     correct angle is the only equilibrium and is globally attractive.
 * So gamma trades the two: T_obs = 1 / (2 n_P omega_crit_m). A lower
 * critical speed means a slower observer (and, for gamma -> 0, the
 * open-loop flux integrator, which drifts with any voltage or R error).
 * mc_fluxobs_f32_gamma_for_critical_speed() gives gamma for a requested
 * critical speed; mc_fluxobs_f32_critical_speed() and
 * mc_fluxobs_f32_time_scale() go back.
 *
 * Discretisation (departure from the continuous (9), chosen so that the
 * open-loop part is exact for the inverter's piecewise-constant voltage):
 *     xh <- xh + dt (v_avg - R (i_prev + i)/2)           (flux integration)
 *     e  =  xh - L i
 *     k  =  dt (gamma/2) (flux^2 - |e|^2),  clamped to k >= -1/2
 *     xh <- xh + k e                                     (gradient step)
 * v_avg is the voltage applied over the last period (the caller accounts
 * for its PWM delay), i_prev and i the currents sampled at its start and
 * end. The clamp only acts for |e| > flux sqrt(1 + 1/(gamma flux^2 dt)),
 * where an Euler step of the cubic term would shrink e by more than half
 * (or flip it): 10 flux for gamma flux^2 dt = 0.01, i.e. far outside the
 * attracting disk |chi| <= 2 (|e| <= 3 flux) at practical gains. Init
 * requires gamma flux^2 dt <= 0.2 so the step samples (9) faithfully near
 * the constraint circle.
 *
 * Divergence monitor: the residual rho = |e| / flux - 1 is 0 on the
 * constraint circle. |rho| > resid_tol for longer than resid_time_s raises
 * the sticky MC_FLUXOBS_ERR_DIVERGED (wrong flux, R, L or voltage, or an
 * estimate that left the constraint). A consistent residual does NOT prove
 * the angle right: at zero speed every point of the circle sigma(chi) = 0
 * (Prop. 4 i) has rho = 0. The caller must also keep the speed above the
 * critical one (the sensorless drive checks the PLL speed).
 *
 * Resistance at run time (a warm winding: copper's R rises about 0.4 %
 * per K): mc_fluxobs_f32_set_r_scale() sets the R the integration uses to
 * cfg.r_ohm times a scale. The scale is state (the derived R/2 the step
 * already reads), not a step input: R moves at the winding's thermal speed
 * (seconds), so a caller's slow loop sets it and the fast step keeps its
 * arguments and its cost. The config stays the R measured cold; reset()
 * keeps the scale, init() restores 1. The q31 twin does the same with its
 * R gain (mc_fluxobs_q31_set_r_scale), both accept the same scales
 * (mc_r_scale_f32_ok, math/mc_math.h).
 *
 * Non-finite input: the step is refused (state unchanged) and the sticky
 * MC_FLUXOBS_ERR_NAN_INPUT is set. No heap, no globals, no I/O.
 */
#ifndef MC_FLUXOBS_H
#define MC_FLUXOBS_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MC_FLUXOBS_ERR_NONE      0u
#define MC_FLUXOBS_ERR_NULL      (1u << 0) /**< a required pointer is NULL */
#define MC_FLUXOBS_ERR_MOTOR     (1u << 1) /**< R < 0, L <= 0, flux <= 0, or not finite */
#define MC_FLUXOBS_ERR_GAMMA     (1u << 2) /**< gamma <= 0, not finite, or gamma flux^2 dt > 0.2 */
#define MC_FLUXOBS_ERR_DT        (1u << 3) /**< dt_s <= 0 or not finite */
#define MC_FLUXOBS_ERR_MONITOR   (1u << 4) /**< resid_tol <= 0 or resid_time_s < 0 / not finite */
#define MC_FLUXOBS_ERR_NAN_INPUT (1u << 5) /**< sticky: a step input was NaN/inf (step refused) */
#define MC_FLUXOBS_ERR_DIVERGED  (1u << 6) /**< sticky: residual out of tolerance too long */
#define MC_FLUXOBS_ERR_ARG \
    (1u << 7) /**< helper: speed/gain/pole pairs invalid; set_r_scale: scale refused */

/** Largest gamma flux^2 dt accepted (Euler step of the gradient term). */
#define MC_FLUXOBS_MAX_GAIN_DT 0.2f

/** Floor of the active flux psi_a, as a fraction of the PM flux (salient
 *  machine): a wrong angle estimate with a large current must not shrink
 *  the constraint circle to a point (the gradient vanishes there). */
#define MC_FLUXOBS_PSI_A_MIN_FRAC 0.1f

/** Configuration. */
typedef struct {
    float r_ohm;         /**< stator resistance [ohm], >= 0 */
    float l_h;           /**< stator inductance [H], > 0: Lq of a salient machine */
    float flux_wb;       /**< PM flux linkage (peak, per phase) [Wb], > 0 */
    float gamma;         /**< observer gain [1/(Wb^2 s)], > 0 */
    float dt_s;          /**< step period [s], > 0 */
    float resid_tol;     /**< divergence monitor: tolerated | |e|/flux - 1 |, > 0 (e.g. 0.3) */
    float resid_time_s;  /**< ... for this long before the flag, >= 0 (e.g. 0.05) */
    float ld_minus_lq_h; /**< Ld - Lq [H], finite, l_h + it > 0; 0: a non-salient machine */
} mc_fluxobs_f32_cfg_t;

/** State. Read-only for callers. */
typedef struct {
    mc_fluxobs_f32_cfg_t cfg;
    float half_gamma_dt;   /**< gamma dt / 2 (derived) */
    float half_r_ohm;      /**< R / 2 in force: cfg.r_ohm r_scale / 2 */
    float r_scale;         /**< R in force / cfg.r_ohm (set_r_scale; 1 after init) */
    float inv_flux_per_wb; /**< 1 / flux (derived) */
    float flux2;           /**< flux^2 [Wb^2] (derived) */
    float psi_a_wb;        /**< active flux of the last step [Wb] (the flux if non-salient) */
    float x_alpha_wb;      /**< flux estimate xh [Wb] */
    float x_beta_wb;
    float i_alpha_prev_a; /**< current at the start of the step [A] */
    float i_beta_prev_a;
    float theta_e_rad; /**< angle estimate, [-pi, pi) */
    float resid;       /**< |e|/flux - 1 of the last step */
    float resid_bad_s; /**< time the residual has been out of tolerance [s] */
    uint32_t flags;    /**< sticky MC_FLUXOBS_ERR_* */
} mc_fluxobs_f32_t;

/**
 * Validate cfg, initialise st with the estimate for angle 0 at zero current
 * (xh = [flux, 0]). Returns the OR of the rules broken; on error st is not
 * written.
 */
uint32_t mc_fluxobs_f32_init(mc_fluxobs_f32_t *st, const mc_fluxobs_f32_cfg_t *cfg);

/**
 * Active flux psi_a = flux + (Ld - Lq) i_d [Wb] of cfg at the d current
 * i_d_a, floored at MC_FLUXOBS_PSI_A_MIN_FRAC flux (the floor for a NaN
 * current too). The flux itself for a non-salient cfg and a finite i_d.
 */
float mc_fluxobs_f32_eval_active_flux(const mc_fluxobs_f32_cfg_t *cfg, float i_d_a);

/**
 * Restart from an angle guess: xh = L i + psi_a c(theta_guess) (psi_a at
 * the i_d of i at theta_guess; the flux if non-salient), previous
 * current = i, sticky flags and monitor cleared. Non-finite argument:
 * MC_FLUXOBS_ERR_NAN_INPUT returned, nothing changed.
 */
uint32_t mc_fluxobs_f32_reset(mc_fluxobs_f32_t *st, float theta_guess_rad, float i_alpha_a,
                              float i_beta_a);

/**
 * R in force = cfg.r_ohm * scale from the next step on (a winding whose
 * temperature moved since R was measured). Outside
 * mc_r_scale_f32_ok (NaN included): MC_FLUXOBS_ERR_ARG, nothing
 * changed. Float arithmetic, meant for a slow loop.
 */
uint32_t mc_fluxobs_f32_set_r_scale(mc_fluxobs_f32_t *st, float scale);

/**
 * One step over the period that ended with the current sample i_ab (see the
 * discretisation above). v_ab: average alpha-beta voltage applied over that
 * period [V]. Returns the MC_FLUXOBS_ERR_* bits raised by this step
 * (NAN_INPUT, DIVERGED); st->flags keeps them.
 */
uint32_t mc_fluxobs_f32_step(mc_fluxobs_f32_t *st, float v_alpha_v, float v_beta_v, float i_alpha_a,
                             float i_beta_a);

/**
 * gamma [1/(Wb^2 s)] whose critical speed (Prop. 4) is omega_crit_m_rad_s:
 * gamma = 4 n_P omega_crit / flux^2. MC_FLUXOBS_ERR_ARG for a speed <= 0,
 * pole_pairs = 0, flux <= 0 or a non-finite result; nothing written then.
 */
uint32_t mc_fluxobs_f32_gamma_for_critical_speed(float omega_crit_m_rad_s, uint32_t pole_pairs,
                                                 float flux_wb, float *p_gamma);

/** Critical mechanical speed gamma flux^2 / (4 n_P) [rad/s]; MC_FLUXOBS_ERR_ARG as above.
 *  Salient machine: pass psi_a for flux (see the header). */
uint32_t mc_fluxobs_f32_critical_speed(float gamma, uint32_t pole_pairs, float flux_wb,
                                       float *p_omega_crit_m_rad_s);

/** Time scale T_obs = 2 / (gamma flux^2) [s] of the error dynamics; MC_FLUXOBS_ERR_ARG. */
uint32_t mc_fluxobs_f32_time_scale(float gamma, float flux_wb, float *p_t_s);

#ifdef __cplusplus
}
#endif

#endif /* MC_FLUXOBS_H */
