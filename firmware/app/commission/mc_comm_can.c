/**
 * @file mc_comm_can.c
 * @brief Commissioning over CAN: see mc_comm_can.h.
 */
#include "mc_comm_can.h"

#include <stddef.h>
#include <string.h>

#include "config/mc_gains.h"
#include "math/mc_math.h"

uint32_t mc_comm_can_init(mc_comm_can_t *m, const mc_comm_can_cfg_t *cfg, mc_comm_t *comm,
                          mc_drive_t *drive, mc_param_srv_t *params)
{
    mc_comm_t probe;
    if ((m == NULL) || (cfg == NULL) || (comm == NULL) || (drive == NULL)) {
        return MC_COMM_CAN_CFG_ERR_NULL;
    }
    if ((mc_comm_init(&probe, &cfg->base) != MC_COMM_CFG_OK) ||
        ((uint32_t)cfg->node_id > MC_CAN_NODE_ID_MAX) || (cfg->status_div == 0u) ||
        !mc_isfinite_f32(cfg->enc_pll_bw_rad_s) || !(cfg->enc_pll_bw_rad_s > 0.0f)) {
        return MC_COMM_CAN_CFG_ERR_VALUE;
    }
    {
        const mc_comm_can_t z = {0};
        *m = z;
    }
    (void)mc_comm_init(comm, &cfg->base);
    m->cfg = *cfg;
    m->comm = comm;
    m->drive = drive;
    m->params = params;
    m->result_next = (uint8_t)MC_COMM_CAN_ITEM_COUNT;
    m->step = (uint8_t)MC_COMM_STEP_IDLE;
    return MC_COMM_CAN_CFG_OK;
}

void mc_comm_can_cfg_for_board(const mc_params_t *p, float i_sense_max_a, float vbus_low_v,
                               bool three_shunts, mc_comm_can_cfg_t *p_out)
{
    const float dt_s = 1.0f / (float)p->pwm_hz;
    const mc_comm_can_cfg_t zero = {0};
    mc_comm_can_cfg_t k = zero;
    mc_params_eff_t e;
    (void)mc_params_resolve(p, &e); /* the encoder loop's bandwidth, derived unless set */
    k.base.dt_s = dt_s;
    k.base.i_test_a = 0.25f * i_sense_max_a;
    k.base.v_test_max_v = 0.9f * vbus_low_v * 0.577350269f; /* / sqrt(3) */
    k.base.offset_max_a = 0.1f * i_sense_max_a;
    k.base.dead_time_s = p->dead_time_s;
    k.base.cur_bw_rad_s = 0.08f / dt_s;
    k.base.speed_max_m_rad_s = p->speed_max_rad_s;
    k.base.bemf_frac = 0.5f;
    k.base.pole_pairs_max = 32u;
    k.base.three_shunts = three_shunts;
    k.base.speed_tau_s =
        (p->encoder_type == MC_PARAMS_ENCODER_HALL) ? MC_COMM_HALL_SPEED_TAU_S : 0.0f;
    k.node_id = (uint8_t)p->can_node_id;
    k.status_div = (p->pwm_hz / p->slow_loop_div) / 10u; /* 10 Hz */
    if (k.status_div == 0u) {
        k.status_div = 1u;
    }
    k.enc_pll_bw_rad_s = e.p.speed_pll_bw_rad_s;
    *p_out = k;
}

bool mc_comm_can_busy(const void *ctx)
{
    return (ctx != NULL) && ((const mc_comm_can_t *)ctx)->running;
}

/* An option: 0 takes the default; else it replaces it. */
static float option(float v, float dflt)
{
    return (v > 0.0f) ? v : dflt;
}

#define INV_SQRT3_F 0.57735026918962576f
/** A default spin-up cap keeps this far below the over-speed trip. */
#define TRIP_MARGIN 0.9f

