/**
 * @file mc_app.c
 * @brief The drive application: see mc_app.h.
 */
#include "mc_app.h"

#include <stddef.h>
#include <string.h>

#include "math/mc_math.h"

#define RING_MASK (MC_APP_RX_RING_LEN - 1u)
#define NODE_MASK 0x7E0u /* the node bits of an 11-bit id (node << 5) */

/* ------------------------------------------------------------ receive ring */

bool mc_app_rx_ring_push(mc_app_rx_ring_t *r, const mc_hal_can_frame_t *p_frame)
{
    const uint32_t tail = __atomic_load_n(&r->tail, __ATOMIC_RELAXED);
    const uint32_t head = __atomic_load_n(&r->head, __ATOMIC_ACQUIRE);
    if ((uint32_t)(tail - head) >= MC_APP_RX_RING_LEN) {
        return false;
    }
    r->frames[tail & RING_MASK] = *p_frame;
    __atomic_store_n(&r->tail, tail + 1u, __ATOMIC_RELEASE);
    return true;
}

bool mc_app_rx_ring_pop(mc_app_rx_ring_t *r, mc_hal_can_frame_t *p_frame)
{
    const uint32_t head = __atomic_load_n(&r->head, __ATOMIC_RELAXED);
    const uint32_t tail = __atomic_load_n(&r->tail, __ATOMIC_ACQUIRE);
    if (head == tail) {
        return false;
    }
    *p_frame = r->frames[head & RING_MASK];
    __atomic_store_n(&r->head, head + 1u, __ATOMIC_RELEASE);
    return true;
}

/* ----------------------------------------------- flash with the watchdog */

/* The store's flash: an erase stalls the CPU (the code runs from the same
 * bank) for longer than the watchdog's normal timeout, so the timeout is
 * stretched around it. */
static int wrap_sector_size(void *ctx, uint32_t sector, uint32_t *p_bytes)
{
    const mc_app_t *a = ctx;
    return mc_hal_flash_sector_size(a->cfg.flash, sector, p_bytes);
}

static int wrap_erase(void *ctx, uint32_t sector)
{
    mc_app_t *a = ctx;
    int rc;
    if (a->wdg_running) {
        (void)mc_hal_wdg_start(a->cfg.wdg, a->cfg.wdg_erase_timeout_ms);
    }
    rc = mc_hal_flash_erase(a->cfg.flash, sector);
    if (a->wdg_running) {
        (void)mc_hal_wdg_start(a->cfg.wdg, a->cfg.wdg_timeout_ms);
    }
    return rc;
}

static int wrap_program(void *ctx, uint32_t sector, uint32_t offset, const uint32_t *p_words,
                        uint32_t n_words)
{
    const mc_app_t *a = ctx;
    return mc_hal_flash_program(a->cfg.flash, sector, offset, p_words, n_words);
}

static int wrap_read(void *ctx, uint32_t sector, uint32_t offset, void *p_buf, uint32_t len)
{
    const mc_app_t *a = ctx;
    return mc_hal_flash_read(a->cfg.flash, sector, offset, p_buf, len);
}

static const mc_hal_flash_ops_t wrap_flash_ops = {
    .sector_size = wrap_sector_size,
    .erase = wrap_erase,
    .program = wrap_program,
    .read = wrap_read,
};

/* -------------------------------------------------------------------- boot */

/* The stored anticogging map at boot (mc_cfg_store_load_map): cog_loaded
 * and why not (EMPTY none stored, LAYOUT another size, FLASH unreadable);
 * validated against the encoder when the drive starts (cog_bind). */
static void cog_boot(mc_app_t *a)
{
    const int rc = mc_cfg_store_load_map(&a->store, &a->cog_map, (uint32_t)sizeof a->cog_map);
    a->cog_loaded = (rc == 0);
    if (rc == 0) {
        a->cog_load_status = (uint32_t)MC_COG_ST_OK;
    } else if (rc == -ENOENT) {
        a->cog_load_status = (uint32_t)MC_COG_ST_EMPTY;
    } else if (rc == -EBADMSG) {
        a->cog_load_status = (uint32_t)MC_COG_ST_LAYOUT;
    } else {
        a->cog_load_status = (uint32_t)MC_COG_ST_FLASH;
    }
}

uint32_t mc_app_boot(mc_app_t *app, const mc_app_cfg_t *cfg)
{
    uint32_t err = MC_APP_CFG_OK;
    if ((app == NULL) || (cfg == NULL) || (cfg->defaults == NULL)) {
        return MC_APP_CFG_ERR_NULL;
    }
    if ((cfg->wdg != NULL) &&
        ((cfg->wdg_timeout_ms == 0u) || (cfg->wdg_timeout_ms > MC_HAL_WDG_TIMEOUT_MAX_MS) ||
         (cfg->wdg_erase_timeout_ms < cfg->wdg_timeout_ms) ||
         (cfg->wdg_erase_timeout_ms > MC_HAL_WDG_TIMEOUT_MAX_MS))) {
        return MC_APP_CFG_ERR_WDG;
    }
    {
        static const mc_app_t z = {0};
        *app = z;
    }
    app->cfg = *cfg;
    app->reset_cause = MC_HAL_WDG_RESET_NONE;
    if (cfg->wdg != NULL) {
        (void)mc_hal_wdg_reset_cause(cfg->wdg, &app->reset_cause);
    }
    app->params = *cfg->defaults;
    app->boot_status = (uint8_t)MC_CFG_BOOT_EMPTY;
    app->cog_load_status = (uint32_t)MC_COG_ST_EMPTY;
    if (cfg->flash != NULL) {
        mc_params_t loaded;
        mc_cfg_store_cfg_t scfg;
        app->flash_wrap.ops = &wrap_flash_ops;
        app->flash_wrap.ctx = app;
        scfg.flash = &app->flash_wrap;
        scfg.sector[0] = cfg->flash_sectors[0];
        scfg.sector[1] = cfg->flash_sectors[1];
        scfg.axis = cfg->flash_axis;
        if (mc_cfg_store_init(&app->store, &scfg) != 0) {
            err |= MC_APP_CFG_ERR_STORE;
        } else {
            mc_cfg_boot_t b;
            app->have_store = true;
            b = mc_cfg_store_load(&app->store, &loaded);
            if ((b == MC_CFG_BOOT_STORED) || (b == MC_CFG_BOOT_MIGRATED)) {
                const bool fits =
                    ((cfg->pwm_hz_fixed == 0u) || (loaded.pwm_hz == cfg->pwm_hz_fixed)) &&
                    ((cfg->slow_loop_div_fixed == 0u) ||
                     (loaded.slow_loop_div == cfg->slow_loop_div_fixed));
                if (fits) {
                    app->params = loaded;
                    if (app->params.anticogging == 2u) {
                        /* a request, never a setting (mc_param_srv do_save
                         * stores the value before it): no calibration and no
                         * feed-forward at boot */
                        app->params.anticogging = 0u;
                    }
                } else {
                    b = MC_CFG_BOOT_INVALID; /* a set this board cannot run */
                }
            }
            app->boot_status = (uint8_t)b;
            cog_boot(app);
        }
    }
    app->status_sent_cfg = app->boot_status;
    return err;
}

/* ------------------------------------------------------------------- start */

/* Setpoint hooks of the command handler (context: the app). */
static int speed_ref_hook(void *ctx, float ref)
{
    mc_app_t *a = ctx;
    return a->cfg.speed_law.set_ref(a->cfg.speed_law.ctx, ref);
}

static int position_ref_hook(void *ctx, float ref)
{
    const mc_app_t *a = ctx;
    return a->cfg.position_law.set_ref(a->cfg.position_law.ctx, ref);
}

/* ------------------------------------------------ the laws from parameters */

/* Every speed law of the parameters takes the drive's shaped reference: the
 * target goes to the drive (the sensorless law's own speed limit, lower
 * than the command handler's, refuses above it). */
