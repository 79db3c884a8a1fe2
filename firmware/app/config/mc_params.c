/**
 * @file mc_params.c
 * @brief Parameter access and whole-configuration validation: see mc_params.h.
 */
#include "mc_params.h"

#include <stddef.h>
#include <string.h>

#include "foc/mc_foc.h"
#include "math/mc_math.h"
#include "mc_law_cfg.h"

static float as_f32(uint32_t raw)
{
    float f;
    (void)memcpy(&f, &raw, sizeof f);
    return f;
}

const mc_param_info_t *mc_param_find(uint32_t id, uint32_t *p_idx)
{
    uint32_t lo = 0u;
    uint32_t hi = MC_PARAM_COUNT;
    while (lo < hi) { /* the generated table is sorted by id */
        const uint32_t mid = lo + (hi - lo) / 2u;
        const uint32_t mid_id = mc_param_table[mid].id;
        if (mid_id == id) {
            if (p_idx != NULL) {
                *p_idx = mid;
            }
            return &mc_param_table[mid];
        }
        if (mid_id < id) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return NULL;
}

uint32_t mc_param_get_raw(const mc_params_t *p, const mc_param_info_t *info)
{
    uint32_t raw = 0u;
    if ((p != NULL) && (info != NULL) && (info->offset != MC_PARAM_NO_FIELD)) {
        (void)memcpy(&raw, (const uint8_t *)p + info->offset, sizeof raw);
    }
    return raw;
}

mc_param_status_t mc_param_check_value(const mc_param_info_t *info, uint32_t raw)
{
    if (info == NULL) {
        return MC_PARAM_ERR_UNKNOWN_ID;
    }
    if (info->type == MC_PARAM_TYPE_F32) {
        const float v = as_f32(raw);
        /* NaN fails both compares */
        return (mc_isfinite_f32(v) && (v >= info->min.f) && (v <= info->max.f))
                   ? MC_PARAM_OK
                   : MC_PARAM_ERR_RANGE;
    }
    return ((raw >= info->min.u) && (raw <= info->max.u)) ? MC_PARAM_OK : MC_PARAM_ERR_RANGE;
}

void mc_param_set_raw(mc_params_t *p, const mc_param_info_t *info, uint32_t raw)
{
    if ((p != NULL) && (info != NULL) && (info->offset != MC_PARAM_NO_FIELD)) {
        (void)memcpy((uint8_t *)p + info->offset, &raw, sizeof raw);
    }
}

/* ------------------------------------------------------------ derivations */

static float fmin_f(float a, float b)
{
    return (b < a) ? b : a;
}

static float fmax_f(float a, float b)
{
    return (a < b) ? b : a;
}

/* A parameter's value, or its derivation when it is 0 ("0: derived"). */
static float or_derived(float v, double derived)
{
    return (v > 0.0f) ? v : (float)derived;
}

/* The drive's own derivations (the gains' are mc_gains.c's): the trip
 * above the current limit inside the sensor's range, the bus window around
 * the nominal bus (its top bounded by the board's limit), the over-speed
 * trip above the motor's top speed, and the bus-power thresholds as
 * fractions of the margin vbus_max - vbus. */
static void resolve_drive(const mc_params_t *p, const mc_gains_motor_t *m, const mc_gains_t *g,
                          mc_params_t *r)
{
    const float i_lim = (float)g->i_limit_a;
    float margin;
    r->i_trip_a = or_derived(p->i_trip_a, (double)fmin_f(1.6f * i_lim, 0.98f * p->i_sense_max_a));
    r->vbus_min_v = or_derived(p->vbus_min_v, 0.5 * (double)p->vbus_v);
    r->vbus_max_v = (float)mc_gains_vbus_max_v(m);
    r->omega_max_rad_s = or_derived(p->omega_max_rad_s, 1.5 * (double)p->speed_max_rad_s);
    margin = r->vbus_max_v - p->vbus_v;
    r->brake_on_v = or_derived(p->brake_on_v, (double)(p->vbus_v + (0.2f * margin)));
    r->brake_full_v = or_derived(p->brake_full_v, (double)(p->vbus_v + (0.45f * margin)));
    r->vbus_regen_start_v =
        or_derived(p->vbus_regen_start_v, (double)(p->vbus_v + (0.5f * margin)));
    r->vbus_regen_end_v = or_derived(p->vbus_regen_end_v, (double)(p->vbus_v + (0.8f * margin)));
    /* braking in the windings: at most half the current that cancels the
     * magnet's flux (no demagnetisation), within the current limit */
    r->regen_id_a = or_derived(p->regen_id_a, (double)fmin_f(i_lim, 0.5f * p->flux_wb / p->ld_h));
    /* the field-weakening loop d|v|/d id ~ omega_e Ld closes at a tenth of
     * the current loop's bandwidth at the top speed */
    r->fw_ki_a_per_vs = or_derived(
        p->fw_ki_a_per_vs, g->cur_bw_rad_s / (10.0 * (double)p->pole_pairs *
                                              (double)p->speed_max_rad_s * (double)p->ld_h));
}

uint32_t mc_params_resolve(const mc_params_t *p, mc_params_eff_t *e)
{
    mc_params_t *r = &e->p;
    const mc_gains_t *g = &e->g;
    const uint32_t err = mc_law_gains_from_params(p, &e->m, &e->g);
    *r = *p;
    /* the gains: given values come back unchanged (a float held in double) */
    r->current_bw_rad_s = (float)g->cur_bw_rad_s;
    r->speed_pll_bw_rad_s = (float)g->enc_pll_bw_rad_s;
    r->speed_bw_rad_s = (float)g->speed_wc_rad_s;
    r->speed_kp_a_s_rad = (float)g->speed_kp_a_s_rad;
    r->speed_ki_a_rad = (float)g->speed_ki_a_rad;
    r->speed_ramp_rad_s2 = (float)g->speed_accel_rad_s2;
    r->obs_omega_crit_m_rad_s = (float)g->obs_crit_rad_s;
    r->obs_pll_bw_rad_s = (float)g->pll_bw_rad_s;
    r->sls_speed_bw_rad_s = (float)g->sls_wc_rad_s;
    r->sls_handover_rad_s = (float)g->handover_rad_s;
    r->sls_if_current_a = (float)g->if_current_a;
    r->sls_if_accel_rad_s2 = (float)g->if_accel_rad_s2;
    r->sls_align_time_s = (float)g->align_time_s;
    r->pi2d_wn_rad_s = (float)g->pi2d_wn_rad_s;
    r->pi2d_a_per_s = (float)g->pi2d_a_per_s;
    r->pos_kp_per_s = (float)g->pos_kp_per_s;
    r->traj_v_max_rad_s = (float)g->pos_v_max_rad_s;
    r->traj_a_max_rad_s2 = (float)g->pos_a_max_rad_s2;
    r->traj_d_max_rad_s2 = (float)g->pos_d_max_rad_s2;
    r->traj_filter_bw_rad_s = (float)g->pos_filter_bw_rad_s;
    r->stop_decel_rad_s2 = (float)g->stop_decel_rad_s2;
    resolve_drive(p, &e->m, g, r);
    return err;
}

int32_t mc_param_find_name(const char *name)
{
    if (name == NULL) {
        return -1;
    }
    for (uint32_t i = 0u; i < MC_PARAM_COUNT; ++i) {
        const char *a = mc_param_names[i];
        const char *b = name;
        while ((*a != '\0') && (*a == *b)) {
            a++;
            b++;
        }
        if ((*a == '\0') && (*b == '\0')) {
            return (int32_t)i;
        }
    }
    return -1;
}

/* The thermal derating and the winding model (mc_drive_thermal.h). */
static void mc_params_thermal_cfg(const mc_params_t *p, mc_drive_thermal_cfg_t *t)
{
    t->fet_start_c = p->derate_fet_start_c;
    t->fet_end_c = p->derate_fet_end_c;
    t->motor_start_c = p->derate_motor_start_c;
    t->motor_end_c = p->derate_motor_end_c;
    t->model_enable = p->winding_model != 0u;
    t->r_ohm = p->r_ohm;
    t->i_rated_a = p->i_rated_a;
    t->rise_k = p->winding_rise_k;
    t->share = p->winding_share;
    t->tau_w_s = p->winding_tau_s;
    t->tau_h_s = p->housing_tau_s;
    t->ambient_c = p->ambient_c;
    t->r_follow = p->winding_r_follow != 0u;
}

void mc_params_eff_to_drive_cfg(const mc_params_eff_t *e, mc_drive_cfg_t *cfg)
{
    const mc_params_t *p = &e->p;
    const mc_gains_t *g = &e->g;
    const float i_lim = (float)g->i_limit_a;
    const float dt = 1.0f / (float)p->pwm_hz;
    {
        const mc_drive_cfg_t z = {0};
        *cfg = z;
    }
    /* the gains' own check ran in mc_params_resolve: L, R, bw positive */
    (void)mc_foc_f32_gains_from_bandwidth(p->r_ohm, p->ld_h, p->current_bw_rad_s,
                                          &cfg->foc.kp_d_v_per_a, &cfg->foc.ki_d_v_per_as);
    (void)mc_foc_f32_gains_from_bandwidth(p->r_ohm, p->lq_h, p->current_bw_rad_s,
                                          &cfg->foc.kp_q_v_per_a, &cfg->foc.ki_q_v_per_as);
    cfg->foc.r_ohm = p->r_ohm;
    cfg->foc.ld_h = p->ld_h;
    cfg->foc.lq_h = p->lq_h;
    cfg->foc.flux_wb = p->flux_wb;
    cfg->foc.dt_s = dt;
    cfg->foc.aw = MC_PI_AW_CLAMP;
    cfg->foc.kaw_per_s = 0.0f;
    cfg->foc.limit_mode = MC_SVPWM_LIMIT_CIRCLE;
    cfg->foc.v_limit_ratio = p->v_limit_ratio;
    cfg->foc.v_abs_max_v = p->vbus_max_v; /* static PI limit: above any usable voltage */
    cfg->foc.decouple = true;
    cfg->pole_pairs = p->pole_pairs;
    cfg->encoder_offset_rad = p->encoder_offset_rad;
    cfg->encoder_reversed = (p->encoder_reversed != 0u);
    cfg->enc_steps_checked = (p->encoder_type == MC_PARAMS_ENCODER_HALL);
    cfg->angle_ref = p->angle_ref; /* MC_DRIVE_ANGLE_REF_* is the parameter's value */
    cfg->encoder_latency_s = p->encoder_latency_s;
    cfg->i_offset_a[0] = p->i_offset_a_a;
    cfg->i_offset_a[1] = p->i_offset_b_a;
    cfg->i_offset_a[2] = p->i_offset_c_a;
    cfg->speed_pll_bw_rad_s = p->speed_pll_bw_rad_s;
    cfg->slow_loop_div = p->slow_loop_div;
    cfg->i_max_a = i_lim;
    cfg->i_trip_a = p->i_trip_a;
    cfg->vbus_min_v = p->vbus_min_v;
    cfg->vbus_max_v = p->vbus_max_v;
    cfg->omega_max_rad_s = p->omega_max_rad_s;
    cfg->temp_max_c = p->temp_max_c;
    cfg->stall_current_frac = p->stall_current_frac;
    cfg->stall_speed_rad_s = p->stall_speed_rad_s;
    cfg->stall_time_s = p->stall_time_s;
    cfg->i_unbalance_max_a = p->i_unbalance_max_a;
    cfg->open_phase_i_min_a = p->open_phase_i_min_a;
    cfg->open_phase_time_s = p->open_phase_time_s;
    cfg->asc_enable = p->asc_enable != 0u;
    /* controlled stop: the speed loop's kp, the feed-forward J decel / kt,
     * rest below 0.2 % of the rated speed the bus allows */
    cfg->stop_decel_rad_s2 = p->stop_decel_rad_s2;
    cfg->stop_rest_rad_s = (float)(0.002 * g->speed_rated_eff_rad_s);
    cfg->stop_kp_a_s_rad = p->speed_kp_a_s_rad;
    cfg->stop_iq_ff_a =
        fmin_f(i_lim, (float)((double)p->j_kgm2 * (double)p->stop_decel_rad_s2 / g->kt_nm_a));
    cfg->temp_warn_c = p->temp_warn_c;
    cfg->vbus_sag_v = p->vbus_sag_v;
    cfg->vbus_regen_start_v = p->vbus_regen_start_v;
    cfg->vbus_regen_end_v = p->vbus_regen_end_v;
    cfg->regen_id_a = p->regen_id_a;
    cfg->bus.i_bus_max_a = p->i_bus_max_a;
    cfg->bus.i_bus_regen_max_a = p->i_bus_regen_max_a;
    cfg->bus.p_bus_max_w = p->p_bus_max_w;
    cfg->bus.p_bus_regen_max_w = p->p_bus_regen_max_w;
    if (p->brake_enable != 0u) {
        cfg->brake_on_v = p->brake_on_v;
        cfg->brake_full_v = p->brake_full_v;
    }
    cfg->speed_accel_rad_s2 = p->speed_ramp_rad_s2;
    cfg->dead_time_comp = (p->dead_time_comp != 0u) && (p->dead_time_s > 0.0f);
    cfg->dead_time_s = p->dead_time_s;
    cfg->dead_band_a = fmax_f(1e-3f, 0.01f * p->i_rated_a);
    cfg->fw_enable = p->fw_enable != 0u;
    cfg->anticogging = p->anticogging != 0u;
    cfg->fw.ld_h = p->ld_h;
    cfg->fw.lq_h = p->lq_h;
    cfg->fw.flux_wb = p->flux_wb;
    cfg->fw.i_max_a = i_lim;
    cfg->fw.v_margin = p->fw_v_margin;
    cfg->fw.k_demag = 0.9f;
    cfg->fw.ki_fw_a_per_vs = p->fw_ki_a_per_vs;
    cfg->fw.dt_s = dt;
    mc_params_thermal_cfg(p, &cfg->thermal);
}

uint32_t mc_params_to_drive_cfg(const mc_params_t *p, mc_drive_cfg_t *cfg)
{
    mc_params_eff_t e;
    if ((p == NULL) || (cfg == NULL)) {
        return MC_PARAMS_ERR_NULL;
    }
    if (p->pwm_hz == 0u) {
        return MC_PARAMS_ERR_RANGE;
    }
    if (mc_params_resolve(p, &e) != MC_GAINS_OK) {
        return MC_PARAMS_ERR_GAINS;
    }
    mc_params_eff_to_drive_cfg(&e, cfg);
    return MC_PARAMS_OK;
}

uint32_t mc_params_hall_table(const mc_params_t *p, mc_hall_f32_cfg_t *t)
{
    if ((p == NULL) || (t == NULL)) {
        return MC_PARAMS_ERR_NULL;
    }
    const float edges[MC_HALL_SECTORS] = {p->hall_edge0_e_rad, p->hall_edge1_e_rad,
                                          p->hall_edge2_e_rad, p->hall_edge3_e_rad,
                                          p->hall_edge4_e_rad, p->hall_edge5_e_rad};
    uint8_t map[8];
    uint32_t k;
    for (k = 0u; k < MC_HALL_SECTORS; k++) {
        t->code_of_sector[k] = (uint8_t)((p->hall_codes >> (3u * k)) & 7u);
        t->edge_e_rad[k] = edges[k];
    }
    t->hysteresis_e_rad = p->hall_hysteresis_e_rad;
    t->dt_s = (p->pwm_hz > 0u) ? 1.0f / (float)p->pwm_hz : 0.0f;
    t->omega_min_e_rad_s = p->hall_omega_min_e_rad_s;
    return (mc_hall_f32_validate(t, map, NULL) == MC_HALL_ERR_NONE) ? MC_PARAMS_OK
                                                                    : MC_PARAMS_ERR_ENCODER;
}

uint32_t mc_params_validate(const mc_params_t *p)
{
    uint32_t err = MC_PARAMS_OK;
    mc_drive_cfg_t cfg;
    mc_params_eff_t e;
    const mc_params_t *r = &e.p;
    if (p == NULL) {
        return MC_PARAMS_ERR_NULL;
    }
    for (uint32_t i = 0u; i < MC_PARAM_COUNT; ++i) {
        const mc_param_info_t *info = &mc_param_table[i];
        if ((info->offset != MC_PARAM_NO_FIELD) &&
            (mc_param_check_value(info, mc_param_get_raw(p, info)) != MC_PARAM_OK)) {
            err |= MC_PARAMS_ERR_RANGE;
        }
    }
    if (err != MC_PARAMS_OK) {
        return err; /* the cross checks below assume every value in range */
    }
    if ((p->encoder_cpr != 0u) && (p->encoder_cpr < 4u)) {
        err |= MC_PARAMS_ERR_ENCODER;
    }
    if ((p->encoder_type == MC_PARAMS_ENCODER_HALL) &&
        ((p->encoder_cpr != 6u * p->pole_pairs) || (p->angle_ref != MC_DRIVE_ANGLE_REF_STORED))) {
        err |= MC_PARAMS_ERR_ENCODER; /* the Hall's resolution; referenced at power-up */
    }
    if (p->encoder_type == MC_PARAMS_ENCODER_HALL) {
        mc_hall_f32_cfg_t t;
        err |= mc_params_hall_table(p, &t);
    }
    /* the angle's reference is the encoder's: none to find without one */
    if ((p->encoder_cpr == 0u) &&
        ((p->angle_ref != MC_DRIVE_ANGLE_REF_STORED) || (p->angle_find_at_enable != 0u))) {
        err |= MC_PARAMS_ERR_ANGLE_REF;
    }
    if (mc_params_resolve(p, &e) != MC_GAINS_OK) {
        return err | MC_PARAMS_ERR_GAINS; /* nothing derived to check */
    }
    /* the board's bus limit: no trip above it, the nominal bus below it */
    if ((p->vbus_board_max_v > 0.0f) &&
        ((r->vbus_max_v > p->vbus_board_max_v) || !(p->vbus_v < p->vbus_board_max_v))) {
        err |= MC_PARAMS_ERR_BOARD;
    }
    /* the current sensor must see every current the drive trips on */
    if (r->i_trip_a > r->i_sense_max_a) {
        err |= MC_PARAMS_ERR_SENSE;
    }
    if (r->current_bw_rad_s > MC_PARAMS_BW_DT_MAX * (float)r->pwm_hz) {
        err |= MC_PARAMS_ERR_BANDWIDTH;
    }
    if (r->dead_time_s > MC_PARAMS_DEAD_TIME_FRAC_MAX / (float)r->pwm_hz) {
        err |= MC_PARAMS_ERR_DEAD_TIME;
    }
    if ((r->can_bitrate_bps != 125000u) && (r->can_bitrate_bps != 250000u) &&
        (r->can_bitrate_bps != 500000u) && (r->can_bitrate_bps != 1000000u)) {
        err |= MC_PARAMS_ERR_BITRATE;
    }
    mc_params_eff_to_drive_cfg(&e, &cfg);
    if (mc_drive_check_cfg(&cfg) != 0u) {
        err |= MC_PARAMS_ERR_DRIVE;
    }
    if (mc_law_speed_check(p) != 0u) {
        err |= MC_PARAMS_ERR_LAW;
    }
    if (p->hall_obs_end_e_rad_s > 0.0f) {
        mc_drive_hallobs_cfg_t hc;
        if (mc_law_hallobs_cfg(p, &hc) != MC_DRIVE_HALLOBS_ERR_NONE) {
            err |= MC_PARAMS_ERR_HALL_OBS;
        }
    }
    return err;
}