/* The drive's limits on the test values (mc_comm_can.h): current, voltage
 * (0 when the bus is not measured), speed (and the trip it must stay
 * strictly below; 0: off). */
typedef struct {
    float i_a, v_v, w_rad_s, w_trip_rad_s;
} limits_t;

static limits_t limits_of(const mc_comm_can_t *m)
{
    const mc_drive_t *d = m->drive;
    const float vbus = d->tm.vbus_v;
    limits_t l;
    l.i_a = d->cfg.i_max_a;
    l.v_v = (mc_isfinite_f32(vbus) && (vbus > 0.0f)) ? vbus * INV_SQRT3_F : 0.0f;
    l.w_rad_s = (m->params != NULL) ? m->params->active.speed_max_rad_s : 3.4e38f;
    l.w_trip_rad_s = (d->cfg.omega_max_rad_s > 0.0f) ? d->cfg.omega_max_rad_s : 0.0f;
    return l;
}

static bool within_limits(const limits_t *l, const mc_comm_cfg_t *cc)
{
    return (cc->i_test_a <= l->i_a) && (cc->v_test_max_v <= l->v_v) &&
           (cc->speed_max_m_rad_s <= l->w_rad_s) &&
           ((l->w_trip_rad_s == 0.0f) || (cc->speed_max_m_rad_s < l->w_trip_rad_s));
}

static float min_f(float a, float b)
{
    return (a < b) ? a : b;
}

/* The board's defaults bounded by the drive's limits: a zero option always
 * takes a value the drive allows (the image's boards default to a quarter
 * of their current-sense range, above a small motor's i_max_a). */
static void bound_defaults(const limits_t *l, mc_comm_cfg_t *cc)
{
    cc->i_test_a = min_f(cc->i_test_a, l->i_a);
    cc->v_test_max_v = min_f(cc->v_test_max_v, l->v_v);
    cc->speed_max_m_rad_s = min_f(cc->speed_max_m_rad_s, l->w_rad_s);
    if (l->w_trip_rad_s > 0.0f) {
        cc->speed_max_m_rad_s = min_f(cc->speed_max_m_rad_s, TRIP_MARGIN * l->w_trip_rad_s);
    }
}

static mc_can_err_t start(mc_comm_can_t *m, const float *v)
{
    mc_drive_t *d = m->drive;
    mc_comm_cfg_t cc = m->cfg.base;
    if (m->running) {
        return MC_CAN_ERR_MODE;
    }
    if ((d->mode == MC_DRIVE_MODE_FAULT) || (d->faults != 0u)) {
        return MC_CAN_ERR_REFUSED; /* a latched fault: clear it first */
    }
    if (d->mode != MC_DRIVE_MODE_IDLE) {
        return MC_CAN_ERR_MODE;
    }
    if (mc_drive_angle_state(d) == MC_DRIVE_ANGLE_NEED_INDEX) {
        /* angle_ref index: the offset is measured against the index, and the
         * encoder's count starts from it only once it has been seen; measured
         * before, it would be relative to the power-up count and wrong after
         * the next power cycle. Run the index search (or turn the rotor past
         * the index) first. */
        return MC_CAN_ERR_REFUSED;
    }
    {
        const limits_t lim = limits_of(m);
        mc_comm_t probe;
        bound_defaults(&lim, &cc);
        /* no encoder (none on the board, or encoder_cpr 0 in force): the
         * pole pairs in force (the user's), the flux from an I-f spin
         * (mc_commission.h, README.md "Without an encoder") */
        const bool no_enc = (d->hal->encoder == NULL) ||
                            ((m->params != NULL) && (m->params->active.encoder_cpr == 0u));
        cc.pole_pairs_given = no_enc ? d->cfg.pole_pairs : 0u;
        cc.i_test_a = option(v[MC_CAN_COMMISSION_CMD_I_TEST_A], cc.i_test_a);
        cc.v_test_max_v = option(v[MC_CAN_COMMISSION_CMD_V_TEST_MAX_V], cc.v_test_max_v);
        cc.speed_max_m_rad_s =
            option(v[MC_CAN_COMMISSION_CMD_SPEED_MAX_M_RAD_S], cc.speed_max_m_rad_s);
        if ((mc_comm_init(&probe, &cc) != MC_COMM_CFG_OK) || !within_limits(&lim, &cc)) {
            return MC_CAN_ERR_RANGE; /* nothing energised */
        }
    }
    m->prev_ctrl = d->ctrl;
    (void)mc_comm_init(m->comm, &cc);
    mc_comm_restart(m->comm);
    if (mc_drive_attach_ctrl(d, mc_comm_ops(m->comm)) != 0) {
        (void)mc_drive_attach_ctrl(d, m->prev_ctrl);
        return MC_CAN_ERR_REFUSED; /* no bridge or no encoder */
    }
    if (mc_drive_set_mode(d, MC_DRIVE_MODE_CTRL) != 0) {
        (void)mc_drive_attach_ctrl(d, m->prev_ctrl);
        return MC_CAN_ERR_REFUSED;
    }
    m->running = true;
    m->have_result = false;
    m->staged = false;
    m->err = MC_COMM_ERR_NONE;
    m->step = (uint8_t)MC_COMM_STEP_IDLE;
    m->result_next = (uint8_t)MC_COMM_CAN_ITEM_COUNT;
    m->status_due = true;
    m->div_n = 0u;
    return MC_CAN_ERR_NONE;
}

