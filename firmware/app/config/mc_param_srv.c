/**
 * @file mc_param_srv.c
 * @brief The parameter service: see mc_param_srv.h.
 */
#include "mc_param_srv.h"

#include "mc_law_cfg.h"

#include <stddef.h>
#include <string.h>

int mc_param_srv_init(mc_param_srv_t *s, const mc_params_t *p, mc_drive_t *drive,
                      const mc_hal_t *hal, mc_cfg_store_t *store, uint8_t boot_status)
{
    if ((s == NULL) || (p == NULL) || (drive == NULL) || (hal == NULL) ||
        (mc_params_validate(p) != MC_PARAMS_OK)) {
        return -EINVAL;
    }
    {
        const mc_param_srv_t z = {0};
        *s = z;
    }
    s->active = *p;
    s->staged = *p;
    s->drive = drive;
    s->hal = hal;
    s->store = store;
    s->boot_status = boot_status;
    s->store_status = boot_status;
    s->save_tokens = MC_PARAM_SAVE_BURST;
    return 0;
}

void mc_param_srv_tick(mc_param_srv_t *s, uint32_t tick_hz)
{
    if ((s == NULL) || (tick_hz == 0u)) {
        return;
    }
    s->tick_hz = tick_hz;
    if (s->confirm_have) {
        if (s->confirm_left == 0u) {
            s->confirm_have = false; /* the window closed */
        } else {
            s->confirm_left--;
        }
    }
    if (s->save_tokens < MC_PARAM_SAVE_BURST) {
        s->save_acc++;
        if (s->save_acc >= MC_PARAM_SAVE_PERIOD_S * tick_hz) {
            s->save_acc = 0u;
            s->save_tokens++;
        }
    }
}

static bool bridge_on(const mc_param_srv_t *s)
{
    return (s->drive->mode == MC_DRIVE_MODE_CURRENT) || (s->drive->mode == MC_DRIVE_MODE_CTRL);
}

static bool fault_latched(const mc_param_srv_t *s)
{
    return (s->drive->mode == MC_DRIVE_MODE_FAULT) || (s->drive->faults != 0u);
}

static uint32_t read_value(const mc_param_srv_t *s, const mc_param_info_t *info)
{
    switch (info->id) {
    case MC_PARAM_ID_CFG_LAYOUT_VERSION:
        return MC_PARAMS_LAYOUT_VERSION;
    case MC_PARAM_ID_CFG_STORE_STATUS:
        return s->store_status;
    case MC_PARAM_ID_CFG_STORE_SEQ:
        return (s->store != NULL) ? s->store->seq : 0u;
    case MC_PARAM_ID_CFG_PENDING:
        return s->pending ? 1u : 0u;
    case MC_PARAM_ID_LAW_ERROR:
        return s->law_error;
    case MC_PARAM_ID_ANGLE_ERROR:
        return s->angle_error;
    case MC_PARAM_ID_HALL_ERROR:
        return s->hall_error;
    case MC_PARAM_ID_COG_STATUS:
        return s->cog_status;
    case MC_PARAM_ID_COG_CAL_STATUS:
        return s->cog_cal_status;
    case MC_PARAM_ID_HALL_OBS_WEIGHT: {
        uint32_t u;
        (void)memcpy(&u, &s->hall_obs_weight, sizeof u);
        return u;
    }
    default:
        return mc_param_get_raw(&s->staged, info);
    }
}

static mc_param_status_t do_write(mc_param_srv_t *s, uint32_t id, uint32_t value)
{
    const mc_param_info_t *info = mc_param_find(id, NULL);
    mc_param_status_t st;
    if (info == NULL) {
        return MC_PARAM_ERR_UNKNOWN_ID;
    }
    if (info->access == MC_PARAM_ACCESS_READONLY) {
        return MC_PARAM_ERR_READONLY;
    }
    st = mc_param_check_value(info, value);
    if (st != MC_PARAM_OK) {
        return st;
    }
    if ((info->access != MC_PARAM_ACCESS_RUNTIME) && bridge_on(s)) {
        return MC_PARAM_ERR_RUNNING;
    }
    if ((info->access == MC_PARAM_ACCESS_REBOOT) && (value != mc_param_get_raw(&s->staged, info))) {
        /* the node id or bit rate: only with the CONFIRM that must follow */
        s->confirm_have = true;
        s->confirm_id = id;
        s->confirm_value = value;
        s->confirm_left = MC_PARAM_CONFIRM_WINDOW_S * s->tick_hz;
        return MC_PARAM_ERR_NEEDS_CONFIRM;
    }
    mc_param_set_raw(&s->staged, info, value);
    s->pending = true;
    return MC_PARAM_OK;
}

