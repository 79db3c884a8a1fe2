/**
 * @file mc_telemetry.c
 * @brief Cyclic CAN telemetry: see mc_telemetry.h.
 */
#include "mc_telemetry.h"

#include <errno.h>
#include <stddef.h>

#include "math/mc_math.h"
#include "mc_can_cmd.h"
#include "transforms/mc_transforms.h"

static const uint8_t k_slot_msg[MC_TM_COUNT] = {
    (uint8_t)MC_CAN_MSG_HEARTBEAT,    (uint8_t)MC_CAN_MSG_CURRENTS,
    (uint8_t)MC_CAN_MSG_VOLTAGES,     (uint8_t)MC_CAN_MSG_SPEED,
    (uint8_t)MC_CAN_MSG_POSITION,     (uint8_t)MC_CAN_MSG_OBSERVER,
    (uint8_t)MC_CAN_MSG_CONTROLLER,   (uint8_t)MC_CAN_MSG_STEPPER,
    (uint8_t)MC_CAN_MSG_CURRENT_REFS, (uint8_t)MC_CAN_MSG_POSITION_REF,
    (uint8_t)MC_CAN_MSG_BUS_CURRENT,  (uint8_t)MC_CAN_MSG_THERMAL,
};

#define NO_SAT 0xFFu
/* index of each slot's `sat` signal (NO_SAT: the message has none) */
static const uint8_t k_slot_sat[MC_TM_COUNT] = {
    NO_SAT,
    (uint8_t)MC_CAN_CURRENTS_SAT,
    (uint8_t)MC_CAN_VOLTAGES_SAT,
    (uint8_t)MC_CAN_SPEED_SAT,
    (uint8_t)MC_CAN_POSITION_SAT,
    (uint8_t)MC_CAN_OBSERVER_SAT,
    (uint8_t)MC_CAN_CONTROLLER_SAT,
    NO_SAT,
    (uint8_t)MC_CAN_CURRENT_REFS_SAT,
    (uint8_t)MC_CAN_POSITION_REF_SAT,
    (uint8_t)MC_CAN_BUS_CURRENT_SAT,
    (uint8_t)MC_CAN_THERMAL_SAT,
};

#define TWO_PI_F 6.28318530717958647692f

uint32_t mc_telemetry_msg(uint32_t slot)
{
    return (slot < (uint32_t)MC_TM_COUNT) ? (uint32_t)k_slot_msg[slot] : MC_CAN_MSG_COUNT;
}

uint32_t mc_telemetry_slot_of_cmd(uint32_t cmd)
{
    uint32_t i;
    for (i = 0u; i < (uint32_t)MC_TM_COUNT; i++) {
        if ((uint32_t)mc_can_messages[k_slot_msg[i]].cmd == cmd) {
            return i;
        }
    }
    return (uint32_t)MC_TM_COUNT;
}

float mc_telemetry_bus_load(const mc_telemetry_cfg_t *cfg)
{
    float bits_per_s = 0.0f;
    uint32_t i;
    if ((cfg == NULL) || (cfg->bitrate_bps == 0u)) {
        return 0.0f;
    }
    for (i = 0u; i < (uint32_t)MC_TM_COUNT; i++) {
        const uint32_t dlc = mc_can_messages[k_slot_msg[i]].dlc;
        bits_per_s += (float)cfg->rate_hz[i] * (float)mc_can_frame_bits_worst(dlc);
    }
    /* the rate-limited replies: the most one second can carry */
    bits_per_s += (float)MC_TM_REPLY_RESERVE_HZ * (float)mc_can_frame_bits_worst(MC_TM_REPLY_DLC);
    return bits_per_s / (float)cfg->bitrate_bps;
}

void mc_tm_reply_lim_init(mc_tm_reply_lim_t *l, uint32_t tick_hz)
{
    if (l == NULL) {
        return;
    }
    l->tick_hz = (tick_hz == 0u) ? 1u : tick_hz;
    l->tokens = MC_TM_REPLY_BURST;
    l->acc = 0u;
    l->taken = 0u;
}

