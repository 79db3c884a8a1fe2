/**
 * @file mc_law_cfg.c
 * @brief The control laws' configurations from the gains: see mc_law_cfg.h.
 */
#include "mc_law_cfg.h"

#include <string.h>

#include "math/mc_math.h"

static double dmax(double a, double b)
{
    return (a < b) ? b : a; /* std::max's choice */
}

static double dabs(double x)
{
    return (x < 0.0) ? -x : x;
}

/* std::round of x >= 0 (half away from zero) */
static double round_pos(double x)
{
    const double f = (double)(uint64_t)x; /* floor; x - f is exact */
    return ((x - f) >= 0.5) ? (f + 1.0) : f;
}

void mc_law_sls_cfg(const mc_gains_motor_t *m, const mc_gains_t *g, mc_ctrl_sls_cfg_t *c)
{
    (void)memset(c, 0, sizeof *c); /* padding too: configurations compare bytewise */
    c->r_ohm = (float)m->r_ohm;
    c->l_h = (float)m->lq_h;
    c->flux_wb = (float)m->flux_wb;
    c->pole_pairs = (uint32_t)m->pole_pairs;
    /* a salient machine: the active-flux observer and MTPA's d current
     * (mc_ctrl_sensorless.h); mc_app leaves MTPA to the drive when its own
     * runs (fw_enable) */
    c->ld_minus_lq_h = (float)(m->ld_h - m->lq_h);
    c->law_mtpa = true;
    c->dt_s = (float)(1.0 / m->pwm_hz);
    c->pwm_delay_periods = (uint32_t)m->delay_periods;
    c->speed_div = (uint32_t)dmax(1.0, round_pos(m->pwm_hz / 1000.0)); /* about 1 kHz */
    c->dead_time_s = (float)m->dead_time_s;
    c->dead_band_a = (float)dmax(1e-3, 0.01 * m->i_rated_a);
    c->dead_comp_duty = true;
    c->omega_crit_m_rad_s = (float)g->obs_crit_rad_s;
    c->resid_tol = 0.3f;
    c->resid_time_s = 0.05f;
    c->pll_bw_rad_s = (float)g->pll_bw_rad_s;
    c->cur_bw_rad_s = (float)g->cur_bw_rad_s;
    c->v_limit_ratio = 0.95f;
    c->vbus_max_v = (float)mc_gains_vbus_max_v(m); /* the drive's trip (mc_params.c) */
    /* the sensored PI's formula at the sensorless crossover; a refusal
     * (J or kt not positive) leaves 0, which mc_ctrl_sls_init refuses */
    (void)mc_gains_speed_pi(m->j_kgm2, g->kt_nm_a, g->sls_wc_rad_s, &c->speed_kp_a_s_rad,
                            &c->speed_ki_a_rad);
    /* the I-f vector may reach 1.25 iq */
    c->iq_max_a = (float)(g->i_limit_a / 1.25);
    c->speed_slew_rad_s2 = (float)mc_gains_sls_slew_rad_s2(m, g);
    c->speed_max_rad_s = (float)g->speed_limit_rad_s;
    c->if_current_a = (float)g->if_current_a;
    c->align_time_s = (float)g->align_time_s;
    c->if_accel_rad_s2 = (float)g->if_accel_rad_s2;
    c->handover_speed_rad_s = (float)g->handover_rad_s;
    c->handover_hyst = 0.3f;
    c->lock_tol = 0.2f;
    c->if_lock_timeout_s = 0.5f;
    c->blend_time_s = 0.05f;
    c->lowspeed_fallback = true;
    c->if_damping = true;
    c->align_any_angle = true; /* the rotor may start anywhere */
    c->ref_from_drive = true;  /* the drive shapes the reference (ramp, stop) */
}

void mc_law_speed_cfg(const mc_gains_motor_t *m, const mc_gains_t *g, mc_ctrl_speed_cfg_t *c)
{
    (void)memset(c, 0, sizeof *c); /* padding too: configurations compare bytewise */
    c->kp_a_s_rad = (float)g->speed_kp_a_s_rad;
    c->ki_a_rad = (float)g->speed_ki_a_rad;
    c->dt_s = (float)(1.0 / m->pwm_hz);
    c->iq_max_a = (float)g->i_limit_a;
    c->kt_nm_a = (float)g->kt_nm_a;
    c->j_kgm2 = (float)m->j_kgm2;
    c->b_nm_s_rad = (float)m->b_nm_s_rad;
    c->pole_pairs = (uint32_t)m->pole_pairs;
    c->ref_lag_s = (float)((1.0 / g->cur_bw_rad_s) + (1.5 / m->pwm_hz));
}