/* The run is over: bridge off, the application's plug-in back. */
static void finish(mc_comm_can_t *m, uint32_t err)
{
    mc_drive_t *d = m->drive;
    if (d->mode == MC_DRIVE_MODE_CTRL) {
        (void)mc_drive_set_mode(d, MC_DRIVE_MODE_IDLE);
    }
    (void)mc_drive_attach_ctrl(d, m->prev_ctrl);
    m->running = false;
    m->err = err;
    m->step = (uint8_t)((err == MC_COMM_ERR_NONE) ? MC_COMM_STEP_DONE : MC_COMM_STEP_FAILED);
    m->status_due = true;
}

void mc_comm_can_host_lost(void *ctx)
{
    mc_comm_can_t *m = (mc_comm_can_t *)ctx;
    if ((m != NULL) && m->running) {
        finish(m, m->comm->err | MC_COMM_ERR_ABORTED | MC_COMM_ERR_HOST_LOST);
    }
}

mc_can_err_t mc_comm_can_command(void *ctx, const float *v)
{
    mc_comm_can_t *m = (mc_comm_can_t *)ctx;
    if ((m == NULL) || (v == NULL)) {
        return MC_CAN_ERR_ARG;
    }
    switch ((uint32_t)v[MC_CAN_COMMISSION_CMD_ACTION]) {
    case MC_COMM_CAN_START:
        return start(m, v);
    case MC_COMM_CAN_ABORT:
        if (m->running) {
            finish(m, m->comm->err | MC_COMM_ERR_ABORTED);
        }
        return MC_CAN_ERR_NONE;
    case MC_COMM_CAN_REPORT:
        if (!m->have_result) {
            return MC_CAN_ERR_REFUSED; /* no successful run to report */
        }
        m->result_next = 0u;
        m->status_due = true;
        return MC_CAN_ERR_NONE;
    default:
        return MC_CAN_ERR_RANGE; /* the DBC range already stops it */
    }
}

static uint32_t f32_bits(float x)
{
    uint32_t u;
    (void)memcpy(&u, &x, sizeof u);
    return u;
}

