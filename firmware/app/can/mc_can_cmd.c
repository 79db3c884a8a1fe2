/**
 * @file mc_can_cmd.c
 * @brief CAN command handler: see mc_can_cmd.h.
 */
#include "mc_can_cmd.h"

#include <errno.h>

#include <stddef.h>

#include "math/mc_math.h"

#define TIMEOUT_MAX_S 60.0f

static bool positive_finite(float x)
{
    return mc_isfinite_f32(x) && (x > 0.0f);
}

static bool mode_usable(mc_drive_mode_t m)
{
    return (m == MC_DRIVE_MODE_CURRENT) || (m == MC_DRIVE_MODE_CTRL);
}

uint32_t mc_can_cmd_init(mc_can_cmd_t *c, const mc_can_cmd_cfg_t *cfg, mc_drive_t *drive,
                         mc_telemetry_t *tm)
{
    uint32_t err = MC_CAN_CMD_CFG_OK;
    float ticks = 0.0f;
    if ((c == NULL) || (cfg == NULL) || (drive == NULL)) {
        return MC_CAN_CMD_CFG_ERR_NULL;
    }
    if ((uint32_t)cfg->node_id > MC_CAN_NODE_ID_MAX) {
        err |= MC_CAN_CMD_CFG_ERR_NODE;
    }
    if ((cfg->tick_hz == 0u) || (cfg->tick_hz > MC_TM_TICK_MAX_HZ)) {
        err |= MC_CAN_CMD_CFG_ERR_TICK;
    } else {
        ticks = cfg->timeout_s * (float)cfg->tick_hz;
        if (!mc_isfinite_f32(cfg->timeout_s) || !(ticks >= 1.0f) ||
            !(cfg->timeout_s <= TIMEOUT_MAX_S)) {
            err |= MC_CAN_CMD_CFG_ERR_TIMEOUT;
        }
    }
    if (!positive_finite(cfg->stop_ramp_a_per_s) || !positive_finite(cfg->stop_decel_rad_s2)) {
        err |= MC_CAN_CMD_CFG_ERR_RAMP;
    }
    if (!positive_finite(cfg->speed_max_rad_s)) {
        err |= MC_CAN_CMD_CFG_ERR_SPEED;
    }
    if (((cfg->set_speed_ref != NULL) && !mode_usable(cfg->speed_drive_mode)) ||
        ((cfg->set_position_ref != NULL) && !mode_usable(cfg->position_drive_mode))) {
        err |= MC_CAN_CMD_CFG_ERR_MODE;
    }
    if (err != MC_CAN_CMD_CFG_OK) {
        return err;
    }
    {
        const mc_can_cmd_t z = {0};
        *c = z;
    }
    c->cfg = *cfg;
    c->drive = drive;
    c->tm = tm;
    c->timeout_ticks = (uint32_t)(ticks + 0.5f);
    c->control_mode = (uint8_t)MC_CAN_CTRL_NONE;
    c->stop_reason = (uint8_t)MC_CAN_STOP_NONE;
    c->cfg_status = (uint8_t)MC_CAN_VAL_CFG_STATUS_EMPTY;
    mc_tm_reply_lim_init(&c->reply, cfg->tick_hz);
    return MC_CAN_CMD_CFG_OK;
}

/* ---------------------------------------------------- parameter exchange */

/* Telemetry slots the parameter table sets, in slot order. */
static void tm_rates(const mc_params_t *p, uint32_t rate[MC_TM_POSITION + 1u])
{
    rate[MC_TM_HEARTBEAT] = p->tm_heartbeat_hz;
    rate[MC_TM_CURRENTS] = p->tm_currents_hz;
    rate[MC_TM_VOLTAGES] = p->tm_voltages_hz;
    rate[MC_TM_SPEED] = p->tm_speed_hz;
    rate[MC_TM_POSITION] = p->tm_position_hz;
}

static uint32_t params_check(void *ctx, const mc_params_t *p)
{
    const mc_can_cmd_t *c = (const mc_can_cmd_t *)ctx;
    const float ticks = p->can_timeout_s * (float)c->cfg.tick_hz;
    if (!(ticks >= 1.0f)) {
        return 1u; /* timeout shorter than one supervision step */
    }
    if (c->tm != NULL) {
        mc_telemetry_cfg_t t = c->tm->cfg;
        uint32_t rate[MC_TM_POSITION + 1u];
        tm_rates(p, rate);
        for (uint32_t i = 0u; i <= (uint32_t)MC_TM_POSITION; ++i) {
            if (rate[i] > t.tick_hz) {
                return 1u;
            }
            t.rate_hz[i] = (uint16_t)rate[i];
        }
        if (mc_telemetry_bus_load(&t) > t.bus_budget_frac) {
            return 1u;
        }
    }
    return 0u;
}