static int drive_speed_hook(void *ctx, float ref)
{
    mc_app_t *a = ctx;
    if (a->laws.sls_ok && !(mc_abs_f32(ref) <= a->laws.sls_speed_max_rad_s)) {
        return -1;
    }
    return mc_drive_set_speed_ref(a->drive, ref);
}

/* ref is relative to the angle at enable (mc_can_cmd.h); the position
 * law's frame is turn 0 at enable plus the encoder's angle within its turn
 * (mc_ctrl_position.h): the angle at enable is added. */
static int pos_ref_hook(void *ctx, float ref)
{
    mc_app_t *a = ctx;
    return (mc_ctrl_pos_set_target_rad(&a->laws.pos, ref + a->pos_theta0_rad) == 0u) ? 0 : -1;
}

/* The encoder's angle within its turn as the law's first step will see it
 * (the rotor at rest or nearly: the last step's). */
static void pos_frame_at_enable(mc_app_t *a)
{
    const float th = a->drive->tm.theta_m_rad;
    /* the law counts the HAL's raw count: a reversed encoder's cpr - count */
    const bool rev = a->drive->cfg.encoder_reversed && (th > 0.0f);
    a->pos_theta0_rad = !mc_isfinite_f32(th) ? 0.0f : (rev ? (MC_TWO_PI_F32 - th) : th);
}

/* The configurations of every law for p (the builders zero them first, so
 * that they compare bytewise). Returns the gains' bits; *p_sls_err etc. the
 * builders' own. */
typedef struct {
    mc_ctrl_speed_cfg_t spd;
    mc_ctrl_sls_cfg_t sls;
    mc_ctrl_pi2d_cfg_t pi2d;
    mc_ctrl_pos_cfg_t pos;
    mc_ctrl_align_cfg_t align;
    mc_ctrl_idx_cfg_t idx;
    uint32_t gains_err, pi2d_err;
} laws_cfgs_t;

static void laws_cfgs(const mc_app_t *a, const mc_params_t *p, laws_cfgs_t *c)
{
    mc_gains_motor_t m;
    mc_gains_t g;
    mc_drive_cfg_t dc;
    (void)memset(c, 0, sizeof *c);
    c->gains_err = mc_law_gains_from_params(p, &m, &g);
    if (c->gains_err != MC_GAINS_OK) {
        return;
    }
    mc_law_speed_cfg(&m, &g, &c->spd);
    mc_law_sls_cfg(&m, &g, &c->sls);
    c->sls.law_mtpa = p->fw_enable == 0u; /* else the drive's MTPA shapes the command */
    c->pi2d_err = mc_law_pi2d_cfg(&m, &g, &c->pi2d);
    mc_law_pos_cfg(&m, &g, &c->pos);
    c->pos.input_mode = (p->pos_input_mode != 0u) ? MC_TRAJ_MODE_FILTER : MC_TRAJ_MODE_TRAP;
    /* built whatever angle_ref (an APPLY compares them); initialised only
     * for the reference that needs it */
    if ((p->encoder_cpr != 0u) && (mc_params_to_drive_cfg(p, &dc) == MC_PARAMS_OK)) {
        mc_law_find_cfg(p, &m, &g, &dc, a->hal->encoder, &c->align, &c->idx);
    }
}

/* The law that finds the angle after a power-up, the one angle_ref selects
 * (with an encoder). Returns law_error bits. */
static uint32_t finder_init(mc_app_laws_t *l, const mc_params_t *p, const laws_cfgs_t *c)
{
    l->align_ok = false;
    l->idx_ok = false;
    l->angle_ref = p->angle_ref;
    l->find_at_enable = (p->angle_find_at_enable != 0u);
    if (p->encoder_cpr == 0u) {
        return 0u; /* mc_params_validate refuses a reference without an encoder */
    }
    if (p->angle_ref == MC_DRIVE_ANGLE_REF_ALIGN) {
        l->align_ok = mc_ctrl_align_init(&l->align, &c->align) == 0u;
        return l->align_ok ? 0u : MC_LAW_ERR_ALIGN_INIT;
    }
    if (p->angle_ref == MC_DRIVE_ANGLE_REF_INDEX) {
        l->idx_ok = mc_ctrl_idx_init(&l->idx, &c->idx) == 0u;
        return l->idx_ok ? 0u : MC_LAW_ERR_IDX_INIT;
    }
    return 0u;
}

/* Initialise the laws the set selects from c; a law whose init refuses is
 * left out. Returns law_error bits (of the selected laws). */
static uint32_t laws_init(mc_app_t *a, const mc_params_t *p, const laws_cfgs_t *c)
{
    mc_app_laws_t *l = &a->laws;
    uint32_t err = c->gains_err;
    l->speed_law = p->speed_law;
    l->spd_ok = false;
    l->sls_ok = false;
    l->pi2d_ok = false;
    l->pos_ok = false;
    l->sls_speed_max_rad_s = c->sls.speed_max_rad_s;
    l->align_ok = false;
    l->idx_ok = false;
    if (c->gains_err != MC_GAINS_OK) {
        return err;
    }
    if (p->speed_law == MC_LAW_SPEED_SENSORLESS) {
        l->sls_ok = mc_ctrl_sls_init(&l->sls, &c->sls) == 0u;
        err |= l->sls_ok ? 0u : MC_LAW_ERR_SLS_INIT;
    } else if (p->speed_law == MC_LAW_SPEED_PI2D) {
        if (p->encoder_cpr == 0u) {
            err |= MC_LAW_ERR_ENCODER;
        } else if (c->pi2d_err != 0u) {
            err |= c->pi2d_err;
        } else {
            l->pi2d_ok = mc_ctrl_pi2d_init(&l->pi2d, &c->pi2d) == 0u;
            err |= l->pi2d_ok ? 0u : MC_LAW_ERR_PI2D_INIT;
        }
    } else if (p->encoder_cpr == 0u) {
        err |= MC_LAW_ERR_ENCODER; /* the sensored speed law */
    } else {
        l->spd_ok = mc_ctrl_speed_init(&l->spd, &c->spd) == 0u;
        err |= l->spd_ok ? 0u : MC_LAW_ERR_SPD_INIT;
    }
    if (p->encoder_cpr != 0u) {
        l->pos_ok = mc_ctrl_pos_init(&l->pos, &c->pos) == 0u;
        err |= l->pos_ok ? 0u : MC_LAW_ERR_POS_INIT;
    }
    err |= finder_init(l, p, c);
    (void)memcpy(&l->align_cfg, &c->align, sizeof l->align_cfg);
    (void)memcpy(&l->idx_cfg, &c->idx, sizeof l->idx_cfg);
    (void)memcpy(&l->spd_cfg, &c->spd, sizeof l->spd_cfg); /* padding too */
    (void)memcpy(&l->sls_cfg, &c->sls, sizeof l->sls_cfg);
    (void)memcpy(&l->pi2d_cfg, &c->pi2d, sizeof l->pi2d_cfg);
    (void)memcpy(&l->pos_cfg, &c->pos, sizeof l->pos_cfg);
    return err;
}

/* The slots and the command handler's modes from the laws. */
static void laws_plug(mc_app_t *a)
{
    mc_app_laws_t *l = &a->laws;
    const mc_app_law_t z = {0};
    a->cfg.speed_law = z;
    a->cfg.position_law = z;
    a->cfg.speed_law.set_ref = drive_speed_hook;
    if (l->sls_ok) {
        a->cfg.speed_law.ctrl = mc_ctrl_sls_ops(&l->sls);
        a->cfg.speed_law.tm_ext = &l->sls_ext;
    } else if (l->pi2d_ok) {
        a->cfg.speed_law.ctrl = mc_ctrl_pi2d_ops(&l->pi2d);
    } else if (l->spd_ok) {
        a->cfg.speed_law.ctrl = mc_ctrl_speed_ops(&l->spd);
    } else {
        a->cfg.speed_law.set_ref = NULL; /* SPEED unsupported */
    }
    a->cfg.speed_law.ctx = a;
    if (l->pos_ok) {
        a->cfg.position_law.ctrl = mc_ctrl_pos_ops(&l->pos);
        a->cfg.position_law.set_ref = pos_ref_hook;
        a->cfg.position_law.ctx = a;
    }
}