static void collect(mc_comm_can_t *m)
{
    const mc_comm_result_t *r = &m->comm->res;
    const mc_drive_cfg_t *dc = &m->drive->cfg;
    float *o = m->result;
    o[MC_COMM_CAN_ITEM_R_OHM] = r->r_ohm;
    o[MC_COMM_CAN_ITEM_LD_H] = r->ld_h;
    o[MC_COMM_CAN_ITEM_LQ_H] = r->lq_h;
    o[MC_COMM_CAN_ITEM_FLUX_WB] = r->flux_wb;
    o[MC_COMM_CAN_ITEM_POLE_PAIRS] = (float)r->pole_pairs;
    o[MC_COMM_CAN_ITEM_ENCODER_OFFSET_RAD] = r->encoder_offset_rad;
    o[MC_COMM_CAN_ITEM_ENCODER_DIRECTION] = (float)r->encoder_direction;
    /* absolute: the offsets in use plus the measured remainder */
    for (uint32_t k = 0u; k < 3u; ++k) {
        o[MC_COMM_CAN_ITEM_ADC_OFFSET_A_A + k] = dc->i_offset_a[k] + r->adc_offset_a[k];
    }
    o[MC_COMM_CAN_ITEM_J_KGM2] = r->j_kgm2;
    o[MC_COMM_CAN_ITEM_B_NM_S_RAD] = r->b_nm_s_rad;
}

static bool write_f32(mc_param_srv_t *s, uint32_t id, float x)
{
    uint32_t raw = f32_bits(x);
    return mc_param_srv_request(s, MC_PARAM_OP_WRITE, id, &raw) == MC_PARAM_OK;
}

static bool write_u32(mc_param_srv_t *s, uint32_t id, uint32_t x)
{
    uint32_t raw = x;
    return mc_param_srv_request(s, MC_PARAM_OP_WRITE, id, &raw) == MC_PARAM_OK;
}

/* A reboot parameter (the Hall table): WRITE, and the CONFIRM the service
 * asks of any change of one (the sequence the host would send). */
static bool write_reboot(mc_param_srv_t *s, uint32_t id, uint32_t raw)
{
    uint32_t v = raw;
    const mc_param_status_t st = mc_param_srv_request(s, MC_PARAM_OP_WRITE, id, &v);
    if (st == MC_PARAM_OK) {
        return true;
    }
    v = raw;
    return (st == MC_PARAM_ERR_NEEDS_CONFIRM) &&
           (mc_param_srv_request(s, MC_PARAM_OP_CONFIRM, id, &v) == MC_PARAM_OK);
}

/* The Hall table measured: codes, edges and band (parameters 166-173).
 * Its edges are the d axis's angles (the vector's), so the drive's angle
 * from the count is the d axis's with encoder_offset_rad 0, and the codes
 * run in the positive order: encoder_reversed 0 (mc_drive_hall.h). The
 * encoder step's offset and direction are against the table the drive ran
 * the sequence on, and replaced here with the table. */
static bool stage_hall(mc_param_srv_t *s, const mc_comm_hall_table_t *t)
{
    static const uint32_t edge_id[MC_HALL_SECTORS] = {
        MC_PARAM_ID_HALL_EDGE0_E_RAD, MC_PARAM_ID_HALL_EDGE1_E_RAD, MC_PARAM_ID_HALL_EDGE2_E_RAD,
        MC_PARAM_ID_HALL_EDGE3_E_RAD, MC_PARAM_ID_HALL_EDGE4_E_RAD, MC_PARAM_ID_HALL_EDGE5_E_RAD};
    uint32_t codes = 0u;
    bool ok = true;
    for (uint32_t k = 0u; k < MC_HALL_SECTORS; k++) {
        codes |= ((uint32_t)t->code_of_sector[k] & 7u) << (3u * k);
        ok = ok && write_reboot(s, edge_id[k], f32_bits(t->edge_e_rad[k]));
    }
    return ok && write_reboot(s, MC_PARAM_ID_HALL_CODES, codes) &&
           write_reboot(s, MC_PARAM_ID_HALL_HYSTERESIS_E_RAD, f32_bits(t->hysteresis_e_rad)) &&
           write_f32(s, MC_PARAM_ID_ENCODER_OFFSET_RAD, 0.0f) &&
           write_u32(s, MC_PARAM_ID_ENCODER_REVERSED, 0u);
}