static void params_apply(void *ctx, const mc_params_t *p)
{
    mc_can_cmd_t *c = (mc_can_cmd_t *)ctx;
    mc_params_eff_t e;
    (void)mc_params_resolve(p, &e); /* validated by the service before */
    c->cfg.timeout_s = p->can_timeout_s;
    c->timeout_ticks = (uint32_t)(p->can_timeout_s * (float)c->cfg.tick_hz + 0.5f);
    c->cfg.stop_ramp_a_per_s = p->stop_ramp_a_per_s;
    c->cfg.stop_decel_rad_s2 = e.p.stop_decel_rad_s2;
    c->cfg.speed_max_rad_s = p->speed_max_rad_s;
    if (c->tm != NULL) {
        uint32_t rate[MC_TM_POSITION + 1u];
        tm_rates(p, rate);
        /* lowered rates first, so no intermediate set exceeds the budget
         * that the whole set (checked in params_check) respects */
        for (uint32_t pass = 0u; pass < 2u; ++pass) {
            for (uint32_t i = 0u; i <= (uint32_t)MC_TM_POSITION; ++i) {
                const bool lower = rate[i] <= c->tm->cfg.rate_hz[i];
                if ((pass == 0u) == lower) {
                    (void)mc_telemetry_set_rate(c->tm, i, (uint16_t)rate[i]);
                }
            }
        }
    }
}

void mc_can_cmd_attach_params(mc_can_cmd_t *c, mc_param_srv_t *srv)
{
    if (c == NULL) {
        return;
    }
    c->params = srv;
    if (srv != NULL) {
        srv->hook.check = params_check;
        srv->hook.apply = params_apply;
        srv->hook.ctx = c;
        srv->tick_hz = c->cfg.tick_hz; /* mc_can_cmd_step ticks it */
        c->cfg_status = srv->store_status;
    }
}

void mc_can_cmd_attach_commission(mc_can_cmd_t *c, mc_can_cmd_comm_fn fn, mc_can_cmd_busy_fn busy,
                                  mc_can_cmd_lost_fn lost, void *ctx)
{
    if (c == NULL) {
        return;
    }
    c->comm_fn = fn;
    c->comm_busy = (fn != NULL) ? busy : NULL;
    c->comm_lost = (fn != NULL) ? lost : NULL;
    c->comm_ctx = (fn != NULL) ? ctx : NULL;
}

/* A run begins (enable, commissioning START): the keep-alive counts from
 * now, and the run's first HOST_HEARTBEAT sets the counter's reference. */
static void run_begin(mc_can_cmd_t *c)
{
    c->ticks_since_alive = 0u;
    c->hb_have = false;
}

static bool comm_busy(const mc_can_cmd_t *c)
{
    return (c->comm_busy != NULL) && c->comm_busy(c->comm_ctx);
}

void mc_can_cmd_attach_boot(mc_can_cmd_t *c, mc_can_cmd_boot_fn fn, void *ctx)
{
    if (c == NULL) {
        return;
    }
    c->boot_fn = fn;
    c->boot_ctx = (fn != NULL) ? ctx : NULL;
}

static mc_can_err_t do_boot(mc_can_cmd_t *c, const mc_hal_can_t *can,
                            const mc_hal_can_frame_t *p_frame)
{
    if (c->boot_fn == NULL) {
        return MC_CAN_ERR_UNSUPPORTED;
    }
    if ((can != NULL) && !mc_tm_reply_lim_take(&c->reply)) {
        return MC_CAN_ERR_LIMITED; /* its BOOT_REPLY could not go out: not served */
    }
    /* a reset refills the SAVE bucket: not before it is full again */
    c->boot_fn(c->boot_ctx, p_frame,
               c->enabled || c->stopping || comm_busy(c) ||
                   !mc_param_srv_save_budget_full(c->params),
               can);
    return MC_CAN_ERR_NONE; /* answered, with its status, by BOOT_REPLY */
}

