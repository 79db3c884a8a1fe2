/**
 * @file mc_fw.c
 * @brief See mc_fw.h.
 */
#include "fw/mc_fw.h"

#include <stddef.h>

#include "math/mc_math.h"

static bool fin(float x)
{
    return mc_isfinite_f32(x);
}

uint32_t mc_fw_f32_init(mc_fw_f32_t *st, const mc_fw_f32_cfg_t *cfg)
{
    if (st == NULL || cfg == NULL) {
        return MC_FW_ERR_NULL;
    }
    uint32_t e = MC_FW_ERR_NONE;
    if (!fin(cfg->ld_h) || !fin(cfg->lq_h) || !fin(cfg->flux_wb) || !(cfg->ld_h > 0.0f) ||
        !(cfg->lq_h > 0.0f) || !(cfg->flux_wb > 0.0f)) {
        e |= MC_FW_ERR_MOTOR;
    }
    if (!fin(cfg->i_max_a) || !(cfg->i_max_a > 0.0f) || !fin(cfg->v_margin) ||
        !(cfg->v_margin > 0.0f) || !(cfg->v_margin <= 1.0f) || !fin(cfg->k_demag) ||
        !(cfg->k_demag > 0.0f) || !(cfg->k_demag <= 1.0f)) {
        e |= MC_FW_ERR_LIMIT;
    }
    if (!fin(cfg->ki_fw_a_per_vs) || cfg->ki_fw_a_per_vs < 0.0f || !fin(cfg->dt_s) ||
        !(cfg->dt_s > 0.0f)) {
        e |= MC_FW_ERR_GAIN;
    }
    if (e != MC_FW_ERR_NONE) {
        return e;
    }
    st->cfg = *cfg;
    st->dl_h = cfg->lq_h - cfg->ld_h;
    const float lmax = (cfg->lq_h > cfg->ld_h) ? cfg->lq_h : cfg->ld_h;
    st->salient = mc_abs_f32(st->dl_h) > 1.0e-3f * lmax;
    const float demag = -cfg->k_demag * cfg->flux_wb / cfg->ld_h;
    st->id_min_a = (demag > -cfg->i_max_a) ? demag : -cfg->i_max_a;
    st->id_fw_a = 0.0f;
    return MC_FW_ERR_NONE;
}

uint32_t mc_fw_f32_reset(mc_fw_f32_t *st)
{
    if (st == NULL) {
        return MC_FW_ERR_NULL;
    }
    st->id_fw_a = 0.0f;
    return MC_FW_ERR_NONE;
}

float mc_fw_f32_mtpa_id(const mc_fw_f32_t *st, float i_abs_a)
{
    if (!st->salient) {
        return 0.0f;
    }
    const float psi = st->cfg.flux_wb;
    const float dl = st->dl_h;
    const float r = mc_sqrt_f32(psi * psi + 8.0f * dl * dl * i_abs_a * i_abs_a);
    /* psi - r cancels for small dL I: rationalise, id = -8 dL I^2 / (4 (psi + r)),
     * which has the right sign for either sign of dL. */
    return -2.0f * dl * i_abs_a * i_abs_a / (psi + r);
}

uint32_t mc_fw_f32_step(mc_fw_f32_t *st, const mc_fw_f32_in_t *in, mc_fw_f32_out_t *out)
{
    if (!fin(in->i_cmd_a) || !fin(in->vd_v) || !fin(in->vq_v) || !fin(in->vbus_v)) {
        out->id_ref_a = 0.0f;
        out->iq_ref_a = 0.0f;
        return MC_FW_ERR_INPUT;
    }
    const mc_fw_f32_cfg_t *c = &st->cfg;
    const float imax = c->i_max_a;
    float ia = mc_abs_f32(in->i_cmd_a);
    ia = (ia > imax) ? imax : ia;
    const float id_mtpa = mc_fw_f32_mtpa_id(st, ia);
    const float v_max = c->v_margin * in->vbus_v * (1.0f / MC_SQRT3_F32);
    const float v_mag = mc_sqrt_f32(in->vd_v * in->vd_v + in->vq_v * in->vq_v);
    if (c->ki_fw_a_per_vs > 0.0f) {
        float x = st->id_fw_a + c->ki_fw_a_per_vs * (v_max - v_mag) * c->dt_s;
        x = (x > 0.0f) ? 0.0f : x;
        x = (x < st->id_min_a) ? st->id_min_a : x;
        st->id_fw_a = x;
    }
    float id = id_mtpa + st->id_fw_a;
    id = (id < st->id_min_a) ? st->id_min_a : id;
    id = (id > id_mtpa) ? id_mtpa : id;
    float iq;
    if (!st->salient && st->id_fw_a == 0.0f) {
        iq = in->i_cmd_a; /* non-salient, no weakening: the command as it is */
        iq = (iq > imax) ? imax : ((iq < -imax) ? -imax : iq);
    } else {
        const float iq2 = ia * ia - id_mtpa * id_mtpa;
        float iq_abs = (iq2 > 0.0f) ? mc_sqrt_f32(iq2) : 0.0f;
        const float room2 = imax * imax - id * id;
        const float room = (room2 > 0.0f) ? mc_sqrt_f32(room2) : 0.0f;
        iq_abs = (iq_abs > room) ? room : iq_abs;
        iq = (in->i_cmd_a < 0.0f) ? -iq_abs : iq_abs;
    }
    out->id_ref_a = id;
    out->iq_ref_a = iq;
    out->id_mtpa_a = id_mtpa;
    out->v_mag_v = v_mag;
    out->v_max_v = v_max;
    return MC_FW_ERR_NONE;
}