/* Every result into the staged set, each through the service's WRITE
 * checks; all or nothing. */
static bool stage(mc_comm_can_t *m)
{
    mc_param_srv_t *s = m->params;
    const mc_comm_result_t *r = &m->comm->res;
    const float *o = m->result;
    bool ok;
    mc_params_t keep;
    bool keep_pending;
    if (s == NULL) {
        return false;
    }
    keep = s->staged;
    keep_pending = s->pending;
    ok = write_f32(s, MC_PARAM_ID_R_OHM, r->r_ohm) && write_f32(s, MC_PARAM_ID_LD_H, r->ld_h) &&
         write_f32(s, MC_PARAM_ID_LQ_H, r->lq_h) && write_f32(s, MC_PARAM_ID_FLUX_WB, r->flux_wb) &&
         write_u32(s, MC_PARAM_ID_POLE_PAIRS, r->pole_pairs) &&
         (((r->valid & MC_COMM_HAVE_ENCODER) == 0u) ||
          (write_f32(s, MC_PARAM_ID_ENCODER_OFFSET_RAD, r->encoder_offset_rad) &&
           write_u32(s, MC_PARAM_ID_ENCODER_REVERSED, (r->encoder_direction < 0) ? 1u : 0u))) &&
         write_f32(s, MC_PARAM_ID_I_OFFSET_A_A, o[MC_COMM_CAN_ITEM_ADC_OFFSET_A_A]) &&
         write_f32(s, MC_PARAM_ID_I_OFFSET_B_A, o[MC_COMM_CAN_ITEM_ADC_OFFSET_B_A]) &&
         write_f32(s, MC_PARAM_ID_I_OFFSET_C_A, o[MC_COMM_CAN_ITEM_ADC_OFFSET_C_A]);
    if (ok && r->have_hall) {
        ok = stage_hall(s, &r->hall);
    }
    if (ok && ((r->valid & MC_COMM_HAVE_MECH) != 0u)) {
        /* the speed gains follow the identified inertia: 0 = derived from
         * it (mc_params_resolve: kp = J wc / kt, zero at wc / 4) */
        ok = write_f32(s, MC_PARAM_ID_J_KGM2, r->j_kgm2) &&
             write_f32(s, MC_PARAM_ID_B_NM_S_RAD, r->b_nm_s_rad) &&
             write_f32(s, MC_PARAM_ID_SPEED_KP_A_S_RAD, 0.0f) &&
             write_f32(s, MC_PARAM_ID_SPEED_KI_A_RAD, 0.0f);
    }
    if (!ok) {
        s->staged = keep;
        s->pending = keep_pending;
    }
    return ok;
}

static void follow(mc_comm_can_t *m)
{
    const mc_comm_t *c = m->comm;
    if (c->step == MC_COMM_STEP_DONE) {
        finish(m, MC_COMM_ERR_NONE); /* IDLE first: the writes need the bridge off */
        collect(m);
        m->have_result = true;
        m->staged = stage(m);
        if ((m->params != NULL) && !m->staged) {
            m->have_result = false;
            m->err = MC_COMM_ERR_RANGE;
            m->step = (uint8_t)MC_COMM_STEP_FAILED;
            return;
        }
        m->result_next = 0u;
        return;
    }
    if (m->drive->mode != MC_DRIVE_MODE_CTRL) {
        /* the plug-in failed (the drive faulted with its bits) or the
         * drive was stopped under it */
        const uint32_t hall = mc_comm_hall_fault_reason(c, m->drive->faults);
        finish(m, (c->err != MC_COMM_ERR_NONE) ? c->err
                  : (hall != 0u)               ? hall
                                               : MC_COMM_ERR_ABORTED);
        return;
    }
    if ((uint8_t)c->step != m->step) {
        m->step = (uint8_t)c->step;
        m->status_due = true;
    }
    if (++m->div_n >= m->cfg.status_div) {
        m->status_due = true;
    }
}