static void sls_ext_update(mc_app_t *a)
{
    mc_telemetry_ext_t *x = &a->laws.sls_ext;
    x->have_observer = true;
    x->tau_l_hat_nm = 0.0f; /* the law estimates no load torque */
    x->omega_hat_rad_s = a->laws.sls.tm.omega_hat_m_rad_s;
    x->theta_hat_rad = a->laws.sls.tm.theta_hat_e_rad;
}

/* Which laws the command handler offers (the slots, or the sensored PI). */
static void cmd_modes(const mc_app_t *a, mc_can_cmd_cfg_t *cc)
{
    cc->set_speed_ref = NULL;
    cc->set_position_ref = NULL;
    cc->speed_drive_mode = MC_DRIVE_MODE_IDLE;
    cc->position_drive_mode = MC_DRIVE_MODE_IDLE;
    if ((a->cfg.speed_law.ctrl != NULL) && (a->cfg.speed_law.set_ref != NULL)) {
        cc->set_speed_ref = speed_ref_hook;
        cc->speed_drive_mode = MC_DRIVE_MODE_CTRL;
    }
    if ((a->cfg.position_law.ctrl != NULL) && (a->cfg.position_law.set_ref != NULL)) {
        cc->set_position_ref = position_ref_hook;
        cc->position_drive_mode = MC_DRIVE_MODE_CTRL;
    }
}

/* Bytewise equality of two configurations built by the same builder (which
 * zeroes them first, padding included, and they are stored with memcpy):
 * any value that differs, differs here. */
static bool same_bytes(const void *a, const void *b, size_t n)
{
    const uint8_t *pa = a;
    const uint8_t *pb = b;
    for (size_t i = 0u; i < n; i++) {
        if (pa[i] != pb[i]) {
            return false;
        }
    }
    return true;
}

/* An APPLY's laws: unchanged, or rebuilt while disabled (see mc_app.h).
 * With the bridge on only runtime parameters can differ (the service
 * refuses the others): the laws stay as they are and take the drive's
 * limits in force each step. */
static uint32_t laws_check(mc_app_t *a, const mc_params_t *p)
{
    laws_cfgs_t c;
    mc_app_laws_t *l = &a->laws;
    uint32_t err;
    if (a->cmd.enabled || (a->drive->mode != MC_DRIVE_MODE_IDLE)) {
        a->laws_rebuilt = false;
        return 0u;
    }
    laws_cfgs(a, p, &c);
    a->laws_rebuilt = true;
    if ((p->speed_law == l->speed_law) && (c.gains_err == MC_GAINS_OK) &&
        same_bytes(&c.spd, &l->spd_cfg, sizeof c.spd) &&
        same_bytes(&c.sls, &l->sls_cfg, sizeof c.sls) &&
        same_bytes(&c.pi2d, &l->pi2d_cfg, sizeof c.pi2d) &&
        same_bytes(&c.pos, &l->pos_cfg, sizeof c.pos) &&
        same_bytes(&c.align, &l->align_cfg, sizeof c.align) &&
        same_bytes(&c.idx, &l->idx_cfg, sizeof c.idx) && (p->angle_ref == l->angle_ref) &&
        ((p->angle_find_at_enable != 0u) == l->find_at_enable) &&
        (a->srv.active.encoder_cpr == p->encoder_cpr)) {
        return 0u;
    }
    err = laws_init(a, p, &c);
    /* the selected speed law must run; the position law is offered when it
     * can (law_error says why not) */
    if ((err & ~MC_LAW_ERR_POS_INIT) != 0u) {
        laws_cfgs(a, &a->srv.active, &c); /* the laws before (c reused: stack) */
        l->error = laws_init(a, &a->srv.active, &c);
        a->srv.law_error = err;
        a->laws_rebuilt = false;
        return MC_PARAMS_ERR_LAW;
    }
    l->error = err;
    return 0u;
}

/* What this board cannot run (MC_PARAMS_ERR_BOARD): the brake chopper
 * where it has none, or its bus limit raised above its own (the defaults'
 * vbus_board_max_v: the rating inside what its divider reads; a set may
 * lower it, never raise it or take it away). */
static bool board_refuses(const mc_app_cfg_t *cfg, const mc_hal_t *hal, const mc_params_t *p)
{
    const float board_v = (cfg->defaults != NULL) ? cfg->defaults->vbus_board_max_v : 0.0f;
    if ((p->brake_enable != 0u) && (hal->brake == NULL)) {
        return true; /* no brake chopper on this board */
    }
    if ((p->encoder_type == MC_PARAMS_ENCODER_HALL) && (cfg->hall == NULL)) {
        return true; /* no Hall inputs on this board */
    }
    return (board_v > 0.0f) && !((p->vbus_board_max_v > 0.0f) && (p->vbus_board_max_v <= board_v));
}

/* The parameter service's hook: the board's check (the PWM rate and the slow
 * divider stay the booted ones: the timer and the CAN tick run on them),
 * then the command handler's own check and apply (telemetry rates, timeout,
 * ramps, speed limit). */
/* ------------------------------------------------------------ anticogging */

/* The encoder a map is bound to: the parameters' type, counts, direction
 * and pole pairs, and the offset in force in the drive (the parameter's, or
 * what an alignment found since power-up: an encoder without an index
 * counts from where the rotor stood, so a map measured before a power cycle
 * no longer sits at the angle the counts say; the new offset tells it). */
static mc_cog_ident_t cog_ident(const mc_app_t *a, const mc_params_t *p)
{
    mc_cog_ident_t id;
    id.enc_type = p->encoder_type;
    id.enc_cpr = p->encoder_cpr;
    id.enc_reversed = p->encoder_reversed;
    id.pole_pairs = p->pole_pairs;
    id.enc_offset_rad =
        (a->drive != NULL) ? a->drive->cfg.encoder_offset_rad : p->encoder_offset_rad;
    return id;
}

/* cog_status from the map and the parameters in effect p; the map attached
 * to the drive when it is valid for this encoder, detached otherwise
 * (anticogging, the drive's cfg.anticogging, then has no effect). */
static void cog_bind(mc_app_t *a, const mc_params_t *p)
{
    const mc_cog_ident_t id = cog_ident(a, p);
    const uint32_t st =
        a->cog_loaded ? (uint32_t)mc_cog_check(&a->cog_map, &id) : a->cog_load_status;
    bool on = st == (uint32_t)MC_COG_ST_OK;
    if (a->drive != NULL) {
        on = on && (mc_drive_attach_cog(a->drive, &a->cog_map) == 0);
        if (!on) {
            (void)mc_drive_attach_cog(a->drive, NULL);
        }
    }
    a->srv.cog_status = st;
}

static const mc_params_t *active_params(const mc_app_t *a)
{
    return a->params_valid ? &a->srv.active : &a->params;
}

mc_cog_status_t mc_app_cog_load(mc_app_t *app, const float *i_q_a, uint32_t n)
{
    const mc_params_t *p;
    mc_cog_ident_t id;
    mc_cog_status_t st;
    if ((app == NULL) || (app->drive == NULL)) {
        return MC_COG_ST_ARG;
    }
    p = active_params(app);
    id = cog_ident(app, p);
    /* the fast step never reads a map half rebuilt */
    (void)mc_drive_attach_cog(app->drive, NULL);
    /* the slots unknown: the order the currents show, if one stands out */
    const uint32_t order = (p->cog_slots == 0u) ? mc_cog_find_order(i_q_a, n, p->pole_pairs)
                                                : mc_cog_order(p->cog_slots, p->pole_pairs);
    st = mc_cog_build(&app->cog_map, i_q_a, n, &id, MC_APP_COG_BOUND_FRAC * p->i_max_a, order);
    if (st == MC_COG_ST_OK) {
        app->cog_loaded = true;
        app->cog_load_status = (uint32_t)MC_COG_ST_OK;
        app->cog_unsaved = true;
    }
    cog_bind(app, p);
    return st;
}