void mc_tm_reply_lim_step(mc_tm_reply_lim_t *l)
{
    if ((l == NULL) || (l->tick_hz == 0u)) {
        return;
    }
    l->acc += MC_TM_REPLY_MAX_HZ;
    while (l->acc >= l->tick_hz) {
        l->acc -= l->tick_hz;
        if (l->tokens < MC_TM_REPLY_BURST) {
            l->tokens++;
        }
    }
}

bool mc_tm_reply_lim_ready(const mc_tm_reply_lim_t *l)
{
    return (l != NULL) && (l->tokens > 0u);
}

bool mc_tm_reply_lim_take(mc_tm_reply_lim_t *l)
{
    if (!mc_tm_reply_lim_ready(l)) {
        return false;
    }
    l->tokens--;
    l->taken++;
    return true;
}

static uint32_t check_rates(const mc_telemetry_cfg_t *cfg)
{
    uint32_t err = MC_TM_CFG_OK;
    uint32_t i;
    for (i = 0u; i < (uint32_t)MC_TM_COUNT; i++) {
        if ((uint32_t)cfg->rate_hz[i] > cfg->tick_hz) {
            err |= MC_TM_CFG_ERR_RATE;
        }
    }
    if (cfg->rate_hz[MC_TM_HEARTBEAT] < MC_TM_HEARTBEAT_MIN_HZ) {
        err |= MC_TM_CFG_ERR_HEARTBEAT;
    }
    if (mc_telemetry_bus_load(cfg) > cfg->bus_budget_frac) {
        err |= MC_TM_CFG_ERR_LOAD;
    }
    return err;
}

uint32_t mc_telemetry_init(mc_telemetry_t *t, const mc_telemetry_cfg_t *cfg)
{
    uint32_t err = MC_TM_CFG_OK;
    uint32_t i;
    if ((t == NULL) || (cfg == NULL)) {
        return MC_TM_CFG_ERR_NULL;
    }
    if ((uint32_t)cfg->node_id > MC_CAN_NODE_ID_MAX) {
        err |= MC_TM_CFG_ERR_NODE;
    }
    if ((cfg->bitrate_bps < MC_TM_BITRATE_MIN_BPS) || (cfg->bitrate_bps > MC_TM_BITRATE_MAX_BPS)) {
        err |= MC_TM_CFG_ERR_BITRATE;
    }
    if ((cfg->tick_hz == 0u) || (cfg->tick_hz > MC_TM_TICK_MAX_HZ)) {
        err |= MC_TM_CFG_ERR_TICK;
    }
    if (!mc_isfinite_f32(cfg->bus_budget_frac) || !(cfg->bus_budget_frac > 0.0f) ||
        !(cfg->bus_budget_frac <= MC_TM_BUDGET_FRAC_MAX)) {
        err |= MC_TM_CFG_ERR_BUDGET;
    }
    if (err == MC_TM_CFG_OK) {
        err = check_rates(cfg);
    }
    if (err != MC_TM_CFG_OK) {
        return err;
    }
    {
        const mc_telemetry_t z = {0};
        *t = z;
    }
    t->cfg = *cfg;
    for (i = 0u; i < (uint32_t)MC_TM_COUNT; i++) {
        /* staggered phases: slot i fires first after (COUNT - i) / COUNT of
         * its period at most, so equal rates spread over the ticks */
        t->acc[i] = (uint32_t)(((uint64_t)cfg->tick_hz * i) / (uint64_t)MC_TM_COUNT);
    }
    t->load_frac = mc_telemetry_bus_load(cfg);
    return MC_TM_CFG_OK;
}

uint32_t mc_telemetry_set_rate(mc_telemetry_t *t, uint32_t slot, uint16_t rate_hz)
{
    mc_telemetry_cfg_t probe;
    uint32_t err;
    if (t == NULL) {
        return MC_TM_CFG_ERR_NULL;
    }
    if (slot >= (uint32_t)MC_TM_COUNT) {
        return MC_TM_CFG_ERR_RATE;
    }
    probe = t->cfg;
    probe.rate_hz[slot] = rate_hz;
    err = check_rates(&probe);
    if (err != MC_TM_CFG_OK) {
        return err;
    }
    t->cfg.rate_hz[slot] = rate_hz;
    t->load_frac = mc_telemetry_bus_load(&t->cfg);
    return MC_TM_CFG_OK;
}

