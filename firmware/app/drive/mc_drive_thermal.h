/* mc_drive_thermal.h: thermal derating of the current limit and the
 * winding's temperature estimate (issue 33 items 1 and 2).
 *
 * Derating. Each temperature (the power stage's thermistor, the motor's
 * thermistor, the winding estimate below) gives a factor
 *     k(T) = 1 for T <= start, (end - T) / (end - start) between, 0 for T >= end
 * and the current limit in force is i_max_a min(k_fet, k_motor, k_winding).
 * A pair start = end = 0 switches that derating off. The motor pair derates
 * both the motor thermistor and the winding estimate (both stand for the
 * winding's temperature). An absent or unreadable sensor derates nothing:
 * the drive's trip (temp_max_c, the sensor's grace) handles it as before.
 * The warning (mc_drive_thermal_derating) is set when a factor falls below
 * 1 and cleared only when every temperature is MC_DRIVE_THERMAL_HYST_K below
 * its start, so it does not chatter around the start.
 *
 * Winding model (model_enable): two thermal nodes, winding (w) and housing
 * (h), to the ambient (a):
 *     C_w dT_w/dt = P_cu - (T_w - T_h) / R_wh
 *     C_h dT_h/dt = (T_w - T_h) / R_wh - (T_h - T_a) / R_ha
 *     P_cu = 3/2 R(T_w) (i_d^2 + i_q^2)      (amplitude-invariant dq)
 *     R(T) = r_ohm (1 + a (T - 20)) / (1 + a (T_a - 20)),  a = 0.00393 / K
 * (copper's coefficient at 20 C, IEC 60028). r_ohm is the drive's phase
 * resistance, taken as measured at ambient_c. The network comes from the
 * motor's rating: R_wh + R_ha makes the steady winding rise at i_rated_a
 * (with R at the hot winding) exactly rise_k; share = R_wh / (R_wh + R_ha);
 * tau_w = C_w R_wh, tau_h = C_h R_ha. Because R_total is derived from the
 * same r_ohm the losses use, an error of r_ohm cancels in the steady rise
 * (rise_k (i / i_rated)^2 R(T_w) / R(T_a + rise_k)). Defaults (params.toml,
 * the plant's mcsim::thermal_from_rating gives the same structure, written
 * independently): rise 80 K (IEC 60034-1, insulation class B by
 * resistance), share 0.3, tau_w 30 s, tau_h 900 s (small-motor catalogues,
 * 50-500 W). Integration: backward Euler per slow step (stable for any
 * step; error about dt / (2 tau) of a transient), the increments summed
 * with their rounding carried (Kahan), as a millisecond step against a
 * time constant of minutes would otherwise stall kelvins short in float.
 *
 * After a power-up the estimate starts from the motor thermistor when the
 * board has one, else from the larger of ambient_c and the power stage's
 * thermistor: heat stored before a power cycle without a motor thermistor
 * is forgotten (nothing is stored in flash), so a motor switched off hot
 * and on again is under-estimated by its remaining rise; set ambient_c to
 * the hottest start expected where that matters.
 */
#ifndef MC_DRIVE_THERMAL_H
#define MC_DRIVE_THERMAL_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MC_DRIVE_THERMAL_ERR_NONE 0u
#define MC_DRIVE_THERMAL_ERR_NULL (1u << 0) /**< NULL state or config */
#define MC_DRIVE_THERMAL_ERR_DERATE \
    (1u << 1) /**< a start/end pair not finite, negative,
                                                  end <= start, or only one of them 0 */
#define MC_DRIVE_THERMAL_ERR_MODEL \
    (1u << 2) /**< model_enable with r_ohm, i_rated_a,
                                                  rise_k, a tau <= 0 or not finite, share
                                                  outside (0, 1), ambient_c outside
                                                  [-50, 150] C */

#define MC_DRIVE_THERMAL_HYST_K       5.0f     /**< the warning clears this far below start */
#define MC_DRIVE_THERMAL_ALPHA_CU_1_K 0.00393f /**< copper, per K at 20 C (IEC 60028) */

typedef struct {
    float fet_start_c, fet_end_c;     /**< power-stage thermistor derating [C] (0, 0: off) */
    float motor_start_c, motor_end_c; /**< motor thermistor and winding estimate [C] */
    bool model_enable;                /**< run the winding model */
    float r_ohm;                      /**< phase resistance at ambient_c [ohm] */
    float i_rated_a;                  /**< continuous current (dq amplitude) [A] */
    float rise_k;                     /**< steady winding rise at i_rated_a [K] */
    float share;                      /**< R_wh / (R_wh + R_ha), (0, 1) */
    float tau_w_s;                    /**< C_w R_wh [s] */
    float tau_h_s;                    /**< C_h R_ha [s] */
    float ambient_c;                  /**< ambient; the estimate's start without sensors [C] */
    bool r_follow;                    /**< with model_enable: the law's R follows the estimate
                        (mc_drive_thermal_r_scale) */
} mc_drive_thermal_cfg_t;

/** One slow step's temperatures; a sensor absent or without a reading has
 *  its flag false (its value is then ignored). */
typedef struct {
    float fet_c;
    float motor_c;
    bool fet_ok;
    bool motor_ok;
} mc_drive_thermal_in_t;

typedef struct {
    mc_drive_thermal_cfg_t cfg;
    float r_wh_k_w, r_ha_k_w; /**< the network from the rating [K/W] */
    float c_w_j_k, c_h_j_k;   /**< heat capacities [J/K] */
    float t_w_c, t_h_c;       /**< the estimate: winding, housing [C] */
    float t_w_lo, t_h_lo;     /**< their rounding carried (compensated sums) [K] */
    float k;                  /**< derating factor in force, [0, 1] */
    bool started;             /**< the estimate has its initial temperature */
    bool derating;            /**< the warning, with hysteresis */
} mc_drive_thermal_t;

/** Validates cfg and starts the state (k = 1, the estimate unset until the
 *  first step). On error *th is unchanged. */
uint32_t mc_drive_thermal_init(mc_drive_thermal_t *th, const mc_drive_thermal_cfg_t *cfg);

/** The factor k(T) of one start/end pair (1 when the pair is off or t_c is
 *  not finite). */
float mc_drive_thermal_factor(float t_c, float start_c, float end_c);

/** One slow step of dt_s [s] with the mean i_d^2 + i_q^2 [A^2] over it
 *  (0 with the bridge off): advances the estimate, updates k and the
 *  warning; returns k. */
float mc_drive_thermal_step(mc_drive_thermal_t *th, float dt_s, float i_sq_a2,
                            const mc_drive_thermal_in_t *in);

/** The scale of the phase resistance in force: R(T_w) / R(ambient_c) of
 *  copper at the winding estimate when the model runs with r_follow and has
 *  started, else 1. The drive's slow step hands it to its current loop
 *  (mc_foc_f32_set_r_scale: ki = R bw) and to a running law
 *  (mc_drive_ctrl_t.set_r_scale: the sensorless observer's R); measured
 *  effect in firmware/app/README.md (thermal). */
float mc_drive_thermal_r_scale(const mc_drive_thermal_t *th);

/** The current limit in force: i_max_a times the factor of the last step. */
static inline float mc_drive_thermal_limit_a(const mc_drive_thermal_t *th, float i_max_a)
{
    return th->k * i_max_a;
}

#ifdef __cplusplus
}
#endif

#endif /* MC_DRIVE_THERMAL_H */