int mc_app_cog_save(mc_app_t *app)
{
    const mc_cog_ident_t id = cog_ident(app, active_params(app));
    if (!app->cog_loaded || (mc_cog_check(&app->cog_map, &id) != MC_COG_ST_OK)) {
        return -ENOENT;
    }
    if ((app->drive->mode == MC_DRIVE_MODE_CURRENT) || (app->drive->mode == MC_DRIVE_MODE_CTRL) ||
        (app->drive->mode == MC_DRIVE_MODE_STOPPING)) {
        return -EBUSY;
    }
    if (!app->have_store) {
        return -ENODEV;
    }
    const int rc = mc_cfg_store_save_map(&app->store, &app->cog_map, (uint32_t)sizeof app->cog_map);
    if (rc == 0) {
        app->cog_unsaved = false;
    }
    return rc;
}

/* The param server's SAVE, after the configuration: a map built since the
 * last map save (a calibration's) is stored with it; none, or one not valid
 * for the encoder in force (cog_status says why), is no error. */
static int params_save(void *ctx)
{
    mc_app_t *a = ctx;
    if (!a->cog_unsaved) {
        return 0;
    }
    const int rc = mc_app_cog_save(a);
    return (rc == -ENOENT) ? 0 : rc;
}

/* anticogging 2 may be applied only where the calibration can run. */
static bool cog_cal_ready(const mc_app_t *a)
{
    return a->cmd.enabled && !a->cmd.stopping && !a->cmd.angle_finding &&
           (a->cmd.control_mode == MC_CAN_CTRL_SPEED) && (a->cmd.cfg.set_speed_ref != NULL) &&
           (a->cmd.omega_ref_rad_s == 0.0f) && !a->cog_cal_run;
}

/* The calibration's start, end and service are kept out of their callers
 * (noinline): inlined, their frames (a whole mc_drive_cfg_t here) sit on
 * the stack through params_apply's and mc_app_slow_work's deepest calls (the
 * command handler's APPLY), which overflowed the boards' 4 KiB main stack
 * (PIL: pil: stack overflow, hal/pil/mc_hal_pil.c). */
#define MC_APP_NOINLINE __attribute__((noinline))

/* anticogging := v in the sets in force and staged, and the drive's. */
static MC_APP_NOINLINE void cog_cal_set_mode(mc_app_t *a, uint32_t v)
{
    mc_drive_cfg_t dc = a->drive->cfg;
    a->srv.active.anticogging = v;
    a->srv.staged.anticogging = v;
    dc.anticogging = v != 0u;
    mc_drive_set_runtime_limits(a->drive, &dc);
}

static MC_APP_NOINLINE void cog_cal_start(mc_app_t *a, const mc_params_t *p)
{
    mc_comm_cog_cfg_t g;
    g.dt_s = (float)p->slow_loop_div / (float)p->pwm_hz;
    g.w_rad_s = MC_APP_COG_CAL_SPEED_RAD_S;
    g.t_ramp_s = MC_APP_COG_CAL_RAMP_S;
    g.t_settle_s = MC_APP_COG_CAL_SETTLE_S;
    g.i_bound_a = MC_APP_COG_BOUND_FRAC * p->i_max_a;
    g.agree_frac = MC_APP_COG_CAL_AGREE;
    g.i_floor_a = MC_APP_COG_CAL_FLOOR_FRAC * p->i_max_a;
    g.offset_known = mc_drive_angle_state(a->drive) == MC_DRIVE_ANGLE_KNOWN;
    (void)mc_drive_attach_cog(a->drive, NULL); /* the q reference without a map */
    const uint32_t e = mc_comm_cog_start(&a->cog_cal, &g);
    a->cog_cal_run = e == 0u;
    a->cog_cal_pass = 0u;
    a->srv.cog_cal_status = ((uint32_t)a->cog_cal.phase & 0xFFu) | ((e & 0xFFu) << 8);
    if (e != 0u) {
        a->srv.cog_cal_status = (uint32_t)MC_COMM_COG_FAILED | ((e & 0xFFu) << 8);
        cog_cal_set_mode(a, 0u);
        cog_bind(a, &a->srv.active);
    }
}

/* The slow step's part: the calibration's speed reference, its end. */
static MC_APP_NOINLINE void cog_cal_service(mc_app_t *a)
{
    float w = 0.0f;
    if (!a->cog_cal_run) {
        return;
    }
    if (!a->cmd.enabled || a->cmd.stopping || (a->cmd.control_mode != MC_CAN_CTRL_SPEED)) {
        mc_comm_cog_abort(&a->cog_cal);
    }
    const mc_drive_telemetry_t *tm = &a->drive->tm;
    /* the q reference the rotor took, the previous pass's feed-forward in
     * it (none in the first: no map is attached) */
    const uint32_t e = mc_comm_cog_step(&a->cog_cal, tm->theta_m_rad, tm->iq_ref_a, &w);
    if (a->cmd.enabled && !a->cmd.stopping && (a->cmd.cfg.set_speed_ref != NULL) &&
        (a->cmd.cfg.set_speed_ref(a->cmd.cfg.hook_ctx, w) == 0)) {
        a->cmd.omega_ref_rad_s = w;
    }
    uint32_t st = 0u;
    const float *i = mc_comm_cog_currents(&a->cog_cal);
    if (i != NULL) {
        st = (uint32_t)mc_app_cog_load(a, i, MC_COG_N);
    }
    a->srv.cog_cal_status =
        ((uint32_t)a->cog_cal.phase & 0xFFu) | ((e & 0xFFu) << 8) | ((st & 0xFFu) << 16);
    if ((a->cog_cal.phase == MC_COMM_COG_DONE) && (st == (uint32_t)MC_COG_ST_OK) &&
        ((a->cog_cal_pass + 1u) < MC_APP_COG_CAL_PASSES)) {
        /* the next pass runs on this pass's map (mc_app.h): the same
         * configuration, accepted once already */
        const mc_comm_cog_cfg_t g = a->cog_cal.cfg;
        a->cog_cal_pass++;
        (void)mc_drive_attach_cog(a->drive, &a->cog_map);
        (void)mc_comm_cog_start(&a->cog_cal, &g);
        a->srv.cog_cal_status = (uint32_t)a->cog_cal.phase; /* not DONE: a host would stop */
    }
    a->srv.cog_cal_status |= (a->cog_cal_pass & 0xFFu) << 24;
    if ((a->cog_cal.phase == MC_COMM_COG_DONE) || (a->cog_cal.phase == MC_COMM_COG_FAILED)) {
        a->cog_cal_run = false;
        const bool ok = (i != NULL) && (st == (uint32_t)MC_COG_ST_OK);
        if (ok) {
            a->srv.cog_cal_status = (uint32_t)MC_COMM_COG_DONE;
        } else if (i != NULL) {
            a->srv.cog_cal_status = (uint32_t)MC_COMM_COG_FAILED | ((st & 0xFFu) << 16) |
                                    ((a->cog_cal_pass & 0xFFu) << 24);
        }
        cog_cal_set_mode(a, ok ? 1u : 0u);
        cog_bind(a, &a->srv.active);
    }
}