static float u8f(uint32_t v)
{
    return (float)(v & 0xFFu);
}

static void values_heartbeat(const mc_telemetry_src_t *src, float *v)
{
    const mc_drive_t *d = src->drive;
    const mc_can_cmd_t *c = src->cmd;
    v[MC_CAN_HEARTBEAT_MODE] = (float)(uint32_t)d->mode;
    v[MC_CAN_HEARTBEAT_FAULTS] = (float)(d->faults & 0xFFFFu);
    if (c != NULL) {
        v[MC_CAN_HEARTBEAT_CONTROL_MODE] = u8f(c->control_mode);
        v[MC_CAN_HEARTBEAT_ENABLED] = c->enabled ? 1.0f : 0.0f;
        v[MC_CAN_HEARTBEAT_STOPPING] = c->stopping ? 1.0f : 0.0f;
        v[MC_CAN_HEARTBEAT_STOP_REASON] = u8f(c->stop_reason);
        v[MC_CAN_HEARTBEAT_CFG_STATUS] = u8f(c->cfg_status);
        v[MC_CAN_HEARTBEAT_CAN_STATE] = (float)(c->can_state & 0x3u);
        v[MC_CAN_HEARTBEAT_LAST_ERROR] = u8f(c->last_error);
        v[MC_CAN_HEARTBEAT_LAST_ERROR_CMD] = u8f(c->last_error_cmd);
    } else {
        v[MC_CAN_HEARTBEAT_CONTROL_MODE] = 0.0f;
        v[MC_CAN_HEARTBEAT_ENABLED] = 0.0f;
        v[MC_CAN_HEARTBEAT_STOPPING] = 0.0f;
        v[MC_CAN_HEARTBEAT_STOP_REASON] = 0.0f;
        v[MC_CAN_HEARTBEAT_CFG_STATUS] = (float)MC_CAN_VAL_CFG_STATUS_EMPTY;
        v[MC_CAN_HEARTBEAT_CAN_STATE] = 0.0f;
        v[MC_CAN_HEARTBEAT_LAST_ERROR] = 0.0f;
        v[MC_CAN_HEARTBEAT_LAST_ERROR_CMD] = 0.0f;
    }
}

static void values_currents(const mc_telemetry_src_t *src, float *v)
{
    const mc_drive_telemetry_t *tm = &src->drive->tm;
    float alpha;
    float beta;
    float s;
    float co;
    float id;
    float iq;
    mc_clarke_f32(tm->ia_a, tm->ib_a, &alpha, &beta);
    mc_sincos_f32(tm->theta_e_rad, &s, &co);
    mc_park_f32(alpha, beta, s, co, &id, &iq);
    v[MC_CAN_CURRENTS_I_D_A] = id;
    v[MC_CAN_CURRENTS_I_Q_A] = iq;
}

float mc_telemetry_theta_multi_rad(const mc_telemetry_t *t, const mc_drive_t *drive)
{
    if ((t == NULL) || !t->have_theta) {
        return (drive != NULL) ? drive->tm.theta_m_rad : 0.0f;
    }
    return (float)t->turns * TWO_PI_F + t->theta_prev_rad;
}

/* Unwrap the drive's single-turn angle: the turn count whose step is
 * nearest the measured speed times the tick. */