uint32_t mc_law_pi2d_cfg(const mc_gains_motor_t *m, const mc_gains_t *g, mc_ctrl_pi2d_cfg_t *cc)
{
    /* linearised mechanical loop s^3 + kd (b/a) s^2 + (kp - ki b/a) s + ki
     * with a triple pole at -wn (as the pi2d-motor scenario) */
    const double wn = g->pi2d_wn_rad_s;
    const double a = g->pi2d_a_per_s;
    const double bb = 1.0;
    const double ki = wn * wn * wn;
    const double kd = 3.0 * wn * a / bb;
    const double kp = 3.0 * wn * wn + ki * bb / a;
    const double lmax = dmax(m->ld_h, m->lq_h);
    mc_pi2d_f32_cfg_t *c = &cc->law;
    uint32_t err = MC_GAINS_OK;
    (void)memset(cc, 0, sizeof *cc);
    c->r_ohm = (float)m->r_ohm;
    c->l_h = (float)m->lq_h;
    c->pole_pairs = (uint32_t)m->pole_pairs;
    c->ke_v_s_rad = (float)(m->pole_pairs * m->flux_wb);
    c->kt_nm_a = (float)g->kt_nm_a;
    c->j_kgm2 = (float)m->j_kgm2;
    c->k1_per_s = (float)g->cur_bw_rad_s;
    c->k2_per_s = (float)g->cur_bw_rad_s;
    c->kp_per_s2 = (float)kp;
    c->kd_per_s2 = (float)kd;
    c->ki_per_s3 = (float)ki;
    c->a_per_s = (float)a;
    c->b = (float)bb;
    c->eps_per_s = (float)(2.0 * ki / kp);
    c->dt_s = (float)(1.0 / m->pwm_hz);
    c->iq_max_a = (float)g->i_limit_a;
    c->v_max_v = (float)g->v_max_v;
    c->nu_max_nm = (float)(2.0 * g->torque_rated_nm);
    cc->limit_mode = MC_SVPWM_LIMIT_CIRCLE;
    /* the board's delay plus half a period (mc_ctrl_pi2d.h) */
    cc->angle_advance_periods = (float)(m->delay_periods + 0.5);
    cc->ref_from_drive = true; /* the drive shapes the reference (ramp, stop) */
    if (!(a >= 3.0 * wn)) {
        err |= MC_GAINS_ERR_PI2D_FILTER;
    }
    if (!(g->pi2d_coupling <= MC_GAINS_PI2D_COUPLING_MAX)) {
        err |= MC_GAINS_ERR_PI2D_COUPLING;
    }
    if (dabs(m->ld_h - m->lq_h) > 0.05 * lmax) {
        err |= MC_GAINS_ERR_SALIENT;
    }
    return err;
}

void mc_law_pos_cfg(const mc_gains_motor_t *m, const mc_gains_t *g, mc_ctrl_pos_cfg_t *c)
{
    (void)memset(c, 0, sizeof *c);
    c->dt_s = (float)(1.0 / m->pwm_hz);
    c->pole_pairs = (uint32_t)m->pole_pairs;
    c->traj.v_max_rad_s = (float)g->pos_v_max_rad_s;
    c->traj.a_max_rad_s2 = (float)g->pos_a_max_rad_s2;
    c->traj.d_max_rad_s2 = (float)g->pos_d_max_rad_s2;
    c->traj.filter_bw_rad_s = (float)g->pos_filter_bw_rad_s;
    c->traj.dt_s = c->dt_s;
    c->pos_kp_per_s = (float)g->pos_kp_per_s;
    /* the sensored speed PI (speed_kp, speed_ki: derived at speed_wc
     * unless set) */
    c->vel_kp_a_s_rad = (float)g->speed_kp_a_s_rad;
    c->vel_ki_a_rad = (float)g->speed_ki_a_rad;
    c->vel_limit_rad_s = (float)g->speed_limit_rad_s;
    c->iq_max_a = (float)g->i_limit_a;
    c->kt_nm_a = (float)g->kt_nm_a;
    c->j_kgm2 = (float)m->j_kgm2;
    c->b_nm_s_rad = (float)m->b_nm_s_rad;
    /* torque lags its reference by the current loop's 1/bw plus the
     * computation delay and half a period (the PWM's zero-order hold) */
    c->ff_lead_s = (float)(1.0 / g->cur_bw_rad_s + (m->delay_periods + 0.5) / m->pwm_hz);
}