static uint32_t params_check(void *ctx, const mc_params_t *p)
{
    mc_app_t *a = ctx;
    if (a->srv.active.anticogging != 2u) {
        a->srv.cog_persist = a->srv.active.anticogging; /* what a SAVE stores for a 2 */
    }
    if ((p->anticogging == 2u) && (a->srv.active.anticogging != 2u) && !cog_cal_ready(a)) {
        return MC_PARAMS_ERR_COG_CAL;
    }
    if ((p->pwm_hz != a->params.pwm_hz) || (p->slow_loop_div != a->params.slow_loop_div)) {
        return 1u;
    }
    if (board_refuses(&a->cfg, a->hal, p)) {
        return MC_PARAMS_ERR_BOARD;
    }
    if ((a->cmd_hook.check != NULL) && (a->cmd_hook.check(a->cmd_hook.ctx, p) != 0u)) {
        return 1u;
    }
    /* last: it rebuilds the laws when they change (the apply follows) */
    return a->cfg.laws_from_params ? laws_check(a, p) : 0u;
}

static void params_apply(void *ctx, const mc_params_t *p)
{
    mc_app_t *a = ctx;
    if (a->cmd_hook.apply != NULL) {
        a->cmd_hook.apply(a->cmd_hook.ctx, p);
    }
    if (a->cfg.laws_from_params && a->laws_rebuilt) {
        mc_can_cmd_cfg_t cc = a->cmd.cfg;
        laws_plug(a);
        cmd_modes(a, &cc);
        a->cmd.cfg.set_speed_ref = cc.set_speed_ref;
        a->cmd.cfg.set_position_ref = cc.set_position_ref;
        a->cmd.cfg.speed_drive_mode = cc.speed_drive_mode;
        a->cmd.cfg.position_drive_mode = cc.position_drive_mode;
        a->srv.law_error = a->laws.error;
    }
    cog_bind(a, p); /* the encoder or anticogging may have changed */
    if ((p->anticogging == 2u) && !a->cog_cal_run) {
        cog_cal_start(a, p);
    }
}

/* ------------------------------------------------- the angle at enable */

/* The law of the selected control mode (NULL: CURRENT, or none). */
static const mc_drive_ctrl_t *law_of(const mc_app_t *a)
{
    if (a->cmd.control_mode == MC_CAN_CTRL_SPEED) {
        return a->cfg.speed_law.ctrl;
    }
    if (a->cmd.control_mode == MC_CAN_CTRL_POSITION) {
        return a->cfg.position_law.ctrl;
    }
    return NULL;
}

/* SET_ENABLE's question (mc_can_cmd_angle_fn): enter mode now (0), find the
 * angle first (1), or refuse ANGLE_UNKNOWN (-1). See mc_app.h. */
static int angle_enable(void *ctx, mc_drive_mode_t mode)
{
    mc_app_t *a = ctx;
    mc_drive_t *d = a->drive;
    const mc_drive_ctrl_t *law = d->ctrl;
    const uint32_t st = mc_drive_angle_state(d);
    const mc_drive_ctrl_t *finder = NULL;
    bool needs;
    pos_frame_at_enable(a);
    needs = (mode == MC_DRIVE_MODE_CURRENT) || ((mode == MC_DRIVE_MODE_CTRL) && (law != NULL) &&
                                                law->needs_encoder && !law->finds_angle);
    if (!needs || (st == MC_DRIVE_ANGLE_KNOWN)) {
        return 0;
    }
    if (!a->laws.find_at_enable) {
        return -1;
    }
    if ((st == MC_DRIVE_ANGLE_NEED_ALIGN) && a->laws.align_ok) {
        finder = mc_ctrl_align_ops(&a->laws.align);
    } else if ((st == MC_DRIVE_ANGLE_NEED_INDEX) && a->laws.idx_ok) {
        finder = mc_ctrl_idx_ops(&a->laws.idx);
    } else {
        return -1; /* no finder for it (law_error says why) */
    }
    if ((mc_drive_attach_ctrl(d, finder) != 0) || (mc_drive_set_mode(d, MC_DRIVE_MODE_CTRL) != 0)) {
        (void)mc_drive_set_mode(d, MC_DRIVE_MODE_IDLE);
        return -1; /* the slow step attaches the law again */
    }
    a->angle_running = true;
    return 1;
}

/* The finder's status and failure bits. */
static mc_ctrl_align_status_t finder_status(const mc_app_t *a, uint32_t *p_fail, float *p_offset)
{
    if (a->drive->ctrl == &a->laws.align.ops) {
        mc_ctrl_align_result_t r;
        (void)mc_ctrl_align_get_result(&a->laws.align, &r);
        *p_fail = r.fail;
        *p_offset = r.offset_e_rad;
        return r.status;
    }
    if (a->drive->ctrl == &a->laws.idx.ops) {
        mc_ctrl_idx_result_t r;
        (void)mc_ctrl_idx_get_result(&a->laws.idx, &r);
        *p_fail = r.fail;
        *p_offset = -1.0f; /* the drive took the index */
        return r.status;
    }
    *p_fail = 0u;
    *p_offset = -1.0f;
    return MC_CTRL_ALIGN_FAILED; /* detached: the run ended */
}

/* Slow step, after the command handler's: a find that ended (see mc_app.h). */
static void angle_service(mc_app_t *a)
{
    uint32_t fail = 0u;
    float offset = -1.0f;
    mc_ctrl_align_status_t st;
    if (!a->angle_running) {
        return;
    }
    st = finder_status(a, &fail, &offset);
    if ((st == MC_CTRL_ALIGN_RUNNING) && a->cmd.enabled) {
        return;
    }
    a->angle_running = false;
    if (st == MC_CTRL_ALIGN_DONE) {
        a->angle_error = 0u;
        if (a->cmd.enabled && a->cmd.angle_finding) {
            const mc_drive_ctrl_t *law = law_of(a);
            if (offset >= 0.0f) {
                (void)mc_drive_set_encoder_offset(a->drive, offset);
                cog_bind(a, active_params(a)); /* the map checked at the new offset */
            }
            (void)mc_drive_set_mode(a->drive, MC_DRIVE_MODE_IDLE);
            if (law != NULL) {
                (void)mc_drive_attach_ctrl(a->drive, law);
            }
            pos_frame_at_enable(a);
            (void)mc_can_cmd_angle_found(&a->cmd);
        }
    } else if (fail != 0u) {
        /* the finder's error bits faulted the drive (bridge off in that
         * step); the command handler ended the run with FAULT: name it */
        a->angle_error = fail;
        if (a->cmd.enabled) {
            mc_can_cmd_end_run(&a->cmd, (uint8_t)MC_CAN_STOP_ANGLE_FIND);
        } else if (a->cmd.stop_reason == (uint8_t)MC_CAN_STOP_FAULT) {
            a->cmd.stop_reason = (uint8_t)MC_CAN_STOP_ANGLE_FIND;
        } else {
            /* ended otherwise (disable, timeout): its reason stands */
        }
    } else {
        /* the run ended before the find did (disable, timeout) */
    }
    a->srv.angle_error = a->angle_error;
}

/* BOOT_REQ (can/mc_boot_enter.h), answered on can. */
static void boot_req(void *ctx, const mc_hal_can_frame_t *p_frame, bool busy,
                     const mc_hal_can_t *can)
{
    mc_app_t *a = ctx;
    mc_hal_can_frame_t r;
    if ((mc_boot_enter_handle(&a->boot, p_frame, busy, &r) == 1u) && (can != NULL) &&
        (mc_hal_can_send(can, &r) != 0)) {
        a->cmd.reply_dropped++;
    }
}

static void boot_start(mc_app_t *a)
{
    uint32_t seed = 0u;
    if ((a->cfg.boot == NULL) || (a->cfg.enter_boot == NULL)) {
        return;
    }
    (void)mc_hal_tick_read(a->hal->tick, &seed);
    mc_boot_enter_init(&a->boot, a->cfg.boot, a->cmd.cfg.node_id, a->tick_hz, seed);
    mc_can_cmd_attach_boot(&a->cmd, boot_req, a);
    a->boot_on = true;
}

/* A confirmed ENTER, one slow step after its OK was queued: bridge off,
 * then the board resets into the bootloader. */