static void track_turns(mc_telemetry_t *t, const mc_drive_t *d)
{
    const float th = d->tm.theta_m_rad;
    if (!mc_isfinite_f32(th)) {
        return;
    }
    if (t->have_theta) {
        const float dt = 1.0f / (float)t->cfg.tick_hz;
        const float w = mc_isfinite_f32(d->tm.omega_m_rad_s) ? d->tm.omega_m_rad_s : 0.0f;
        const float x = (w * dt - (th - t->theta_prev_rad)) / TWO_PI_F;
        const float n = (x >= 0.0f) ? (float)(int32_t)(x + 0.5f) : -(float)(int32_t)(0.5f - x);
        t->turns += (int32_t)n;
    }
    t->theta_prev_rad = th;
    t->have_theta = true;
}

/* Set the slot's sat signal if another signal (seq excepted) is outside its
 * range or not a number. */
static void flag_saturation(uint32_t slot, float *v)
{
    const uint32_t si = (uint32_t)k_slot_sat[slot];
    const mc_can_message_t *m = &mc_can_messages[k_slot_msg[slot]];
    bool sat = false;
    if (si == (uint32_t)NO_SAT) {
        return;
    }
    for (uint32_t j = 0u; (j + 1u) < (uint32_t)m->n_signals; j++) {
        const mc_can_signal_t *s = &m->signals[j];
        if ((j != si) && (!mc_isfinite_f32(v[j]) || (v[j] < s->min) || (v[j] > s->max))) {
            sat = true;
        }
    }
    v[si] = sat ? 1.0f : 0.0f;
}

static bool values_of(uint32_t slot, const mc_telemetry_src_t *src, float *values);

bool mc_telemetry_values(uint32_t slot, const mc_telemetry_src_t *src,
                         float values[MC_CAN_NSIG_MAX])
{
    if (!values_of(slot, src, values)) {
        return false;
    }
    flag_saturation(slot, values);
    return true;
}

static bool values_of(uint32_t slot, const mc_telemetry_src_t *src, float *values)
{
    const mc_telemetry_ext_t *x;
    const mc_drive_t *d;
    if ((src == NULL) || (src->drive == NULL) || (values == NULL)) {
        return false;
    }
    d = src->drive;
    x = src->ext;
    switch (slot) {
    case MC_TM_HEARTBEAT:
        values_heartbeat(src, values);
        return true;
    case MC_TM_CURRENTS:
        values_currents(src, values);
        return true;
    case MC_TM_VOLTAGES: {
        const bool foc = (d->mode == MC_DRIVE_MODE_CURRENT);
        values[MC_CAN_VOLTAGES_V_D_V] = foc ? d->tm.foc.vd_v : 0.0f;
        values[MC_CAN_VOLTAGES_V_Q_V] = foc ? d->tm.foc.vq_v : 0.0f;
        values[MC_CAN_VOLTAGES_V_BUS_V] = d->tm.vbus_v;
        return true;
    }
    case MC_TM_SPEED:
        values[MC_CAN_SPEED_OMEGA_M_RAD_S] = d->tm.omega_m_rad_s;
        values[MC_CAN_SPEED_OMEGA_REF_RAD_S] =
            (src->cmd != NULL) ? src->cmd->omega_ref_rad_s : 0.0f;
        return true;
    case MC_TM_POSITION:
        values[MC_CAN_POSITION_THETA_M_RAD] = mc_telemetry_theta_multi_rad(src->tm, d);
        values[MC_CAN_POSITION_THETA_E_RAD] = d->tm.theta_e_rad;
        return true;
    case MC_TM_CURRENT_REFS:
        values[MC_CAN_CURRENT_REFS_I_D_REF_A] = d->tm.id_ref_a;
        values[MC_CAN_CURRENT_REFS_I_Q_REF_A] = d->tm.iq_ref_a;
        return true;
    case MC_TM_POSITION_REF:
        values[MC_CAN_POSITION_REF_THETA_REF_RAD] =
            (src->cmd != NULL) ? src->cmd->theta_ref_rad : 0.0f;
        return true;
    case MC_TM_BUS_CURRENT:
        values[MC_CAN_BUS_CURRENT_I_BUS_EST_A] = mc_drive_bus_current_a(d);
        values[MC_CAN_BUS_CURRENT_I_BUS_MAX_A] = d->bus.i_mot_lim_a;
        values[MC_CAN_BUS_CURRENT_I_BUS_REGEN_MAX_A] = d->bus.i_regen_lim_a;
        return true;
    case MC_TM_THERMAL:
        values[MC_CAN_THERMAL_T_WINDING_EST_C] = d->thermal.t_w_c;
        values[MC_CAN_THERMAL_I_LIMIT_A] = mc_drive_thermal_limit_a(&d->thermal, d->cfg.i_max_a);
        values[MC_CAN_THERMAL_DERATE_FACTOR] = d->thermal.k;
        values[MC_CAN_THERMAL_DERATING] = d->thermal.derating ? 1.0f : 0.0f;
        return true;
    case MC_TM_OBSERVER:
        if ((x == NULL) || !x->have_observer) {
            return false;
        }
        values[MC_CAN_OBSERVER_TAU_L_HAT_NM] = x->tau_l_hat_nm;
        values[MC_CAN_OBSERVER_OMEGA_HAT_RAD_S] = x->omega_hat_rad_s;
        values[MC_CAN_OBSERVER_THETA_HAT_RAD] = x->theta_hat_rad;
        return true;
    case MC_TM_CONTROLLER:
        if ((x == NULL) || !x->have_controller) {
            return false;
        }
        values[MC_CAN_CONTROLLER_NU_PU] = x->nu_pu;
        values[MC_CAN_CONTROLLER_VARTHETA_PU] = x->vartheta_pu;
        return true;
    case MC_TM_STEPPER:
        if ((x == NULL) || !x->have_stepper) {
            return false;
        }
        values[MC_CAN_STEPPER_E1_RAD] = x->e1_rad;
        values[MC_CAN_STEPPER_E2_RAD_S] = x->e2_rad_s;
        values[MC_CAN_STEPPER_S1] = x->s1;
        values[MC_CAN_STEPPER_S2] = x->s2;
        return true;
    default:
        return false;
    }
}

