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

uint32_t mc_params_to_drive_cfg(const mc_params_t *p, mc_drive_cfg_t *cfg)
{
    float kp_d = 0.0f;
    float ki_d = 0.0f;
    float kp_q = 0.0f;
    float ki_q = 0.0f;
    if ((p == NULL) || (cfg == NULL)) {
        return MC_PARAMS_ERR_NULL;
    }
    if ((p->pwm_hz == 0u) ||
        (mc_foc_f32_gains_from_bandwidth(p->r_ohm, p->ld_h, p->current_bw_rad_s, &kp_d, &ki_d) !=
         0u) ||
        (mc_foc_f32_gains_from_bandwidth(p->r_ohm, p->lq_h, p->current_bw_rad_s, &kp_q, &ki_q) !=
         0u)) {
        return MC_PARAMS_ERR_RANGE;
    }
    {
        const mc_drive_cfg_t z = {0};
        *cfg = z;
    }
    cfg->foc.r_ohm = p->r_ohm;
    cfg->foc.ld_h = p->ld_h;
    cfg->foc.lq_h = p->lq_h;
    cfg->foc.flux_wb = p->flux_wb;
    cfg->foc.kp_d_v_per_a = kp_d;
    cfg->foc.ki_d_v_per_as = ki_d;
    cfg->foc.kp_q_v_per_a = kp_q;
    cfg->foc.ki_q_v_per_as = ki_q;
    cfg->foc.dt_s = 1.0f / (float)p->pwm_hz;
    cfg->foc.aw = MC_PI_AW_CLAMP;
    cfg->foc.kaw_per_s = 0.0f;
    cfg->foc.limit_mode = MC_SVPWM_LIMIT_CIRCLE;
    cfg->foc.v_limit_ratio = p->v_limit_ratio;
    cfg->foc.v_abs_max_v = p->vbus_max_v; /* static PI limit: above any usable voltage */
    cfg->foc.decouple = true;
    cfg->pole_pairs = p->pole_pairs;
    cfg->encoder_offset_rad = p->encoder_offset_rad;
    cfg->encoder_reversed = (p->encoder_reversed != 0u);
    cfg->i_offset_a[0] = p->i_offset_a_a;
    cfg->i_offset_a[1] = p->i_offset_b_a;
    cfg->i_offset_a[2] = p->i_offset_c_a;
    cfg->speed_pll_bw_rad_s = p->speed_pll_bw_rad_s;
    cfg->slow_loop_div = p->slow_loop_div;
    cfg->i_max_a = p->i_max_a;
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
    return MC_PARAMS_OK;
}

uint32_t mc_params_validate(const mc_params_t *p)
{
    uint32_t err = MC_PARAMS_OK;
    mc_drive_cfg_t cfg;
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
    /* the current sensor must see every current the drive allows or trips on */
    if ((p->i_max_a > p->i_sense_max_a) || (p->i_trip_a > p->i_sense_max_a)) {
        err |= MC_PARAMS_ERR_SENSE;
    }
    if (p->current_bw_rad_s > MC_PARAMS_BW_DT_MAX * (float)p->pwm_hz) {
        err |= MC_PARAMS_ERR_BANDWIDTH;
    }
    if (p->dead_time_s > MC_PARAMS_DEAD_TIME_FRAC_MAX / (float)p->pwm_hz) {
        err |= MC_PARAMS_ERR_DEAD_TIME;
    }
    if ((p->can_bitrate_bps != 125000u) && (p->can_bitrate_bps != 250000u) &&
        (p->can_bitrate_bps != 500000u) && (p->can_bitrate_bps != 1000000u)) {
        err |= MC_PARAMS_ERR_BITRATE;
    }
    if ((mc_params_to_drive_cfg(p, &cfg) != MC_PARAMS_OK) || (mc_drive_check_cfg(&cfg) != 0u)) {
        err |= MC_PARAMS_ERR_DRIVE;
    }
    if (mc_law_speed_check(p) != 0u) {
        err |= MC_PARAMS_ERR_LAW;
    }
    return err;
}