void mc_law_motor_from_params(const mc_params_t *p, mc_gains_motor_t *m)
{
    m->r_ohm = (double)p->r_ohm;
    m->ld_h = (double)p->ld_h;
    m->lq_h = (double)p->lq_h;
    m->flux_wb = (double)p->flux_wb;
    m->pole_pairs = (double)p->pole_pairs;
    m->j_kgm2 = (double)p->j_kgm2;
    m->b_nm_s_rad = (double)p->b_nm_s_rad;
    m->i_max_a = (double)p->i_max_a;
    m->i_rated_a = (double)p->i_rated_a;
    m->speed_max_rad_s = (double)p->speed_max_rad_s;
    m->speed_rated_rad_s = (double)p->speed_rated_rad_s;
    m->vbus_v = (double)p->vbus_v;
    m->pwm_hz = (double)p->pwm_hz;
    m->dead_time_s = (double)p->dead_time_s;
    m->i_sense_max_a = (double)p->i_sense_max_a;
    m->delay_periods = 1.0;
    m->vbus_max_v = (double)p->vbus_max_v;
    m->vbus_board_max_v = (double)p->vbus_board_max_v;
    m->encoder_cpr = (double)p->encoder_cpr;
    m->encoder_latency_s = (double)p->encoder_latency_s;
}

uint32_t mc_law_hallobs_cfg(const mc_params_t *p, mc_drive_hallobs_cfg_t *c)
{
    mc_gains_motor_t m;
    mc_gains_t g;
    mc_ctrl_sls_cfg_t s;
    mc_drive_hallobs_t probe;
    uint32_t err = MC_DRIVE_HALLOBS_ERR_NONE;

    (void)memset(c, 0, sizeof *c);
    c->blend.omega_start_e_rad_s = p->hall_obs_start_e_rad_s;
    c->blend.omega_end_e_rad_s = p->hall_obs_end_e_rad_s;
    c->blend.disagree_max_e_rad = p->hall_obs_disagree_e_rad;
    if (p->encoder_type != MC_PARAMS_ENCODER_HALL) {
        err |= MC_DRIVE_HALLOBS_ERR_NOT_HALL;
    }
    if ((mc_law_gains_from_params(p, &m, &g) != MC_GAINS_OK) || !(m.r_ohm >= 0.0) ||
        !(m.lq_h > 0.0) || !(m.flux_wb > 0.0) ||
        (dabs(m.ld_h - m.lq_h) > 0.05 * dmax(m.ld_h, m.lq_h))) {
        return err | MC_DRIVE_HALLOBS_ERR_MOTOR;
    }
    mc_law_sls_cfg(&m, &g, &s);
    c->r_ohm = s.r_ohm;
    c->l_h = s.l_h;
    c->flux_wb = s.flux_wb;
    if (mc_fluxobs_f32_gamma_for_critical_speed(s.omega_crit_m_rad_s, s.pole_pairs, s.flux_wb,
                                                &c->gamma) != MC_FLUXOBS_ERR_NONE) {
        err |= MC_DRIVE_HALLOBS_ERR_OBSERVER;
    }
    c->resid_tol = s.resid_tol;
    c->resid_time_s = s.resid_time_s;
    c->pll_bw_rad_s = s.pll_bw_rad_s;
    c->omega_max_e_rad_s = 2.0f * s.speed_max_rad_s * (float)s.pole_pairs;
    c->dt_s = s.dt_s;
    c->pwm_delay_periods = s.pwm_delay_periods;
    return err | mc_drive_hallobs_init(&probe, c);
}

uint32_t mc_law_speed_check(const mc_params_t *p)
{
    mc_gains_motor_t m;
    mc_gains_t g;
    uint32_t err;
    if (p->speed_law == MC_LAW_SPEED_PI) {
        return MC_GAINS_OK;
    }
    err = mc_law_gains_from_params(p, &m, &g);
    if (err != MC_GAINS_OK) {
        return err;
    }
    if (p->speed_law == MC_LAW_SPEED_PI2D) {
        mc_ctrl_pi2d_cfg_t c;
        return mc_law_pi2d_cfg(&m, &g, &c);
    }
    /* sensorless: any machine (a salient one with the active-flux observer
     * and MTPA, mc_ctrl_sensorless.h); its own checks are its init's */
    return MC_GAINS_OK;
}

/* A fixed gain from a parameter: 0 means derived (NaN for mc_gains_derive). */
static double fixed(float v)
{
    return (v > 0.0f) ? (double)v : __builtin_nan("");
}