/* The CONFIRM of the armed reboot parameter (the request just before). */
static mc_param_status_t do_confirm(mc_param_srv_t *s, bool armed, uint32_t id, uint32_t value)
{
    const mc_param_info_t *info;
    if (!armed || (id != s->confirm_id) || (value != s->confirm_value)) {
        return MC_PARAM_ERR_NOT_CONFIRMED;
    }
    if (bridge_on(s)) {
        return MC_PARAM_ERR_RUNNING;
    }
    info = mc_param_find(id, NULL); /* found at the WRITE: the table is const */
    if (info == NULL) {
        return MC_PARAM_ERR_NOT_CONFIRMED;
    }
    mc_param_set_raw(&s->staged, info, value);
    s->pending = true;
    return MC_PARAM_OK;
}

/* SAVE of the set in force as it is stored (do_save). */
static mc_param_status_t save_active(mc_param_srv_t *s, uint32_t *p_value)
{
    if (bridge_on(s)) {
        return MC_PARAM_ERR_RUNNING; /* an erase stalls the CPU for up to seconds */
    }
    if (s->store == NULL) {
        return MC_PARAM_ERR_STORE;
    }
    if (mc_cfg_store_holds(s->store, &s->active)) {
        s->saves_skipped++; /* the newest record is the applied set */
        s->store_status = (uint8_t)MC_CFG_BOOT_STORED;
        *p_value = s->store->seq;
        return MC_PARAM_OK;
    }
    if (s->save_tokens == 0u) {
        const uint32_t hz = (s->tick_hz == 0u) ? 1u : s->tick_hz;
        const uint32_t left = MC_PARAM_SAVE_PERIOD_S * hz - s->save_acc;
        s->saves_limited++;
        *p_value = (left + hz - 1u) / hz;
        return MC_PARAM_ERR_RATE_LIMIT;
    }
    s->save_tokens--; /* an attempt may have erased: it counts */
    if (mc_cfg_store_save(s->store, &s->active) != 0) {
        s->store_status = (uint8_t)MC_CFG_BOOT_FLASH;
        return MC_PARAM_ERR_STORE;
    }
    s->store_status = (uint8_t)MC_CFG_BOOT_STORED;
    *p_value = s->store->seq;
    return MC_PARAM_OK;
}

/* SAVE (mc_param_srv.h): unchanged skipped, the rate limit, the store.
 * anticogging 2 (a calibration runs) is stored as cog_persist, the value
 * before it, for the record and the check for an unchanged set alike: a
 * stored 2 would boot with the feed-forward on and no map measured. The
 * set in force keeps its 2 (patched in place: no second mc_params_t on the
 * stack, whose 4 KiB on the boards this path nearly fills). */
static mc_param_status_t do_save(mc_param_srv_t *s, uint32_t *p_value)
{
    const uint32_t cog = s->active.anticogging;
    if (cog == 2u) {
        s->active.anticogging = s->cog_persist;
    }
    const mc_param_status_t st = save_active(s, p_value);
    s->active.anticogging = cog;
    /* the configuration first, then the front end's records (behind it in
     * the sector: an older image's scan, which stops at them, still sees it) */
    if ((st == MC_PARAM_OK) && (s->hook.save != NULL) && (s->hook.save(s->hook.ctx) != 0)) {
        s->store_status = (uint8_t)MC_CFG_BOOT_FLASH;
        return MC_PARAM_ERR_STORE;
    }
    return st;
}

/* LOAD_DEFAULTS: the defaults staged, the reboot parameters kept. */
static void load_defaults(mc_param_srv_t *s)
{
    mc_params_t p = mc_params_default;
    for (uint32_t i = 0u; i < MC_PARAM_COUNT; ++i) {
        const mc_param_info_t *info = &mc_param_table[i];
        if (info->access == MC_PARAM_ACCESS_REBOOT) {
            mc_param_set_raw(&p, info, mc_param_get_raw(&s->staged, info));
        }
    }
    s->staged = p;
    s->pending = true;
}

/* A stopped or reboot parameter differs between staged and active. */
static bool needs_stop(const mc_param_srv_t *s)
{
    for (uint32_t i = 0u; i < MC_PARAM_COUNT; ++i) {
        const mc_param_info_t *info = &mc_param_table[i];
        if (((info->access == MC_PARAM_ACCESS_STOPPED) ||
             (info->access == MC_PARAM_ACCESS_REBOOT)) &&
            (mc_param_get_raw(&s->staged, info) != mc_param_get_raw(&s->active, info))) {
            return true;
        }
    }
    return false;
}