static mc_can_err_t do_commission(mc_can_cmd_t *c, const float *v)
{
    const bool was_busy = comm_busy(c);
    mc_can_err_t e;
    if (c->comm_fn == NULL) {
        return MC_CAN_ERR_UNSUPPORTED;
    }
    if ((v[MC_CAN_COMMISSION_CMD_ACTION] > 0.5f) && (c->enabled || c->stopping)) {
        return MC_CAN_ERR_MODE; /* START / REPORT only while disabled */
    }
    e = c->comm_fn(c->comm_ctx, v);
    if ((e == MC_CAN_ERR_NONE) && !was_busy && comm_busy(c)) {
        run_begin(c); /* START: it needs the keep-alive from now */
        c->stop_reason = (uint8_t)MC_CAN_STOP_NONE;
    }
    return e;
}

/* Send a reply under the limiter; false: no token (nothing sent). */
static bool reply_send(mc_can_cmd_t *c, const mc_hal_can_t *can, const mc_hal_can_frame_t *f)
{
    if (!mc_tm_reply_lim_take(&c->reply)) {
        return false;
    }
    if (mc_hal_can_send(can, f) != 0) {
        c->reply_dropped++;
    }
    return true;
}

static mc_can_err_t do_param(mc_can_cmd_t *c, const mc_hal_can_t *can, const float *v,
                             const mc_hal_can_frame_t *p_frame)
{
    const uint32_t op = (uint32_t)v[MC_CAN_PARAM_REQ_OPCODE];
    const uint32_t id = (uint32_t)v[MC_CAN_PARAM_REQ_PARAM_ID];
    uint32_t value = 0u;
    mc_param_status_t st;
    float r[MC_CAN_PARAM_REPLY_NSIG];
    mc_hal_can_frame_t f;
    if (c->params == NULL) {
        return MC_CAN_ERR_UNSUPPORTED;
    }
    if ((can != NULL) && !mc_tm_reply_lim_ready(&c->reply) && c->held_have) {
        return MC_CAN_ERR_LIMITED; /* no token and the held slot taken: not served */
    }
    /* the value is the raw 32 bits (a float32 signal would lose them) */
    for (uint32_t i = 0u; i < 4u; ++i) {
        value |= (uint32_t)p_frame->data[4u + i] << (8u * i);
    }
    st = mc_param_srv_request(c->params, op, id, &value);
    c->cfg_status = c->params->store_status; /* a SAVE changes it */
    if (can == NULL) {
        return MC_CAN_ERR_NONE;
    }
    r[MC_CAN_PARAM_REPLY_OPCODE] = (float)op;
    r[MC_CAN_PARAM_REPLY_PARAM_ID] = (float)id;
    r[MC_CAN_PARAM_REPLY_STATUS] = (float)(uint32_t)st;
    r[MC_CAN_PARAM_REPLY_VALUE] = 0.0f;
    if (mc_can_proto_pack(MC_CAN_MSG_PARAM_REPLY, c->cfg.node_id, r, MC_CAN_PARAM_REPLY_NSIG, &f) !=
        MC_CAN_ERR_NONE) {
        c->reply_dropped++;
        return MC_CAN_ERR_NONE;
    }
    for (uint32_t i = 0u; i < 4u; ++i) {
        f.data[4u + i] = (uint8_t)(value >> (8u * i));
    }
    if (!reply_send(c, can, &f)) {
        c->held = f; /* goes out at the next step with a token */
        c->held_can = can;
        c->held_have = true;
    }
    return MC_CAN_ERR_NONE; /* answered, with its status, by PARAM_REPLY */
}

static void end_run(mc_can_cmd_t *c, uint8_t reason)
{
    (void)mc_drive_set_mode(c->drive, MC_DRIVE_MODE_IDLE);
    c->enabled = false;
    c->stopping = false;
    c->angle_finding = false;
    c->stop_reason = reason;
}

void mc_can_cmd_end_run(mc_can_cmd_t *c, uint8_t reason)
{
    end_run(c, reason);
}

void mc_can_cmd_attach_angle(mc_can_cmd_t *c, mc_can_cmd_angle_fn fn, void *ctx)
{
    if (c == NULL) {
        return;
    }
    c->angle_fn = fn;
    c->angle_ctx = (fn != NULL) ? ctx : NULL;
}

