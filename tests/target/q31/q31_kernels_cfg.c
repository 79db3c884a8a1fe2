/* Configurations of the q31 kernels for the target sweep and benchmark
 * (see q31_kernels_cfg.h). */
#include "q31_kernels_cfg.h"

#include <string.h>

void mc_q31cfg_ddiff(mc_ddiff_q31_cfg_t *c)
{
    c->f.a_per_s = 50.0f;
    c->f.b = 50.0f;
    c->f.dt_s = 1e-4f;
    c->y_base = 1.0f;
    c->out_base = 4.0f;
}

void mc_q31cfg_spdpll(mc_spdpll_q31_cfg_t *c)
{
    c->f.bw_rad_s = 300.0f;
    c->f.dt_s = 1.25e-4f;
    c->f.omega_max_rad_s = 1500.0f;
    c->omega_base_rad_s = 2000.0f;
}

void mc_q31cfg_fluxobs(mc_fluxobs_q31_cfg_t *c)
{
    float gamma = 0.0f;
    (void)mc_fluxobs_f32_gamma_for_critical_speed(2.1f, 4u, 0.11f, &gamma);
    c->f.r_ohm = 0.675f;
    c->f.l_h = 1.14e-3f;
    c->f.flux_wb = 0.11f;
    c->f.gamma = gamma;
    c->f.dt_s = 1.25e-4f;
    c->f.resid_tol = 0.3f;
    c->f.resid_time_s = 0.05f;
    c->f.ld_minus_lq_h = 0.0f; /* non-salient */
    c->i_base_a = 20.0f;
    c->v_base_v = 400.0f;
    c->flux_base_wb = 0.25f;
}

void mc_q31cfg_foc(mc_foc_q31_cfg_t *c)
{
    float kp = 0.0f;
    float ki = 0.0f;
    (void)mc_foc_f32_gains_from_bandwidth(0.675f, 1.14e-3f, 3141.59f, &kp, &ki);
    memset(c, 0, sizeof *c);
    c->f.r_ohm = 0.675f;
    c->f.ld_h = 1.14e-3f;
    c->f.lq_h = 1.14e-3f;
    c->f.flux_wb = 0.11f;
    c->f.kp_d_v_per_a = kp;
    c->f.ki_d_v_per_as = ki;
    c->f.kp_q_v_per_a = kp;
    c->f.ki_q_v_per_as = ki;
    c->f.dt_s = 5e-5f;
    c->f.aw = MC_PI_AW_CLAMP;
    c->f.limit_mode = MC_SVPWM_LIMIT_CIRCLE;
    c->f.v_limit_ratio = 0.95f;
    c->f.v_abs_max_v = 300.0f;
    c->f.decouple = true;
    c->i_base_a = 50.0f;
    c->v_base_v = 400.0f;
    c->omega_base_rad_s = 1000.0f;
}

void mc_q31cfg_pi2d(mc_pi2d_q31_cfg_t *c)
{
    memset(c, 0, sizeof *c);
    c->f.r_ohm = 1.0f;
    c->f.l_h = 1.0f;
    c->f.pole_pairs = 1u;
    c->f.ke_v_s_rad = 0.17f;
    c->f.kt_nm_a = 0.51f;
    c->f.j_kgm2 = 1.0f;
    c->f.k1_per_s = 4.0f;
    c->f.k2_per_s = 75.0f;
    c->f.kp_per_s2 = 5.0f;
    c->f.kd_per_s2 = 10.0f;
    c->f.ki_per_s3 = 0.01f;
    c->f.a_per_s = 50.0f;
    c->f.b = 50.0f;
    c->f.eps_per_s = 0.02f;
    c->f.dt_s = 1e-4f;
    c->f.iq_max_a = 6.0f;
    c->f.v_max_v = 60.0f;
    c->f.nu_max_nm = 3.0f;
    c->base.i_base_a = 8.0f;
    c->base.v_base_v = 100.0f;
    c->base.theta_base_rad = 1.0f;
    c->base.thetaf_base_rad = 4.0f;
    c->base.omega_base_rad_s = 20.0f;
    c->base.alpha_base_rad_s2 = 20.0f;
    c->base.jerk_base_rad_s3 = 20.0f;
    c->base.did_base_a_s = 10.0f;
    c->base.nu_base_nm = 4.0f;
}

void mc_q31cfg_csmc(mc_csmc_q31_cfg_t *c)
{
    memset(c, 0, sizeof *c);
    c->f.law = MC_CSMC_LAW_MODEL;
    c->f.sw = MC_CSMC_SW_SAT;
    c->f.k1_per_s2 = 7.5e4f;
    c->f.k2_per_s = 550.0f;
    c->f.mu1_a = 0.1f;
    c->f.mu2_rad_s2 = 50.0f;
    (void)mc_csvc_f32_integrator(20.0f, &c->f.sigma1);
    (void)mc_csvc_f32_integrator(100.0f, &c->f.sigma2);
    c->f.m1_v = 50.0f;
    c->f.m2_v = 50.0f;
    c->f.model.km_nm_a = 0.1349f;
    c->f.model.j_kgm2 = 4.1295e-4f;
    c->f.model.b_nms_rad = 0.0013f;
    c->f.model.rotor_teeth = 50u;
    c->f.model.tau_load_nm = 0.2f;
    c->f.model.r_nom_ohm = 20.0f;
    c->f.model.r_min_ohm = 19.0f;
    c->f.model.r_max_ohm = 21.0f;
    c->f.model.l_nom_h = 0.035f;
    c->f.model.l_min_h = 0.030f;
    c->f.model.l_max_h = 0.040f;
    c->f.model.q1_v = 2.1f * 20.0f * 0.1f * 0.040f;
    c->f.model.q2_radh_s3 = 2.1f * 100.0f * 50.0f * 0.040f;
    c->f.v_limit_v = 1.0e4f;
    c->f.dt_s = 1e-5f;
    c->base.i_base_a = 20.0f;
    c->base.theta_base_rad = 0.5f;
    c->base.omega_base_rad_s = 200.0f;
    c->base.alpha_base_rad_s2 = 1.0e5f;
    c->base.did_base_a_s = 1.0e5f;
    c->base.jerk_base_rad_s3 = 1.0e7f;
    c->base.g_base_rad_s3 = 1.0e9f;
    c->base.v_base_v = 2.0e4f;
}

void mc_q31cfg_hgo(mc_hgo_q31_cfg_t *c)
{
    c->f.alpha1 = 17.0f;
    c->f.alpha2 = 80.0f;
    c->f.alpha3 = 100.0f;
    c->f.eps_s = 1e-4f;
    c->f.dt_s = 1e-5f;
    c->f.input_order = 2u;
    c->y_base = 0.1f;
    c->z2_base = 200.0f;
    c->z3_base = 1.0e5f;
}