uint32_t mc_telemetry_step(mc_telemetry_t *t, const mc_hal_can_t *can,
                           const mc_telemetry_src_t *src)
{
    uint32_t sent = 0u;
    uint32_t fail = 0u;
    uint32_t i;
    if (t == NULL) {
        return 0u;
    }
    if ((src != NULL) && (src->drive != NULL)) {
        track_turns(t, src->drive);
    }
    for (i = 0u; i < (uint32_t)MC_TM_COUNT; i++) {
        float v[MC_CAN_NSIG_MAX] = {0.0f};
        mc_hal_can_frame_t f;
        const mc_can_message_t *m = &mc_can_messages[k_slot_msg[i]];
        int rc;
        if (t->cfg.rate_hz[i] == 0u) {
            continue;
        }
        t->acc[i] += t->cfg.rate_hz[i];
        if (t->acc[i] < t->cfg.tick_hz) {
            continue;
        }
        t->acc[i] -= t->cfg.tick_hz;
        if (!mc_telemetry_values(i, src, v)) {
            continue;
        }
        /* the sequence counter is the last signal of every telemetry message */
        v[m->n_signals - 1u] = (float)t->seq[i];
        if (mc_can_proto_pack(k_slot_msg[i], t->cfg.node_id, v, MC_CAN_NSIG_MAX, &f) !=
            MC_CAN_ERR_NONE) {
            continue;
        }
        t->seq[i] = (uint8_t)(t->seq[i] + 1u);
        sent |= 1u << i;
        if ((k_slot_sat[i] != NO_SAT) && (v[k_slot_sat[i]] > 0.5f)) {
            t->saturated++;
        }
        rc = mc_hal_can_send(can, &f);
        if (rc == 0) {
            t->tx_frames++;
        } else {
            fail |= 1u << i;
            t->tx_dropped++;
            if (rc == -ENOBUFS) {
                t->tx_nobufs++;
            } else if (rc == -ENETDOWN) {
                t->tx_busoff++;
            } else {
                /* -EIO, -ENODEV: counted in tx_dropped only */
            }
        }
    }
    t->last_fail_mask = fail;
    return sent;
}