/* The references of the selected control mode from the present state, so
 * that enable is no step (mc_can_cmd.h). */
static int refs_from_present(mc_can_cmd_t *c)
{
    const mc_drive_t *d = c->drive;
    switch (c->control_mode) {
    case MC_CAN_CTRL_CURRENT:
        return mc_drive_set_current_ref(c->drive, 0.0f, 0.0f);
    case MC_CAN_CTRL_SPEED: {
        float w = mc_isfinite_f32(d->tm.omega_m_rad_s) ? d->tm.omega_m_rad_s : 0.0f;
        const float lim = c->cfg.speed_max_rad_s;
        w = (w > lim) ? lim : ((w < -lim) ? -lim : w);
        if (c->cfg.set_speed_ref(c->cfg.hook_ctx, w) != 0) {
            return -1;
        }
        c->omega_ref_rad_s = w;
        return 0;
    }
    case MC_CAN_CTRL_POSITION: {
        const float th = mc_telemetry_theta_multi_rad(c->tm, d);
        if (c->cfg.set_position_ref(c->cfg.hook_ctx, 0.0f) != 0) {
            return -1; /* hold the position at enable */
        }
        c->theta_enable_rad = th;
        c->theta_ref_rad = th;
        return 0;
    }
    default:
        return -1;
    }
}

/* The drive mode of the selected control mode; -1: none selected. */
static int drive_mode_of(const mc_can_cmd_t *c, mc_drive_mode_t *p_mode)
{
    switch (c->control_mode) {
    case MC_CAN_CTRL_CURRENT:
        *p_mode = MC_DRIVE_MODE_CURRENT;
        return 0;
    case MC_CAN_CTRL_SPEED:
        *p_mode = c->cfg.speed_drive_mode;
        return 0;
    case MC_CAN_CTRL_POSITION:
        *p_mode = c->cfg.position_drive_mode;
        return 0;
    default:
        return -1;
    }
}

static void run_on(mc_can_cmd_t *c)
{
    c->enabled = true;
    c->stop_reason = (uint8_t)MC_CAN_STOP_NONE;
    run_begin(c);
}

static mc_can_err_t do_enable(mc_can_cmd_t *c, bool on)
{
    mc_drive_mode_t mode;
    int rc;
    if (!on) {
        if (c->enabled) {
            end_run(c, (uint8_t)MC_CAN_STOP_DISABLE_CMD);
        } else {
            (void)mc_drive_set_mode(c->drive, MC_DRIVE_MODE_IDLE);
        }
        return MC_CAN_ERR_NONE;
    }
    if (c->stopping || comm_busy(c)) {
        return MC_CAN_ERR_MODE;
    }
    if (c->enabled) {
        return MC_CAN_ERR_NONE; /* no new run: the keep-alive counts on */
    }
    if (drive_mode_of(c, &mode) != 0) {
        return MC_CAN_ERR_MODE; /* no control mode selected */
    }
    if (refs_from_present(c) != 0) {
        return MC_CAN_ERR_REFUSED;
    }
    if (c->angle_fn != NULL) {
        const int r = c->angle_fn(c->angle_ctx, mode);
        if (r < 0) {
            return MC_CAN_ERR_ANGLE_UNKNOWN;
        }
        if (r > 0) {
            c->angle_finding = true; /* the application finds the angle first */
            run_on(c);
            return MC_CAN_ERR_NONE;
        }
    }
    rc = mc_drive_set_mode(c->drive, mode);
    if (rc == -EACCES) {
        return MC_CAN_ERR_ANGLE_UNKNOWN; /* the angle unknown since power-up */
    }
    if (rc != 0) {
        return MC_CAN_ERR_REFUSED;
    }
    run_on(c);
    return MC_CAN_ERR_NONE;
}

int mc_can_cmd_angle_found(mc_can_cmd_t *c)
{
    mc_drive_mode_t mode;
    const float w_host = c->omega_ref_rad_s; /* SPEED: the host's, or the one at enable */
    int rc = -1;
    if (!c->enabled || !c->angle_finding) {
        return -1;
    }
    c->angle_finding = false;
    if ((drive_mode_of(c, &mode) == 0) && (refs_from_present(c) == 0)) {
        rc = mc_drive_set_mode(c->drive, mode);
    }
    if ((rc == 0) && (c->control_mode == MC_CAN_CTRL_SPEED)) {
        /* from the present speed to the host's reference, slewed */
        rc = c->cfg.set_speed_ref(c->cfg.hook_ctx, w_host);
        c->omega_ref_rad_s = w_host;
    }
    if (rc != 0) {
        end_run(c, (uint8_t)MC_CAN_STOP_FAULT);
        return -1;
    }
    return 0;
}