static mc_param_status_t do_apply(mc_param_srv_t *s, uint32_t *p_value)
{
    mc_drive_cfg_t cfg;
    uint32_t err = mc_params_validate(&s->staged);
    if ((err == MC_PARAMS_OK) && (s->hook.check != NULL)) {
        /* the front end's refusal: a law it cannot run (LAW), a value the
         * board cannot run (BOARD), else DRIVE */
        const uint32_t h = s->hook.check(s->hook.ctx, &s->staged);
        if ((h & MC_PARAMS_ERR_LAW) != 0u) {
            err = MC_PARAMS_ERR_LAW;
        } else if ((h & MC_PARAMS_ERR_BOARD) != 0u) {
            err = MC_PARAMS_ERR_BOARD;
        } else if (h != 0u) {
            err = MC_PARAMS_ERR_DRIVE;
        } else {
            /* accepted */
        }
    }
    if (err == MC_PARAMS_OK) {
        err = mc_params_to_drive_cfg(&s->staged, &cfg);
    }
    if (err != MC_PARAMS_OK) {
        if ((err & MC_PARAMS_ERR_LAW) != 0u) {
            const uint32_t why = mc_law_speed_check(&s->staged);
            if (why != 0u) {
                s->law_error = why; /* else the front end's hook set it */
            }
        }
        *p_value = err;
        return MC_PARAM_ERR_INVALID;
    }
    if (bridge_on(s)) {
        if (needs_stop(s)) {
            return MC_PARAM_ERR_RUNNING;
        }
        /* Only runtime parameters differ: the limits the running drive
         * reads every step (validated together above). */
        mc_drive_set_runtime_limits(s->drive, &cfg);
    } else {
        const mc_drive_ctrl_t *ctrl = s->drive->ctrl;
        if (mc_drive_init(s->drive, &cfg, s->hal) != MC_DRIVE_CFG_OK) {
            *p_value = MC_PARAMS_ERR_DRIVE; /* the HAL: validated otherwise */
            return MC_PARAM_ERR_INVALID;
        }
        if (ctrl != NULL) {
            (void)mc_drive_attach_ctrl(s->drive, ctrl); /* accepted before, bridge off */
        }
    }
    s->active = s->staged;
    s->pending = false;
    s->applied++;
    if (s->hook.apply != NULL) {
        s->hook.apply(s->hook.ctx, &s->active);
    }
    return MC_PARAM_OK;
}

mc_param_status_t mc_param_srv_request(mc_param_srv_t *s, uint32_t op, uint32_t id,
                                       uint32_t *p_value)
{
    bool armed;
    if ((s == NULL) || (p_value == NULL)) {
        return MC_PARAM_ERR_OPCODE;
    }
    /* a CONFIRM counts only as the very next request after its WRITE */
    armed = s->confirm_have;
    s->confirm_have = false;
    if (op == MC_PARAM_OP_READ) {
        const mc_param_info_t *info = mc_param_find(id, NULL);
        if (info == NULL) {
            return MC_PARAM_ERR_UNKNOWN_ID;
        }
        *p_value = read_value(s, info);
        return MC_PARAM_OK;
    }
    if (op > MC_PARAM_OP_CONFIRM) {
        return MC_PARAM_ERR_OPCODE;
    }
    if (fault_latched(s)) {
        return MC_PARAM_ERR_FAULT;
    }
    switch (op) {
    case MC_PARAM_OP_WRITE:
        return do_write(s, id, *p_value);
    case MC_PARAM_OP_APPLY:
        *p_value = 0u;
        return do_apply(s, p_value);
    case MC_PARAM_OP_SAVE:
        *p_value = 0u;
        return do_save(s, p_value);
    case MC_PARAM_OP_CONFIRM:
        return do_confirm(s, armed, id, *p_value);
    default: /* MC_PARAM_OP_LOAD_DEFAULTS */
        *p_value = 0u;
        if (bridge_on(s)) {
            return MC_PARAM_ERR_RUNNING;
        }
        load_defaults(s);
        return MC_PARAM_OK;
    }
}

bool mc_param_srv_save_budget_full(const mc_param_srv_t *s)
{
    return (s == NULL) || (s->save_tokens >= MC_PARAM_SAVE_BURST);
}
