/**
 * @file mc_fw.h
 * @brief Current reference shaping for PMSMs (float32): MTPA below base
 *        speed, voltage-feedback field weakening above it, the demagnetisation
 *        bound on the d current and the current circle.
 *
 * Input: a signed current command i_cmd_a (the speed loop's output, "how
 * much current, which direction of torque") and the dq voltage the current
 * loop applied in the last step. Output: (id_ref, iq_ref).
 *
 * MTPA (Ld != Lq; amplitude-invariant dq, torque 3/2 p iq (flux + (Ld - Lq) id)):
 * for the current magnitude I = |i_cmd| the d current that maximises torque is
 *   id_mtpa = (flux - sqrt(flux^2 + 8 dL^2 I^2)) / (4 dL),  dL = Lq - Ld,
 * (from dT/dbeta = 0 with id = -I sin beta, iq = I cos beta), and
 * iq = sign(i_cmd) sqrt(I^2 - id^2). Non-salient (|dL| <= 1e-3 max(Ld, Lq)):
 * id_mtpa = 0, iq = i_cmd, bit for bit.
 *
 * Field weakening (voltage feedback): v_max = v_margin * vbus / sqrt(3)
 * (inside the SVPWM circle; the current loop's own limit must be above it so
 * the loop is never saturated in steady state). An integrator
 *   id_fw += ki_fw * (v_max - |v_dq|) * dt,  clamped to [id_min, 0]
 * pulls the d current negative while the applied voltage exceeds v_max and
 * gives it back below. id = max(id_min, min(id_mtpa, id_mtpa + id_fw)); then
 * iq is limited to the circle sqrt(i_max^2 - id^2) (d-axis priority: the d
 * current that keeps the machine controllable wins over torque).
 *
 * Demagnetisation bound: id_min = -k_demag flux / Ld (k_demag in (0, 1]),
 * and never below -i_max. At id = -flux/Ld the magnet's flux is fully
 * cancelled; the magnet's knee lies beyond, but the bound keeps the working
 * point away from it with any k_demag < 1 and also caps the short-circuit
 * current at a loss of control (see README.md).
 *
 * Loss of control (documented, not handled here): with the bridge off the
 * diodes rectify the back-EMF as soon as its line-to-line peak sqrt(3) p
 * flux omega_m exceeds vbus, i.e. above omega_uncontrolled = vbus /
 * (sqrt(3) p flux): the machine brakes into the bus (over-voltage). Above
 * that speed, an active short circuit (all low-side switches on) is the
 * safer reaction when the short-circuit current flux/Ld is within the
 * machine's and the switches' rating.
 */
#ifndef MC_FW_H
#define MC_FW_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MC_FW_ERR_NONE  0u
#define MC_FW_ERR_NULL  (1u << 0) /**< NULL pointer */
#define MC_FW_ERR_MOTOR (1u << 1) /**< ld, lq, flux not > 0 or not finite */
#define MC_FW_ERR_LIMIT \
    (1u << 2)                     /**< i_max not > 0, v_margin not in (0, 1],
                                          k_demag not in (0, 1] */
#define MC_FW_ERR_GAIN  (1u << 3) /**< ki_fw < 0, dt not > 0, not finite */
#define MC_FW_ERR_INPUT (1u << 4) /**< a non-finite input (state unchanged) */

typedef struct {
    float ld_h;           /**< d inductance [H], > 0 */
    float lq_h;           /**< q inductance [H], > 0 */
    float flux_wb;        /**< PM flux linkage [Wb], > 0 */
    float i_max_a;        /**< current circle radius [A], > 0 */
    float v_margin;       /**< v_max = v_margin vbus / sqrt 3, (0, 1] */
    float ki_fw_a_per_vs; /**< FW integrator gain [A/(V s)], >= 0 (0: FW off) */
    float k_demag;        /**< id >= -k_demag flux / Ld, (0, 1] */
    float dt_s;           /**< step [s], > 0 */
} mc_fw_f32_cfg_t;

typedef struct {
    mc_fw_f32_cfg_t cfg;
    float dl_h;     /**< Lq - Ld (derived) */
    bool salient;   /**< |dL| > 1e-3 max(Ld, Lq) (derived) */
    float id_min_a; /**< demagnetisation / circle bound [A] (derived) */
    float id_fw_a;  /**< FW integrator [A], in [id_min, 0] */
} mc_fw_f32_t;

typedef struct {
    float i_cmd_a;    /**< signed current command [A] */
    float vd_v, vq_v; /**< voltage applied by the current loop last step [V] */
    float vbus_v;     /**< DC bus [V] */
} mc_fw_f32_in_t;

typedef struct {
    float id_ref_a, iq_ref_a;
    float id_mtpa_a; /**< the MTPA d current for |i_cmd| */
    float v_mag_v;   /**< |v_dq| seen */
    float v_max_v;   /**< the FW target */
} mc_fw_f32_out_t;

/** Validate cfg, derive, reset. Returns MC_FW_ERR_* (0: ok; on error st unchanged). */
uint32_t mc_fw_f32_init(mc_fw_f32_t *st, const mc_fw_f32_cfg_t *cfg);
/** Integrator to 0. */
uint32_t mc_fw_f32_reset(mc_fw_f32_t *st);
/** MTPA d current for the magnitude i_abs_a (0 for a non-salient machine). */
float mc_fw_f32_mtpa_id(const mc_fw_f32_t *st, float i_abs_a);
/** One step. Returns MC_FW_ERR_INPUT on a non-finite input (out: MTPA-free
 *  zero references, state unchanged). */
uint32_t mc_fw_f32_step(mc_fw_f32_t *st, const mc_fw_f32_in_t *in, mc_fw_f32_out_t *out);

#ifdef __cplusplus
}
#endif

#endif /* MC_FW_H */