/* The keep-alive (mc_can_cmd.h): the counter advanced by 1..MC_CAN_HB_STEP_MAX
 * modulo 256 over the last accepted one, or the run's first. */
static mc_can_err_t do_host_heartbeat(mc_can_cmd_t *c, uint8_t n)
{
    const uint32_t step = (uint32_t)(uint8_t)(n - c->hb_last);
    if (c->hb_have && ((step == 0u) || (step > MC_CAN_HB_STEP_MAX))) {
        return MC_CAN_ERR_STALE; /* a repeat, a step back or a jump: no live host */
    }
    c->hb_have = true;
    c->hb_last = n;
    c->ticks_since_alive = 0u;
    return MC_CAN_ERR_NONE;
}

static mc_can_err_t do_control_mode(mc_can_cmd_t *c, uint32_t mode)
{
    if (c->enabled || c->stopping || comm_busy(c)) {
        return MC_CAN_ERR_MODE;
    }
    if (((mode == MC_CAN_CTRL_SPEED) && (c->cfg.set_speed_ref == NULL)) ||
        ((mode == MC_CAN_CTRL_POSITION) && (c->cfg.set_position_ref == NULL))) {
        return MC_CAN_ERR_UNSUPPORTED;
    }
    c->control_mode = (uint8_t)mode;
    return MC_CAN_ERR_NONE;
}

static mc_can_err_t do_speed_ref(mc_can_cmd_t *c, float w)
{
    if ((c->control_mode != MC_CAN_CTRL_SPEED) || c->stopping || !c->enabled) {
        return MC_CAN_ERR_MODE;
    }
    {
        /* half a raw step of slack: the limit itself, sent as the nearest
         * raw value, must not be refused for float rounding of the scale */
        const mc_can_message_t *m = &mc_can_messages[MC_CAN_MSG_SET_SPEED_REF];
        const float half_step = 0.5f * m->signals[MC_CAN_SET_SPEED_REF_OMEGA_REF_RAD_S].scale;
        if (mc_abs_f32(w) > c->cfg.speed_max_rad_s + half_step) {
            return MC_CAN_ERR_RANGE;
        }
    }
    if (c->cfg.set_speed_ref(c->cfg.hook_ctx, w) != 0) {
        return MC_CAN_ERR_REFUSED;
    }
    c->omega_ref_rad_s = w;
    return MC_CAN_ERR_NONE;
}

static mc_can_err_t do_position_ref(mc_can_cmd_t *c, float th)
{
    if ((c->control_mode != MC_CAN_CTRL_POSITION) || c->stopping || !c->enabled ||
        c->angle_finding) {
        return MC_CAN_ERR_MODE;
    }
    if (c->cfg.set_position_ref(c->cfg.hook_ctx, th - c->theta_enable_rad) != 0) {
        return MC_CAN_ERR_REFUSED;
    }
    c->theta_ref_rad = th;
    return MC_CAN_ERR_NONE;
}

static mc_can_err_t do_tm_rate(mc_can_cmd_t *c, float slot_cmd, float rate)
{
    uint32_t err;
    if (c->tm == NULL) {
        return MC_CAN_ERR_UNSUPPORTED;
    }
    /* the DBC range limits tm_cmd to 1..12 and rate to 0..1000; a command
     * id that names no telemetry message is a bad slot (RANGE) */
    err =
        mc_telemetry_set_rate(c->tm, mc_telemetry_slot_of_cmd((uint32_t)slot_cmd), (uint16_t)rate);
    if (err == MC_TM_CFG_OK) {
        return MC_CAN_ERR_NONE;
    }
    if ((err & MC_TM_CFG_ERR_HEARTBEAT) != 0u) {
        return MC_CAN_ERR_HEARTBEAT_MIN;
    }
    return ((err & MC_TM_CFG_ERR_LOAD) != 0u) ? MC_CAN_ERR_BUDGET : MC_CAN_ERR_RANGE;
}