uint32_t mc_law_gains_from_params(const mc_params_t *p, mc_gains_motor_t *m, mc_gains_t *g)
{
    mc_gains_t fix;
    mc_law_motor_from_params(p, m);
    mc_gains_fix_none(&fix);
    fix.cur_bw_rad_s = fixed(p->current_bw_rad_s);
    fix.enc_pll_bw_rad_s = fixed(p->speed_pll_bw_rad_s);
    fix.speed_wc_rad_s = fixed(p->speed_bw_rad_s);
    fix.speed_kp_a_s_rad = fixed(p->speed_kp_a_s_rad);
    fix.speed_ki_a_rad = fixed(p->speed_ki_a_rad);
    fix.speed_accel_rad_s2 = fixed(p->speed_ramp_rad_s2);
    fix.obs_crit_rad_s = fixed(p->obs_omega_crit_m_rad_s);
    fix.pll_bw_rad_s = fixed(p->obs_pll_bw_rad_s);
    fix.sls_wc_rad_s = fixed(p->sls_speed_bw_rad_s);
    fix.handover_rad_s = fixed(p->sls_handover_rad_s);
    fix.if_current_a = fixed(p->sls_if_current_a);
    fix.if_accel_rad_s2 = fixed(p->sls_if_accel_rad_s2);
    fix.align_time_s = fixed(p->sls_align_time_s);
    fix.pi2d_wn_rad_s = fixed(p->pi2d_wn_rad_s);
    fix.pi2d_a_per_s = fixed(p->pi2d_a_per_s);
    fix.pos_kp_per_s = fixed(p->pos_kp_per_s);
    fix.pos_v_max_rad_s = fixed(p->traj_v_max_rad_s);
    fix.pos_a_max_rad_s2 = fixed(p->traj_a_max_rad_s2);
    fix.pos_d_max_rad_s2 = fixed(p->traj_d_max_rad_s2);
    fix.pos_filter_bw_rad_s = fixed(p->traj_filter_bw_rad_s);
    fix.stop_decel_rad_s2 = fixed(p->stop_decel_rad_s2);
    return mc_gains_derive(m, &fix, g);
}

void mc_law_find_cfg(const mc_params_t *p, const mc_gains_motor_t *m, const mc_gains_t *g,
                     const mc_drive_cfg_t *dc, const mc_hal_encoder_t *p_enc,
                     mc_ctrl_align_cfg_t *al, mc_ctrl_idx_cfg_t *ix)
{
    const double pi = 3.14159265358979323846;
    const double pp = dmax(1.0, m->pole_pairs);
    const double i =
        (p->angle_find_current_a > 0.0f) ? (double)p->angle_find_current_a : 0.5 * g->i_rated_eff_a;
    const double kt = g->kt_nm_a;
    const double k = dabs(kt * i * pp); /* the vector's spring [N m / rad mech.] */
    const double damp =
        (kt > 0.0) ? 2.0 * 0.7 * (double)mc_sqrt_f32((float)(k * m->j_kgm2)) / kt : 0.0;
    const double sweep = pi / 2.0;
    const double cpr = (p->encoder_cpr > 0u) ? (double)p->encoder_cpr : 1.0;
    const double band = 4.0 * 2.0 * pi / cpr;
    (void)memset(al, 0, sizeof *al); /* padding too: configurations compare bytewise */
    (void)memset(ix, 0, sizeof *ix);
    al->foc = dc->foc;
    al->pole_pairs = dc->pole_pairs;
    al->i_max_a = dc->i_max_a;
    al->i_align_a = (float)i;
    al->t_ramp_s = 0.05f;
    al->t_settle_s = 0.1f;
    al->t_timeout_s = 2.0f;
    al->still_band_m_rad = (float)((band < 0.1) ? band : 0.1);
    al->sweep_e_rad = (float)sweep;
    al->omega_sweep_e_rad_s = 20.0f;
    al->sweep_tol_e_rad = 0.3f;
    al->load_tol_e_rad = 0.1f;
    al->damping_a_s_rad = (float)damp;
    al->travel_max_m_rad = (p->angle_find_travel_rad > 0.0f)
                               ? p->angle_find_travel_rad
                               : (float)(1.5 * (pi + 3.0 * sweep) / pp);
    ix->foc = dc->foc;
    ix->pole_pairs = dc->pole_pairs;
    ix->i_max_a = dc->i_max_a;
    ix->i_search_a = (float)i;
    ix->t_ramp_s = 0.05f;
    ix->omega_search_e_rad_s = (float)((10.0 * pp < 2000.0) ? 10.0 * pp : 2000.0);
    ix->damping_a_s_rad = (float)damp;
    ix->travel_max_m_rad =
        (p->angle_find_travel_rad > 0.0f) ? p->angle_find_travel_rad : (float)(1.25 * 2.0 * pi);
    ix->first_direction = 1;
    ix->p_enc = p_enc;
}