static void boot_service(mc_app_t *a)
{
    if (!a->boot_on) {
        return;
    }
    if (mc_boot_enter_due(&a->boot)) {
        (void)mc_drive_set_mode(a->drive, MC_DRIVE_MODE_IDLE);
        a->boot_entries++;
        a->cfg.enter_boot(a->cfg.boot_ctx);
        a->boot.due = false; /* only off the MCU does enter_boot return */
    }
    mc_boot_enter_step(&a->boot);
}

/* encoder_type 1: the Hall kernel on the board's inputs becomes the
 * drive's encoder (mc_drive_hall.h), in a copy of the board's HAL; NULL
 * when the table or the pole pairs are refused. */
/* The Hall + observer hand-over (hall_obs_end_e_rad_s > 0, validated with
 * the set: MC_PARAMS_ERR_HALL_OBS): attached to the drive just initialised.
 * Off: nothing attached, the drive's step pays one pointer test. */
static bool bind_hallobs(mc_app_t *a, const mc_params_t *p)
{
    mc_drive_hallobs_cfg_t hc;
    a->hallobs_on = false;
    if (!(p->hall_obs_end_e_rad_s > 0.0f)) {
        return true;
    }
    if ((mc_law_hallobs_cfg(p, &hc) != MC_DRIVE_HALLOBS_ERR_NONE) ||
        (mc_drive_hallobs_init(&a->hallobs, &hc) != MC_DRIVE_HALLOBS_ERR_NONE) ||
        (mc_drive_attach_hallobs(a->drive, &a->hallobs) != 0)) {
        return false;
    }
    a->hallobs_on = true;
    return true;
}

/* The hall_error parameter: the Hall kernel's reasons and the hand-over's
 * fallback (mc_drive_hallobs.h). */
static uint32_t hall_error_of(const mc_app_t *a)
{
    uint32_t e = a->hall.error;
    if (a->hallobs_on) {
        e |= ((a->hallobs.flags & MC_HALLOBS_ERR_DISAGREE) != 0u) ? MC_DRIVE_HALL_ERR_OBS_DISAGREE
                                                                  : 0u;
        e |= ((a->hallobs.flags & MC_HALLOBS_ERR_NAN) != 0u) ? MC_DRIVE_HALL_ERR_OBS_NAN : 0u;
    }
    return e;
}

static const mc_hal_t *bind_hall(mc_app_t *a, const mc_hal_t *hal, const mc_params_t *p)
{
    mc_drive_hall_cfg_t hc;
    hc.pole_pairs = p->pole_pairs;
    if ((mc_params_hall_table(p, &hc.table) != MC_PARAMS_OK) ||
        (mc_drive_hall_init(&a->hall, &hc, a->cfg.hall, hal->tick) != MC_DRIVE_HALL_ERR_NONE)) {
        return NULL;
    }
    a->hal_hall = *hal;
    a->hal_hall.encoder = mc_drive_hall_encoder(&a->hall);
    a->hal = &a->hal_hall;
    return &a->hal_hall;
}

uint32_t mc_app_start(mc_app_t *app, mc_drive_t *drive, const mc_hal_t *hal,
                      const mc_hal_can_t *can, bool init_drive)
{
    const mc_params_t *p;
    mc_telemetry_cfg_t *tc;
    mc_can_cmd_cfg_t cc;
    uint32_t i;
    if ((app == NULL) || (drive == NULL) || (hal == NULL)) {
        return MC_APP_CFG_ERR_NULL;
    }
    p = &app->params;
    app->drive = drive;
    app->hal = hal;
    app->can = can;
    if (board_refuses(&app->cfg, hal, p)) {
        /* a stored set this board cannot run (no brake chopper, its bus
         * limit raised): the defaults boot and cfg_store_status says so */
        if ((app->cfg.defaults == NULL) || board_refuses(&app->cfg, hal, app->cfg.defaults)) {
            return MC_APP_CFG_ERR_PARAMS;
        }
        app->params = *app->cfg.defaults;
        app->boot_status = (uint8_t)MC_CFG_BOOT_INVALID;
        app->status_sent_cfg = app->boot_status;
    }
    if (p->encoder_type == MC_PARAMS_ENCODER_HALL) {
        hal = bind_hall(app, hal, p);
        if (hal == NULL) {
            return MC_APP_CFG_ERR_PARAMS;
        }
    }
    app->params_valid = init_drive && (mc_params_validate(p) == MC_PARAMS_OK);
    if (init_drive) {
        mc_drive_cfg_t dc;
        if (!app->params_valid || (mc_params_to_drive_cfg(p, &dc) != MC_PARAMS_OK)) {
            return MC_APP_CFG_ERR_PARAMS;
        }
        app->drive_err = mc_drive_init(drive, &dc, hal);
        if (app->drive_err != MC_DRIVE_CFG_OK) {
            return MC_APP_CFG_ERR_DRIVE;
        }
        if (!bind_hallobs(app, p)) {
            return MC_APP_CFG_ERR_PARAMS;
        }
    }
    if ((p->slow_loop_div == 0u) || ((p->pwm_hz % p->slow_loop_div) != 0u)) {
        return MC_APP_CFG_ERR_PARAMS; /* the CAN tick must be a whole rate */
    }
    app->tick_hz = p->pwm_hz / p->slow_loop_div;

    tc = &app->tm_cfg;
    tc->node_id = (uint8_t)p->can_node_id;
    tc->bitrate_bps = p->can_bitrate_bps;
    tc->bus_budget_frac = app->cfg.tm_budget_frac;
    tc->tick_hz = app->tick_hz;
    tc->rate_hz[MC_TM_HEARTBEAT] = (uint16_t)p->tm_heartbeat_hz;
    tc->rate_hz[MC_TM_CURRENTS] = (uint16_t)p->tm_currents_hz;
    tc->rate_hz[MC_TM_VOLTAGES] = (uint16_t)p->tm_voltages_hz;
    tc->rate_hz[MC_TM_SPEED] = (uint16_t)p->tm_speed_hz;
    tc->rate_hz[MC_TM_POSITION] = (uint16_t)p->tm_position_hz;
    for (i = 0u; i < (uint32_t)MC_TM_COUNT - (uint32_t)MC_TM_OBSERVER; i++) {
        tc->rate_hz[(uint32_t)MC_TM_OBSERVER + i] = app->cfg.tm_ext_rate_hz[i];
    }
    app->tm_err = mc_telemetry_init(&app->tm, tc);
    if (app->tm_err != MC_TM_CFG_OK) {
        return MC_APP_CFG_ERR_TM;
    }

    cc.node_id = (uint8_t)p->can_node_id;
    cc.tick_hz = app->tick_hz;
    cc.timeout_s = p->can_timeout_s;
    cc.stop_ramp_a_per_s = p->stop_ramp_a_per_s;
    {
        /* the derived stop deceleration (mc_params_resolve); a set without
         * gains leaves the command handler's rule to refuse it */
        mc_params_eff_t e;
        (void)mc_params_resolve(p, &e);
        cc.stop_decel_rad_s2 = e.p.stop_decel_rad_s2;
        cc.speed_max_rad_s = p->speed_max_rad_s;
    }
    cc.hook_ctx = app;
    if (app->cfg.laws_from_params) {
        laws_cfgs_t lc;
        laws_cfgs(app, p, &lc);
        app->laws.error = laws_init(app, p, &lc);
        laws_plug(app);
    }
    cmd_modes(app, &cc);
    app->cmd_err = mc_can_cmd_init(&app->cmd, &cc, drive, &app->tm);
    if (app->cmd_err != MC_CAN_CMD_CFG_OK) {
        return MC_APP_CFG_ERR_CMD;
    }
    if (app->cfg.laws_from_params) {
        mc_can_cmd_attach_angle(&app->cmd, angle_enable, app);
    }
    if (app->params_valid) {
        if (mc_param_srv_init(&app->srv, p, drive, hal, app->have_store ? &app->store : NULL,
                              app->boot_status) != 0) {
            return MC_APP_CFG_ERR_PARAMS;
        }
        mc_can_cmd_attach_params(&app->cmd, &app->srv);
        app->srv.law_error = app->laws.error;
        app->cmd_hook = app->srv.hook;
        app->srv.hook.check = params_check;
        app->srv.hook.apply = params_apply;
        app->srv.hook.ctx = app;
        app->srv.hook.save = params_save;
    }
    cog_bind(app, p);
    boot_start(app);
    app->tm_src.drive = drive;
    app->tm_src.cmd = &app->cmd;
    app->tm_src.ext = NULL;
    app->tm_src.tm = &app->tm;
    app->status_pending = (app->reset_cause != MC_HAL_WDG_RESET_NONE);

    if (app->cfg.set_rx_filter != NULL) {
        (void)app->cfg.set_rx_filter(app->cfg.filter_ctx, (uint32_t)p->can_node_id << 5u,
                                     NODE_MASK);
    }
    if (app->cfg.wdg != NULL) {
        if (mc_hal_wdg_start(app->cfg.wdg, app->cfg.wdg_timeout_ms) == 0) {
            app->wdg_running = true;
        } else {
            app->faults |= MC_APP_FAULT_WDG;
        }
    }
    return MC_APP_CFG_OK;
}