static mc_can_err_t dispatch(mc_can_cmd_t *c, uint32_t msg, const float *v)
{
    switch (msg) {
    case MC_CAN_MSG_DISABLE:
        return do_enable(c, false);
    case MC_CAN_MSG_SET_ENABLE:
        return do_enable(c, v[MC_CAN_SET_ENABLE_ENABLE] > 0.5f);
    case MC_CAN_MSG_SET_CONTROL_MODE:
        return do_control_mode(c, (uint32_t)v[MC_CAN_SET_CONTROL_MODE_CONTROL_MODE]);
    case MC_CAN_MSG_SET_CURRENT_REF:
        if ((c->control_mode != MC_CAN_CTRL_CURRENT) || c->stopping || !c->enabled ||
            c->angle_finding) {
            return MC_CAN_ERR_MODE;
        }
        if (mc_drive_set_current_ref(c->drive, v[MC_CAN_SET_CURRENT_REF_I_D_REF_A],
                                     v[MC_CAN_SET_CURRENT_REF_I_Q_REF_A]) != 0) {
            return MC_CAN_ERR_RANGE; /* above the drive's i_max_a */
        }
        return MC_CAN_ERR_NONE;
    case MC_CAN_MSG_SET_SPEED_REF:
        return do_speed_ref(c, v[MC_CAN_SET_SPEED_REF_OMEGA_REF_RAD_S]);
    case MC_CAN_MSG_SET_POSITION_REF:
        return do_position_ref(c, v[MC_CAN_SET_POSITION_REF_THETA_REF_RAD]);
    case MC_CAN_MSG_CLEAR_FAULTS:
        if (c->enabled || c->stopping || comm_busy(c)) {
            return MC_CAN_ERR_MODE;
        }
        return (mc_drive_clear_faults(c->drive) == 0) ? MC_CAN_ERR_NONE : MC_CAN_ERR_REFUSED;
    case MC_CAN_MSG_SET_TM_RATE:
        return do_tm_rate(c, v[MC_CAN_SET_TM_RATE_TM_CMD], v[MC_CAN_SET_TM_RATE_RATE_HZ]);
    case MC_CAN_MSG_HOST_HEARTBEAT:
        return do_host_heartbeat(c, (uint8_t)v[MC_CAN_HOST_HEARTBEAT_COUNTER]);
    case MC_CAN_MSG_COMMISSION_CMD:
        return do_commission(c, v);
    case MC_CAN_MSG_BOOT_DATA:
        return MC_CAN_ERR_MODE; /* the bootloader's: not while the application runs */
    default:
        return MC_CAN_ERR_UNKNOWN_CMD;
    }
}

static void reply_error(mc_can_cmd_t *c, const mc_hal_can_t *can, uint32_t cmd, uint32_t len,
                        mc_can_err_t e)
{
    float v[MC_CAN_CMD_ERROR_NSIG];
    mc_hal_can_frame_t f;
    c->last_error = (uint8_t)e;
    c->last_error_cmd = (uint8_t)cmd;
    c->rx_rejected++;
    if (can == NULL) {
        return;
    }
    if (!mc_tm_reply_lim_ready(&c->reply)) {
        c->reply_limited++; /* rate limit: counted, shown in the HEARTBEAT */
        return;
    }
    v[MC_CAN_CMD_ERROR_REJECTED_CMD] = (float)cmd;
    v[MC_CAN_CMD_ERROR_ERROR] = (float)(uint32_t)e;
    v[MC_CAN_CMD_ERROR_RX_LEN] = (float)len;
    v[MC_CAN_CMD_ERROR_SEQ] = (float)c->err_seq;
    c->err_seq = (uint8_t)(c->err_seq + 1u);
    if (mc_can_proto_pack(MC_CAN_MSG_CMD_ERROR, c->cfg.node_id, v, MC_CAN_CMD_ERROR_NSIG, &f) !=
        MC_CAN_ERR_NONE) {
        c->reply_dropped++;
        return;
    }
    (void)reply_send(c, can, &f); /* a token is there (checked above) */
}