/* A reply frame may go out now (a token of lim, or no limiter). */
static bool may_send(mc_tm_reply_lim_t *lim)
{
    return (lim == NULL) || mc_tm_reply_lim_take(lim);
}

static void send(mc_comm_can_t *m, const mc_hal_can_t *can, uint32_t msg, const float *v,
                 uint32_t n, uint32_t raw_value)
{
    mc_hal_can_frame_t f;
    if (mc_can_proto_pack(msg, m->cfg.node_id, v, n, &f) != MC_CAN_ERR_NONE) {
        m->tx_dropped++;
        return;
    }
    if (msg == MC_CAN_MSG_COMMISSION_RESULT) {
        for (uint32_t i = 0u; i < 4u; ++i) {
            f.data[4u + i] = (uint8_t)(raw_value >> (8u * i));
        }
    }
    if (mc_hal_can_send(can, &f) != 0) {
        m->tx_dropped++;
    }
}

void mc_comm_can_step(mc_comm_can_t *m, const mc_hal_can_t *can, mc_tm_reply_lim_t *lim)
{
    if (m == NULL) {
        return;
    }
    if (m->running) {
        follow(m);
    }
    if (can == NULL) {
        m->status_due = false;
        m->result_next = (uint8_t)MC_COMM_CAN_ITEM_COUNT;
        return;
    }
    if ((m->status_due || (m->result_next < (uint8_t)MC_COMM_CAN_ITEM_COUNT)) && !may_send(lim)) {
        return; /* the reply limiter: the frame waits for a later step */
    }
    if (m->status_due) {
        float v[MC_CAN_COMMISSION_STATUS_NSIG];
        v[MC_CAN_COMMISSION_STATUS_STEP] = (float)m->step;
        v[MC_CAN_COMMISSION_STATUS_PROGRESS_PCT] =
            (float)(m->running ? m->comm->progress_pct
                               : ((m->step == (uint8_t)MC_COMM_STEP_DONE) ? 100u : 0u));
        uint32_t detail = 0u;
        v[MC_CAN_COMMISSION_STATUS_ERROR] = (float)mc_comm_err_frame(m->err, &detail);
        v[MC_CAN_COMMISSION_STATUS_DETAIL] = (float)detail;
        v[MC_CAN_COMMISSION_STATUS_VALID] =
            (float)(m->comm->res.valid & (MC_COMM_HAVE_ALL | MC_COMM_SENSORLESS));
        v[MC_CAN_COMMISSION_STATUS_STAGED] = m->staged ? 1.0f : 0.0f;
        v[MC_CAN_COMMISSION_STATUS_SEQ] = (float)m->status_seq;
        m->status_seq = (uint8_t)(m->status_seq + 1u);
        send(m, can, MC_CAN_MSG_COMMISSION_STATUS, v, MC_CAN_COMMISSION_STATUS_NSIG, 0u);
        m->status_due = false;
        m->div_n = 0u;
    } else if (m->result_next < (uint8_t)MC_COMM_CAN_ITEM_COUNT) {
        float v[MC_CAN_COMMISSION_RESULT_NSIG];
        v[MC_CAN_COMMISSION_RESULT_ITEM] = (float)m->result_next;
        v[MC_CAN_COMMISSION_RESULT_SEQ] = (float)m->result_seq;
        v[MC_CAN_COMMISSION_RESULT_VALUE] = 0.0f;
        m->result_seq = (uint8_t)(m->result_seq + 1u);
        send(m, can, MC_CAN_MSG_COMMISSION_RESULT, v, MC_CAN_COMMISSION_RESULT_NSIG,
             f32_bits(m->result[m->result_next]));
        m->result_next = (uint8_t)(m->result_next + 1u);
    }
}