/* -------------------------------------------------------------- fast loop */

void mc_app_fast_mark(mc_app_t *app)
{
    /* the only writer (the fast interrupt): a plain increment, published */
    __atomic_store_n(&app->fast_runs, app->fast_runs + 1u, __ATOMIC_RELAXED);
}

bool mc_app_fast_step(mc_app_t *app)
{
    const bool slow_due = mc_drive_fast_step(app->drive);
    mc_app_fast_mark(app);
    return slow_due;
}

/* ---------------------------------------------------------------- receive */

uint32_t mc_app_can_rx_isr(mc_app_t *app)
{
    mc_hal_can_frame_t f;
    uint32_t n = 0u;
    const mc_hal_can_t *can = app->can;
    const uint32_t node = (uint32_t)app->cmd.cfg.node_id;
    if (can == NULL) {
        return 0u;
    }
    /* bounded: a controller cannot deliver more than this per interrupt */
    while ((n < 2u * MC_APP_RX_RING_LEN) && (mc_hal_can_receive(can, &f) == 0)) {
        n++;
        if (((f.flags & MC_HAL_CAN_FLAG_EXT) != 0u) || (f.id > MC_HAL_CAN_STD_ID_MAX) ||
            (mc_can_id_node(f.id) != node)) {
            app->rx_foreign++;
            continue;
        }
        if (!mc_app_rx_ring_push(&app->rx, &f)) {
            app->rx_overflows++;
        }
    }
    return n;
}

/* -------------------------------------------------------------- slow loop */

/* The law of the selected control mode is the one attached (control modes
 * change only while disabled, so the drive is not running a law then). */
static void attach_law(mc_app_t *a)
{
    const mc_app_law_t *law = NULL;
    if (a->cmd.control_mode == MC_CAN_CTRL_SPEED) {
        law = &a->cfg.speed_law;
    } else if (a->cmd.control_mode == MC_CAN_CTRL_POSITION) {
        law = &a->cfg.position_law;
    }
    if ((law == NULL) || (law->ctrl == NULL)) {
        a->tm_src.ext = NULL;
        return;
    }
    if ((a->drive->ctrl != law->ctrl) && !a->cmd.enabled) {
        if (mc_drive_attach_ctrl(a->drive, law->ctrl) != 0) {
            return;
        }
    }
    a->tm_src.ext = law->tm_ext;
}

static void can_supervise(mc_app_t *a)
{
    mc_hal_can_status_t st;
    uint32_t f = 0u;
    if ((a->can == NULL) || (mc_hal_can_get_status(a->can, &st) != 0)) {
        return;
    }
    if (st.rx_overrun_count != a->can_status.rx_overrun_count) {
        a->hw_rx_overruns += st.rx_overrun_count - a->can_status.rx_overrun_count;
        f |= MC_APP_FAULT_CAN_RX_OVERRUN;
    }
    a->can_status = st;
    if (st.state == MC_HAL_CAN_STATE_BUS_OFF) {
        f |= MC_APP_FAULT_CAN_BUS_OFF;
    } else if (st.state == MC_HAL_CAN_STATE_ERROR_PASSIVE) {
        f |= MC_APP_FAULT_CAN_PASSIVE;
    }
    a->faults |= f;
    /* error-passive or bus-off: the host may not hear us, nor we it: stop
     * under control, and no clear while it lasts */
    mc_drive_warning_cause(a->drive, MC_DRIVE_WARN_CAN_BUS,
                           (f & (MC_APP_FAULT_CAN_BUS_OFF | MC_APP_FAULT_CAN_PASSIVE)) != 0u);
    /* The CAN run ends once the drive has stopped for the bus. */
    if (a->cmd.enabled && ((a->drive->warnings & MC_DRIVE_WARN_CAN_BUS) != 0u) &&
        (a->drive->mode != MC_DRIVE_MODE_STOPPING)) {
        (void)mc_drive_set_mode(a->drive, MC_DRIVE_MODE_IDLE);
        a->cmd.enabled = false;
        a->cmd.stopping = false;
        a->cmd.stop_reason = (uint8_t)MC_CAN_STOP_FAULT;
    }
}

static float sat_f(uint32_t v, uint32_t max)
{
    return (float)((v > max) ? max : v);
}

static void status_send(mc_app_t *a)
{
    float v[MC_CAN_APP_STATUS_NSIG];
    mc_hal_can_frame_t f;
    const uint32_t state = (uint32_t)a->can_status.state & 0x3u;
    const uint32_t key = (a->faults << 2u) | state;
    /* the store's status as the heartbeat says it (a SAVE changes it) */
    const uint8_t cfg = (a->cmd.params != NULL) ? a->cmd.params->store_status : a->boot_status;
    if ((key != a->status_sent_key) || (cfg != a->status_sent_cfg)) {
        a->status_pending = true;
    }
    if (!a->status_pending || (a->can == NULL)) {
        return;
    }
    v[MC_CAN_APP_STATUS_RESET_CAUSE] = (float)(a->reset_cause & 0x7Fu);
    v[MC_CAN_APP_STATUS_CFG_STATUS] = (float)cfg;
    v[MC_CAN_APP_STATUS_CAN_STATE] = (float)state;
    v[MC_CAN_APP_STATUS_APP_FAULTS] = (float)(a->faults & 0xFu);
    v[MC_CAN_APP_STATUS_TX_ERR_COUNT] = sat_f(a->can_status.tx_err_count, 255u);
    v[MC_CAN_APP_STATUS_RX_ERR_COUNT] = sat_f(a->can_status.rx_err_count, 255u);
    v[MC_CAN_APP_STATUS_RX_LOST] = sat_f(a->rx_overflows + a->hw_rx_overruns, 0xFFFFu);
    v[MC_CAN_APP_STATUS_SEQ] = (float)a->status_seq;
    if ((mc_can_proto_pack(MC_CAN_MSG_APP_STATUS, a->cmd.cfg.node_id, v, MC_CAN_APP_STATUS_NSIG,
                           &f) == MC_CAN_ERR_NONE) &&
        (mc_hal_can_send(a->can, &f) == 0)) {
        a->status_seq = (uint8_t)(a->status_seq + 1u);
        a->status_frames++;
        a->status_pending = false;
        a->status_sent_key = key;
        a->status_sent_cfg = cfg;
    }
}