mc_can_err_t mc_can_cmd_handle(mc_can_cmd_t *c, const mc_hal_can_frame_t *p_frame,
                               const mc_hal_can_t *can)
{
    float v[MC_CAN_NSIG_MAX] = {0.0f};
    uint32_t msg = MC_CAN_MSG_COUNT;
    uint32_t cmd;
    mc_can_err_t e;
    if ((c == NULL) || (p_frame == NULL)) {
        return MC_CAN_ERR_ARG;
    }
    /* our identifiers are 11-bit: an extended frame belongs to someone else */
    if (((p_frame->flags & MC_HAL_CAN_FLAG_EXT) != 0u) ||
        (mc_can_id_node(p_frame->id) != (uint32_t)c->cfg.node_id) ||
        (p_frame->id > MC_HAL_CAN_STD_ID_MAX)) {
        return MC_CAN_ERR_IGNORED;
    }
    cmd = mc_can_id_cmd(p_frame->id);
    e = mc_can_proto_unpack(p_frame, &msg, v, MC_CAN_NSIG_MAX);
    if ((e == MC_CAN_ERR_NONE) && (mc_can_messages[msg].dir != (uint8_t)MC_CAN_DIR_RX)) {
        e = MC_CAN_ERR_UNKNOWN_CMD; /* a telemetry id sent to us */
    }
    if ((e == MC_CAN_ERR_NONE) && (msg == MC_CAN_MSG_PARAM_REQ)) {
        e = do_param(c, can, v, p_frame);
    } else if ((e == MC_CAN_ERR_NONE) && (msg == MC_CAN_MSG_BOOT_REQ)) {
        e = do_boot(c, can, p_frame);
    } else if (e == MC_CAN_ERR_NONE) {
        e = dispatch(c, msg, v);
    }
    if (e != MC_CAN_ERR_NONE) {
        reply_error(c, can, cmd, p_frame->len, e);
        return e;
    }
    c->rx_accepted++; /* no keep-alive by itself (mc_can_cmd.h) */
    return MC_CAN_ERR_NONE;
}

uint32_t mc_can_cmd_poll(mc_can_cmd_t *c, const mc_hal_can_t *can, uint32_t max_frames)
{
    uint32_t n = 0u;
    mc_hal_can_frame_t f;
    if ((c == NULL) || (can == NULL)) {
        return 0u;
    }
    uint32_t foreign = 0u;
    while ((n < max_frames) && (foreign < MC_CAN_RX_FOREIGN_MAX) &&
           (mc_hal_can_receive(can, &f) == 0)) {
        /* software acceptance filter: one comparison for another node's frame */
        if (((f.flags & MC_HAL_CAN_FLAG_EXT) != 0u) ||
            (mc_can_id_node(f.id) != (uint32_t)c->cfg.node_id)) {
            foreign++;
            c->rx_foreign++;
            continue;
        }
        (void)mc_can_cmd_handle(c, &f, can);
        n++;
    }
    if ((n + foreign) > c->poll_max) {
        c->poll_max = n + foreign;
    }
    return n;
}

static float toward_zero(float x, float step)
{
    if (x > step) {
        return x - step;
    }
    if (x < -step) {
        return x + step;
    }
    return 0.0f;
}

/* The end of a SPEED / POSITION stop: the bridge opens once the rotor is at
 * rest, or when the stop has taken longer than it could. */
static void end_at_rest(mc_can_cmd_t *c)
{
    const mc_drive_t *d = c->drive;
    const float rest =
        (d->cfg.stop_rest_rad_s > 0.0f) ? d->cfg.stop_rest_rad_s : MC_CAN_STOP_REST_RAD_S;
    if (!(mc_abs_f32(d->tm.omega_m_rad_s) > rest) || (c->stop_ticks_left == 0u)) {
        end_run(c, (uint8_t)MC_CAN_STOP_CMD_TIMEOUT);
        return;
    }
    c->stop_ticks_left--;
}

/* Start of a stop without the drive's controlled stop (mc_can_cmd.h). */
static void stop_begin(mc_can_cmd_t *c)
{
    mc_drive_t *d = c->drive;
    const float w0 = mc_isfinite_f32(d->tm.omega_m_rad_s) ? mc_abs_f32(d->tm.omega_m_rad_s) : 0.0f;
    const float limit_s = (2.0f * w0 / c->cfg.stop_decel_rad_s2) + 0.1f;
    c->stop_ticks_left = (uint32_t)(limit_s * (float)c->cfg.tick_hz);
    c->stop_by_law = false;
    if ((c->control_mode == MC_CAN_CTRL_POSITION) && (d->mode == MC_DRIVE_MODE_CTRL) &&
        (d->ctrl != NULL) && (d->ctrl->stop != NULL)) {
        c->stop_by_law = d->ctrl->stop(d->ctrl->ctx, c->cfg.stop_decel_rad_s2) == 0u;
    }
}

static void stop_step(mc_can_cmd_t *c)
{
    mc_drive_t *d = c->drive;
    const float dt = 1.0f / (float)c->cfg.tick_hz;
    if (c->control_mode == MC_CAN_CTRL_CURRENT && d->mode == MC_DRIVE_MODE_CURRENT) {
        const float step = c->cfg.stop_ramp_a_per_s * dt;
        const float id = toward_zero(d->id_ref_a, step);
        const float iq = toward_zero(d->iq_ref_a, step);
        /* smaller in magnitude than accepted references: cannot be refused */
        (void)mc_drive_set_current_ref(d, id, iq);
        if ((id == 0.0f) && (iq == 0.0f)) {
            end_run(c, (uint8_t)MC_CAN_STOP_CMD_TIMEOUT);
        }
        return;
    }
    if (c->control_mode == MC_CAN_CTRL_SPEED) {
        const float w = toward_zero(c->omega_ref_rad_s, c->cfg.stop_decel_rad_s2 * dt);
        if (c->cfg.set_speed_ref(c->cfg.hook_ctx, w) != 0) {
            c->omega_ref_rad_s = w;
            end_run(c, (uint8_t)MC_CAN_STOP_CMD_TIMEOUT);
            return;
        }
        c->omega_ref_rad_s = w;
        if (w == 0.0f) {
            end_at_rest(c); /* the speed loop brings the rotor to rest */
        }
        return;
    }
    if (c->stop_by_law && (d->mode == MC_DRIVE_MODE_CTRL)) {
        end_at_rest(c);
        return;
    }
    end_run(c,
            (uint8_t)MC_CAN_STOP_CMD_TIMEOUT); /* POSITION without a stop op, or the mode changed */
}

void mc_can_cmd_step(mc_can_cmd_t *c)
{
    if (c == NULL) {
        return;
    }
    if (c->ticks_since_alive < 0xFFFFFFFFu) {
        c->ticks_since_alive++;
    }
    mc_tm_reply_lim_step(&c->reply);
    if (c->held_have && reply_send(c, c->held_can, &c->held)) {
        c->held_have = false; /* the held PARAM_REPLY first */
    }
    if (c->params != NULL) {
        mc_param_srv_tick(c->params, c->cfg.tick_hz);
    }
    if (!c->enabled) {
        if (comm_busy(c) && (c->ticks_since_alive >= c->timeout_ticks) && (c->comm_lost != NULL)) {
            c->comm_lost(c->comm_ctx); /* commissioning without a host: bridge off */
            c->stop_reason = (uint8_t)MC_CAN_STOP_CMD_TIMEOUT;
        }
        return;
    }
    if (c->drive->mode == MC_DRIVE_MODE_FAULT) {
        end_run(c, (uint8_t)MC_CAN_STOP_FAULT);
        return;
    }
    if (c->angle_finding && (c->ticks_since_alive >= c->timeout_ticks)) {
        /* the find's bounded current holds the rotor near rest: off at once */
        end_run(c, (uint8_t)MC_CAN_STOP_CMD_TIMEOUT);
        return;
    }
    if (!c->stopping && (c->ticks_since_alive >= c->timeout_ticks)) {
        c->stopping = true;
        /* SPEED and POSITION with a controlled stop configured: the drive
         * decelerates to standstill itself before it opens the bridge
         * (mc_drive.h). CURRENT (torque) mode: the torque ramps to zero at
         * stop_ramp_a_per_s, then the bridge opens, whatever the load does
         * (the host owned the torque, not the speed: a speed-controlled stop
         * would brake, or drive, against it). */
        c->stop_by_drive =
            (c->control_mode != MC_CAN_CTRL_CURRENT) && (c->drive->cfg.stop_decel_rad_s2 > 0.0f);
        if (c->stop_by_drive) {
            (void)mc_drive_stop(c->drive);
        } else {
            stop_begin(c);
        }
    }
    if (c->stopping && c->stop_by_drive) {
        if (c->drive->mode != MC_DRIVE_MODE_STOPPING) {
            end_run(c, (uint8_t)MC_CAN_STOP_CMD_TIMEOUT);
        }
        return;
    }
    if (c->stopping) {
        stop_step(c);
    }
}