static void wdg_service(mc_app_t *a)
{
    const uint32_t runs = __atomic_load_n(&a->fast_runs, __ATOMIC_RELAXED);
    if (!a->wdg_running) {
        return;
    }
    /* this slow step ran; the fast loop must have run since the last feed */
    if (runs != a->fast_runs_fed) {
        if (mc_hal_wdg_feed(a->cfg.wdg) == 0) {
            a->wdg_feeds++;
        }
        a->fast_runs_fed = runs;
    }
}

uint32_t mc_app_slow_work(mc_app_t *app)
{
    const mc_hal_can_t *can = app->can;
    const uint32_t faults_before = app->drive->faults | app->drive->warnings;
    uint32_t n = 0u;
    mc_hal_can_frame_t f;
    boot_service(app);
    /* commands, in reception order; the law of the control mode is
     * attached before each (a SET_ENABLE right after its SET_CONTROL_MODE
     * finds its law in place) */
    while ((n < MC_APP_RX_PER_STEP) && mc_app_rx_ring_pop(&app->rx, &f)) {
        attach_law(app);
        (void)mc_can_cmd_handle(&app->cmd, &f, can);
        n++;
    }
    attach_law(app);
    mc_can_cmd_step(&app->cmd);
    angle_service(app);
    attach_law(app);
    cog_cal_service(app);
    if (app->comm != NULL) {
        mc_comm_can_step(app->comm, can, &app->cmd.reply);
    }
    app->was_enabled = app->cmd.enabled;
    if (app->cfg.laws_from_params && app->laws.sls_ok) {
        sls_ext_update(app);
    }
    can_supervise(app);
    if ((faults_before != 0u) && ((app->drive->faults | app->drive->warnings) == 0u)) {
        app->faults = MC_APP_FAULT_NONE; /* CLEAR_FAULTS went through */
    }
    app->cmd.can_state = (uint8_t)mc_app_can_state(app);
    app->srv.hall_error = hall_error_of(app);
    app->srv.hall_obs_weight = app->hallobs_on ? app->hallobs.w_obs : 0.0f;
    app->tm_sent = mc_telemetry_step(&app->tm, can, &app->tm_src);
    status_send(app);
    wdg_service(app);
    return app->tm_sent;
}

void mc_app_slow_step(mc_app_t *app)
{
    mc_drive_slow_step(app->drive);
    (void)mc_app_slow_work(app);
}

void mc_app_probe(const mc_app_t *app, mc_app_probe_t *p)
{
    const mc_drive_t *d = app->drive;
    const mc_drive_ctrl_t *ctrl = d->ctrl;
    const mc_app_laws_t *l = &app->laws;
    const mc_app_probe_t z = {0};
    *p = z;
    p->mode = (uint32_t)d->mode;
    p->faults = d->faults;
    p->first_fault = d->first_fault;
    p->warnings = d->warnings;
    p->ctrl_err = d->tm.ctrl_err;
    p->stop_cause = d->stop_cause;
    p->cmd_enabled = app->cmd.enabled ? 1u : 0u;
    p->cmd_stop_reason = app->cmd.stop_reason;
    p->law_error = l->error;
    p->id_ref_a = d->tm.id_ref_a;
    p->iq_ref_a = d->tm.iq_ref_a;
    p->id_a = d->tm.foc.id_a;
    p->iq_a = d->tm.foc.iq_a;
    p->vd_v = d->tm.foc.vd_v;
    p->vq_v = d->tm.foc.vq_v;
    p->theta_e_rad = d->tm.theta_e_rad;
    p->omega_m_rad_s = d->tm.omega_m_rad_s;
    p->vbus_v = d->tm.vbus_v;
    p->regen_scale = d->tm.regen_scale;
    p->i_bus_est_a = mc_drive_bus_current_a(d);
    p->i_bus_mot_lim_a = d->bus.i_mot_lim_a;
    p->i_bus_regen_lim_a = d->bus.i_regen_lim_a;
    p->brake_duty = d->tm.brake_duty;
    p->fw_v_mag_v = d->tm.fw.v_mag_v;
    p->fw_v_max_v = d->tm.fw.v_max_v;
    p->omega_ref_rad_s = d->speed_ref_rad_s;
    p->asc_active = d->asc_active ? 1u : 0u;
    p->angle_state = mc_drive_angle_state(d);
    p->angle_finding = app->angle_running ? 1u : 0u;
    p->angle_error = app->angle_error;
    p->hall_error = hall_error_of(app);
    p->t_winding_est_c = d->thermal.t_w_c;
    p->i_limit_a = mc_drive_thermal_limit_a(&d->thermal, d->cfg.i_max_a);
    p->cog_status = app->srv.cog_status;
    p->cog_ff_a = d->tm.cog_ff_a;
    if ((ctrl != NULL) && app->cfg.laws_from_params) {
        if (l->pi2d_ok && (ctrl == &l->pi2d.ops)) {
            p->id_ref_a = l->pi2d.tm.id_ref_a;
            p->iq_ref_a = l->pi2d.tm.iq_ref_a;
            p->id_a = l->pi2d.tm.id_a;
            p->iq_a = l->pi2d.tm.iq_a;
            p->vd_v = l->pi2d.tm.vd_v;
            p->vq_v = l->pi2d.tm.vq_v;
        }
        if (l->pos_ok && (ctrl == &l->pos.ops)) {
            p->omega_ref_rad_s = l->pos.tm.omega_ref_rad_s;
        }
    }
    if (app->cfg.laws_from_params && l->sls_ok) {
        p->sls_phase = (uint32_t)l->sls.tm.phase;
        p->sls_handovers = l->sls.tm.handovers;
        p->sls_fallbacks = l->sls.tm.fallbacks;
        p->sls_theta_hat_e_rad = l->sls.tm.theta_hat_e_rad;
        p->sls_omega_if_rad_s = l->sls.tm.omega_if_m_rad_s;
    }
    if (app->cfg.laws_from_params && l->pos_ok) {
        p->pos_turns = l->pos.tm.turns;
        p->pos_count = l->pos.tm.count;
        p->pos_theta_ref_rad = l->pos.tm.theta_ref_rad;
        p->pos_traj_duration_s = mc_traj_f32_get_duration_s(&l->pos.traj);
        p->pos_traj_k = l->pos.traj.k;
    }
    p->tm_load_frac = app->tm.load_frac;
    p->tm_tx_frames = app->tm.tx_frames;
    p->tm_tx_dropped = app->tm.tx_dropped;
    p->tm_tx_nobufs = app->tm.tx_nobufs;
    p->tm_tx_busoff = app->tm.tx_busoff;
    p->tm_saturated = app->tm.saturated;
    p->cmd_rx_accepted = app->cmd.rx_accepted;
    p->cmd_rx_rejected = app->cmd.rx_rejected;
    p->cmd_reply_dropped = app->cmd.reply_dropped;
    p->cmd_reply_limited = app->cmd.reply_limited;
    p->cmd_rx_foreign = app->cmd.rx_foreign;
    p->cmd_poll_max = app->cmd.poll_max;
    p->app_rx_foreign = app->rx_foreign;
    p->app_rx_overflows = app->rx_overflows;
    p->speed_law = l->speed_law;
    p->tick_hz = app->tick_hz;
    p->boot_status = app->boot_status;
    p->store_seq = app->have_store ? app->store.seq : 0u;
    p->store_saves = app->have_store ? app->store.saves : 0u;
    p->srv_applied = app->params_valid ? app->srv.applied : 0u;
}

void mc_app_attach_commission(mc_app_t *app, mc_comm_can_t *m)
{
    app->comm = m;
    /* Hall sensors as the encoder: commissioning measures their table first */
    m->cfg.base.hall = (app->hal == &app->hal_hall) ? app->cfg.hall : NULL;
    mc_can_cmd_attach_commission(&app->cmd, mc_comm_can_command, mc_comm_can_busy,
                                 mc_comm_can_host_lost, m);
}

uint32_t mc_app_can_state(const mc_app_t *app)
{
    return (uint32_t)app->can_status.state & 0x3u;
}
