/**
 * @file mc_pil_frame.c
 * @brief PIL link frames: see mc_pil_frame.h.
 */
#include "mc_pil_frame.h"

#include <string.h>

/* Payload sizes [32-bit words]. */
#define CFG_WORDS   23u
#define READY_WORDS 3u
#define MEAS_WORDS  31u
#define OUT_WORDS   23u
#define APP_WORDS   (5u + MC_PIL_TM_EXT_RATES) /* budget, the rates, 4 words */
/* CAN frames: id, time stamp, length and flags, then the data rounded up
 * to whole words (CAN_TX: the period's seq first) */
#define CAN_HEAD_WORDS 3u
/* PARAMS: (id, raw) pairs */
#define PARAM_PAIR_WORDS 2u
#define END_WORDS        1u

uint16_t mc_pil_crc16(const uint8_t *p, size_t n)
{
    uint32_t crc = 0xFFFFu; /* 16-bit register kept in 32 bits, masked per step */
    for (size_t i = 0u; i < n; ++i) {
        crc ^= (uint32_t)p[i] << 8;
        for (int b = 0; b < 8; ++b) {
            crc = ((crc & 0x8000u) != 0u) ? ((crc << 1) ^ 0x1021u) : (crc << 1);
            crc &= 0xFFFFu;
        }
    }
    return (uint16_t)crc;
}

/* ---- writer ------------------------------------------------------------ */

typedef struct {
    uint8_t *buf;
    size_t pos;
} writer_t;

static void put_u32(writer_t *w, uint32_t v)
{
    w->buf[w->pos] = (uint8_t)(v & 0xFFu);
    w->buf[w->pos + 1u] = (uint8_t)((v >> 8) & 0xFFu);
    w->buf[w->pos + 2u] = (uint8_t)((v >> 16) & 0xFFu);
    w->buf[w->pos + 3u] = (uint8_t)((v >> 24) & 0xFFu);
    w->pos += 4u;
}

static void put_i32(writer_t *w, int32_t v)
{
    uint32_t u;
    memcpy(&u, &v, sizeof u);
    put_u32(w, u);
}

static void put_f32(writer_t *w, float v)
{
    uint32_t u;
    memcpy(&u, &v, sizeof u);
    put_u32(w, u);
}

/* Start a frame of `words` payload words; false if it does not fit. */
static bool begin(writer_t *w, uint8_t *buf, size_t cap, mc_pil_type_t type, uint32_t words)
{
    const size_t n = MC_PIL_HEADER_LEN + 4u * (size_t)words + MC_PIL_CRC_LEN;
    if (buf == NULL || cap < n) {
        return false;
    }
    w->buf = buf;
    buf[0] = MC_PIL_SYNC;
    buf[1] = (uint8_t)type;
    buf[2] = (uint8_t)(4u * words);
    w->pos = MC_PIL_HEADER_LEN;
    return true;
}

static size_t finish(writer_t *w)
{
    const uint16_t crc = mc_pil_crc16(&w->buf[1], w->pos - 1u);
    w->buf[w->pos] = (uint8_t)(crc & 0xFFu);
    w->buf[w->pos + 1u] = (uint8_t)(crc >> 8);
    return w->pos + MC_PIL_CRC_LEN;
}

/* ---- reader ------------------------------------------------------------ */

typedef struct {
    const uint8_t *buf;
    size_t pos;
} reader_t;

static uint32_t get_u32(reader_t *r)
{
    const uint8_t *p = &r->buf[r->pos];
    r->pos += 4u;
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static int32_t get_i32(reader_t *r)
{
    const uint32_t u = get_u32(r);
    int32_t v;
    memcpy(&v, &u, sizeof v);
    return v;
}

static float get_f32(reader_t *r)
{
    const uint32_t u = get_u32(r);
    float v;
    memcpy(&v, &u, sizeof v);
    return v;
}

size_t mc_pil_frame_len(const uint8_t *buf, size_t n)
{
    if (buf == NULL || n < MC_PIL_HEADER_LEN) {
        return 0u;
    }
    return MC_PIL_HEADER_LEN + (size_t)buf[2] + MC_PIL_CRC_LEN;
}

int mc_pil_frame_type(const uint8_t *buf, size_t n)
{
    if (buf == NULL || n < MC_PIL_HEADER_LEN + MC_PIL_CRC_LEN) {
        return MC_PIL_ERR_ARG;
    }
    if (buf[0] != MC_PIL_SYNC) {
        return MC_PIL_ERR_SYNC;
    }
    if (mc_pil_frame_len(buf, n) != n) {
        return MC_PIL_ERR_LEN;
    }
    const size_t body = n - MC_PIL_CRC_LEN;
    const uint16_t crc =
        (uint16_t)((uint16_t)buf[body] | (uint16_t)((uint16_t)buf[body + 1u] << 8));
    if (mc_pil_crc16(&buf[1], body - 1u) != crc) {
        return MC_PIL_ERR_CRC;
    }
    return (int)buf[1];
}

/* Check a complete frame of the expected type and payload size; on success
 * the reader points at the payload. */
static int open_frame(reader_t *r, const uint8_t *buf, size_t n, mc_pil_type_t type, uint32_t words)
{
    const int t = mc_pil_frame_type(buf, n);
    if (t < 0) {
        return t;
    }
    if (t != (int)type) {
        return MC_PIL_ERR_TYPE;
    }
    if ((size_t)buf[2] != 4u * (size_t)words) {
        return MC_PIL_ERR_LEN;
    }
    r->buf = buf;
    r->pos = MC_PIL_HEADER_LEN;
    return MC_PIL_OK;
}

/* ---- CFG --------------------------------------------------------------- */

size_t mc_pil_encode_cfg(const mc_drive_cfg_t *cfg, uint8_t *buf, size_t cap)
{
    writer_t w;
    if (cfg == NULL || !begin(&w, buf, cap, MC_PIL_TYPE_CFG, CFG_WORDS)) {
        return 0u;
    }
    const mc_foc_f32_cfg_t *f = &cfg->foc;
    put_f32(&w, f->r_ohm);
    put_f32(&w, f->ld_h);
    put_f32(&w, f->lq_h);
    put_f32(&w, f->flux_wb);
    put_f32(&w, f->kp_d_v_per_a);
    put_f32(&w, f->ki_d_v_per_as);
    put_f32(&w, f->kp_q_v_per_a);
    put_f32(&w, f->ki_q_v_per_as);
    put_f32(&w, f->dt_s);
    put_u32(&w, (uint32_t)f->aw);
    put_f32(&w, f->kaw_per_s);
    put_u32(&w, (uint32_t)f->limit_mode);
    put_f32(&w, f->v_limit_ratio);
    put_f32(&w, f->v_abs_max_v);
    put_u32(&w, f->decouple ? 1u : 0u);
    put_u32(&w, cfg->pole_pairs);
    put_f32(&w, cfg->encoder_offset_rad);
    put_f32(&w, cfg->speed_pll_bw_rad_s);
    put_u32(&w, cfg->slow_loop_div);
    put_f32(&w, cfg->i_max_a);
    put_f32(&w, cfg->i_trip_a);
    put_f32(&w, cfg->vbus_min_v);
    put_f32(&w, cfg->vbus_max_v);
    return finish(&w);
}

int mc_pil_decode_cfg(const uint8_t *buf, size_t n, mc_drive_cfg_t *out)
{
    reader_t r;
    if (out == NULL) {
        return MC_PIL_ERR_ARG;
    }
    const int rc = open_frame(&r, buf, n, MC_PIL_TYPE_CFG, CFG_WORDS);
    if (rc != MC_PIL_OK) {
        return rc;
    }
    mc_drive_cfg_t c;
    memset(&c, 0, sizeof c);
    c.foc.r_ohm = get_f32(&r);
    c.foc.ld_h = get_f32(&r);
    c.foc.lq_h = get_f32(&r);
    c.foc.flux_wb = get_f32(&r);
    c.foc.kp_d_v_per_a = get_f32(&r);
    c.foc.ki_d_v_per_as = get_f32(&r);
    c.foc.kp_q_v_per_a = get_f32(&r);
    c.foc.ki_q_v_per_as = get_f32(&r);
    c.foc.dt_s = get_f32(&r);
    /* Enumerations travel as numbers; mc_drive_init() rejects unknown ones. */
    c.foc.aw = (mc_pi_aw_t)get_u32(&r);
    c.foc.kaw_per_s = get_f32(&r);
    c.foc.limit_mode = (mc_svpwm_limit_t)get_u32(&r);
    c.foc.v_limit_ratio = get_f32(&r);
    c.foc.v_abs_max_v = get_f32(&r);
    c.foc.decouple = get_u32(&r) != 0u;
    c.pole_pairs = get_u32(&r);
    c.encoder_offset_rad = get_f32(&r);
    c.speed_pll_bw_rad_s = get_f32(&r);
    c.slow_loop_div = get_u32(&r);
    c.i_max_a = get_f32(&r);
    c.i_trip_a = get_f32(&r);
    c.vbus_min_v = get_f32(&r);
    c.vbus_max_v = get_f32(&r);
    *out = c;
    return MC_PIL_OK;
}

/* ---- READY ------------------------------------------------------------- */

size_t mc_pil_encode_ready(const mc_pil_ready_t *rd, uint8_t *buf, size_t cap)
{
    writer_t w;
    if (rd == NULL || !begin(&w, buf, cap, MC_PIL_TYPE_READY, READY_WORDS)) {
        return 0u;
    }
    put_u32(&w, rd->drive_cfg_err);
    put_u32(&w, rd->sysclk_hz);
    put_u32(&w, rd->version);
    return finish(&w);
}

int mc_pil_decode_ready(const uint8_t *buf, size_t n, mc_pil_ready_t *out)
{
    reader_t r;
    if (out == NULL) {
        return MC_PIL_ERR_ARG;
    }
    const int rc = open_frame(&r, buf, n, MC_PIL_TYPE_READY, READY_WORDS);
    if (rc != MC_PIL_OK) {
        return rc;
    }
    out->drive_cfg_err = get_u32(&r);
    out->sysclk_hz = get_u32(&r);
    out->version = get_u32(&r);
    return MC_PIL_OK;
}

/* ---- frames of words (PROBE) ------------------------------------------- */

size_t mc_pil_encode_words(mc_pil_type_t type, const uint32_t *words, uint32_t n_words,
                           uint8_t *buf, size_t cap)
{
    writer_t w;
    if ((words == NULL) || (n_words > MC_PIL_MAX_PAYLOAD / 4u) ||
        !begin(&w, buf, cap, type, n_words)) {
        return 0u;
    }
    for (uint32_t i = 0u; i < n_words; ++i) {
        put_u32(&w, words[i]);
    }
    return finish(&w);
}

int mc_pil_decode_words(const uint8_t *buf, size_t n, mc_pil_type_t type, uint32_t *words,
                        uint32_t n_words)
{
    reader_t r;
    if ((words == NULL) || (n_words > MC_PIL_MAX_PAYLOAD / 4u)) {
        return MC_PIL_ERR_ARG;
    }
    const int rc = open_frame(&r, buf, n, type, n_words);
    if (rc != MC_PIL_OK) {
        return rc;
    }
    for (uint32_t i = 0u; i < n_words; ++i) {
        words[i] = get_u32(&r);
    }
    return MC_PIL_OK;
}

/* ---- MEAS -------------------------------------------------------------- */

size_t mc_pil_encode_meas(const mc_pil_meas_t *m, uint8_t *buf, size_t cap)
{
    writer_t w;
    if (m == NULL || !begin(&w, buf, cap, MC_PIL_TYPE_MEAS, MEAS_WORDS)) {
        return 0u;
    }
    put_u32(&w, m->seq);
    put_i32(&w, m->adc_rc);
    put_f32(&w, m->adc.ia_a);
    put_f32(&w, m->adc.ib_a);
    put_f32(&w, m->adc.ic_a);
    put_f32(&w, m->adc.vbus_v);
    put_u32(&w, m->adc.valid_mask);
    put_u32(&w, m->adc.timestamp_ticks);
    put_u32(&w, m->adc.seq);
    put_i32(&w, m->enc_rc);
    put_u32(&w, m->enc.count);
    put_u32(&w, m->enc.counts_per_rev);
    put_u32(&w, m->enc.flags);
    put_u32(&w, m->enc.timestamp_ticks);
    put_i32(&w, m->fault_rc);
    put_u32(&w, m->fault.active_mask);
    put_u32(&w, m->fault.latched_mask);
    put_u32(&w, m->fault.gate_killed ? 1u : 0u);
    put_u32(&w, m->tick_ticks);
    put_u32(&w, m->tick_hz);
    put_u32(&w, m->cmd_flags);
    put_u32(&w, m->mode);
    put_f32(&w, m->id_ref_a);
    put_f32(&w, m->iq_ref_a);
    put_i32(&w, m->temp_rc);
    put_f32(&w, m->temp.power_stage_temp_c);
    put_f32(&w, m->temp.motor_temp_c);
    put_u32(&w, m->temp.valid_mask);
    put_u32(&w, m->temp.absent_mask);
    put_i32(&w, m->hall_rc);
    put_u32(&w, m->hall_code);
    return finish(&w);
}

int mc_pil_decode_meas(const uint8_t *buf, size_t n, mc_pil_meas_t *out)
{
    reader_t r;
    if (out == NULL) {
        return MC_PIL_ERR_ARG;
    }
    const int rc = open_frame(&r, buf, n, MC_PIL_TYPE_MEAS, MEAS_WORDS);
    if (rc != MC_PIL_OK) {
        return rc;
    }
    mc_pil_meas_t m;
    memset(&m, 0, sizeof m);
    m.seq = get_u32(&r);
    m.adc_rc = get_i32(&r);
    m.adc.ia_a = get_f32(&r);
    m.adc.ib_a = get_f32(&r);
    m.adc.ic_a = get_f32(&r);
    m.adc.vbus_v = get_f32(&r);
    m.adc.valid_mask = get_u32(&r);
    m.adc.timestamp_ticks = get_u32(&r);
    m.adc.seq = get_u32(&r);
    m.enc_rc = get_i32(&r);
    m.enc.count = get_u32(&r);
    m.enc.counts_per_rev = get_u32(&r);
    m.enc.flags = get_u32(&r);
    m.enc.timestamp_ticks = get_u32(&r);
    m.fault_rc = get_i32(&r);
    m.fault.active_mask = get_u32(&r);
    m.fault.latched_mask = get_u32(&r);
    m.fault.gate_killed = get_u32(&r) != 0u;
    m.tick_ticks = get_u32(&r);
    m.tick_hz = get_u32(&r);
    m.cmd_flags = get_u32(&r);
    m.mode = get_u32(&r);
    m.id_ref_a = get_f32(&r);
    m.iq_ref_a = get_f32(&r);
    m.temp_rc = get_i32(&r);
    m.temp.power_stage_temp_c = get_f32(&r);
    m.temp.motor_temp_c = get_f32(&r);
    m.temp.valid_mask = get_u32(&r);
    m.temp.absent_mask = get_u32(&r);
    m.hall_rc = get_i32(&r);
    m.hall_code = get_u32(&r);
    *out = m;
    return MC_PIL_OK;
}

/* ---- OUT --------------------------------------------------------------- */

size_t mc_pil_encode_out(const mc_pil_out_t *o, uint8_t *buf, size_t cap)
{
    writer_t w;
    if (o == NULL || !begin(&w, buf, cap, MC_PIL_TYPE_OUT, OUT_WORDS)) {
        return 0u;
    }
    put_u32(&w, o->seq);
    put_u32(&w, o->duty_set_count);
    put_f32(&w, o->duty_a);
    put_f32(&w, o->duty_b);
    put_f32(&w, o->duty_c);
    put_u32(&w, o->pwm_enabled);
    put_u32(&w, o->gate_kill_count);
    put_i32(&w, o->cmd_rc);
    put_u32(&w, o->mode);
    put_u32(&w, o->faults);
    put_u32(&w, o->first_fault);
    put_u32(&w, o->foc_err);
    put_f32(&w, o->id_a);
    put_f32(&w, o->iq_a);
    put_f32(&w, o->vd_v);
    put_f32(&w, o->vq_v);
    put_f32(&w, o->theta_e_rad);
    put_f32(&w, o->omega_m_rad_s);
    put_u32(&w, o->ipsr_fast);
    put_u32(&w, o->ipsr_slow);
    put_u32(&w, o->slow_ran);
    put_u32(&w, o->brake_set_count);
    put_f32(&w, o->brake_duty);
    return finish(&w);
}

int mc_pil_decode_out(const uint8_t *buf, size_t n, mc_pil_out_t *out)
{
    reader_t r;
    if (out == NULL) {
        return MC_PIL_ERR_ARG;
    }
    const int rc = open_frame(&r, buf, n, MC_PIL_TYPE_OUT, OUT_WORDS);
    if (rc != MC_PIL_OK) {
        return rc;
    }
    mc_pil_out_t o;
    o.seq = get_u32(&r);
    o.duty_set_count = get_u32(&r);
    o.duty_a = get_f32(&r);
    o.duty_b = get_f32(&r);
    o.duty_c = get_f32(&r);
    o.pwm_enabled = get_u32(&r);
    o.gate_kill_count = get_u32(&r);
    o.cmd_rc = get_i32(&r);
    o.mode = get_u32(&r);
    o.faults = get_u32(&r);
    o.first_fault = get_u32(&r);
    o.foc_err = get_u32(&r);
    o.id_a = get_f32(&r);
    o.iq_a = get_f32(&r);
    o.vd_v = get_f32(&r);
    o.vq_v = get_f32(&r);
    o.theta_e_rad = get_f32(&r);
    o.omega_m_rad_s = get_f32(&r);
    o.ipsr_fast = get_u32(&r);
    o.ipsr_slow = get_u32(&r);
    o.slow_ran = get_u32(&r);
    o.brake_set_count = get_u32(&r);
    o.brake_duty = get_f32(&r);
    *out = o;
    return MC_PIL_OK;
}

/* ---- END --------------------------------------------------------------- */

size_t mc_pil_encode_end(int32_t exit_code, uint8_t *buf, size_t cap)
{
    writer_t w;
    if (!begin(&w, buf, cap, MC_PIL_TYPE_END, END_WORDS)) {
        return 0u;
    }
    put_i32(&w, exit_code);
    return finish(&w);
}

int mc_pil_decode_end(const uint8_t *buf, size_t n, int32_t *out)
{
    reader_t r;
    if (out == NULL) {
        return MC_PIL_ERR_ARG;
    }
    const int rc = open_frame(&r, buf, n, MC_PIL_TYPE_END, END_WORDS);
    if (rc != MC_PIL_OK) {
        return rc;
    }
    *out = get_i32(&r);
    return MC_PIL_OK;
}

/* ---- HELLO ------------------------------------------------------------- */

size_t mc_pil_encode_hello(uint8_t *buf, size_t cap)
{
    writer_t w;
    if (!begin(&w, buf, cap, MC_PIL_TYPE_HELLO, 0u)) {
        return 0u;
    }
    return finish(&w);
}

int mc_pil_check_hello(const uint8_t *buf, size_t n)
{
    reader_t r;
    return open_frame(&r, buf, n, MC_PIL_TYPE_HELLO, 0u);
}

/* ---- PARAMS ------------------------------------------------------------ */

size_t mc_pil_encode_params(const uint32_t *ids, const uint32_t *raws, uint32_t n, uint8_t *buf,
                            size_t cap)
{
    writer_t w;
    if (ids == NULL || raws == NULL || n == 0u || n > MC_PIL_PARAMS_MAX ||
        !begin(&w, buf, cap, MC_PIL_TYPE_PARAMS, PARAM_PAIR_WORDS * n)) {
        return 0u;
    }
    for (uint32_t i = 0u; i < n; ++i) {
        put_u32(&w, ids[i]);
        put_u32(&w, raws[i]);
    }
    return finish(&w);
}

int mc_pil_decode_params(const uint8_t *buf, size_t n, uint32_t *ids, uint32_t *raws, uint32_t *p_n)
{
    reader_t r;
    if (ids == NULL || raws == NULL || p_n == NULL) {
        return MC_PIL_ERR_ARG;
    }
    const int t = mc_pil_frame_type(buf, n);
    if (t < 0) {
        return t;
    }
    if (t != (int)MC_PIL_TYPE_PARAMS) {
        return MC_PIL_ERR_TYPE;
    }
    const uint32_t pairs = (uint32_t)buf[2] / (4u * PARAM_PAIR_WORDS);
    if (pairs == 0u || pairs > MC_PIL_PARAMS_MAX ||
        (uint32_t)buf[2] != 4u * PARAM_PAIR_WORDS * pairs) {
        return MC_PIL_ERR_LEN;
    }
    const int rc = open_frame(&r, buf, n, MC_PIL_TYPE_PARAMS, PARAM_PAIR_WORDS * pairs);
    if (rc != MC_PIL_OK) {
        return rc;
    }
    for (uint32_t i = 0u; i < pairs; ++i) {
        ids[i] = get_u32(&r);
        raws[i] = get_u32(&r);
    }
    *p_n = pairs;
    return MC_PIL_OK;
}

/* ---- FLASH ------------------------------------------------------------- */

size_t mc_pil_encode_flash(uint32_t offset, const uint8_t *data, uint32_t n, uint8_t *buf,
                           size_t cap)
{
    writer_t w;
    if (data == NULL || n == 0u || n > MC_PIL_FLASH_CHUNK || (n % 4u) != 0u ||
        !begin(&w, buf, cap, MC_PIL_TYPE_FLASH, 1u + n / 4u)) {
        return 0u;
    }
    put_u32(&w, offset);
    memcpy(&w.buf[w.pos], data, n);
    w.pos += n;
    return finish(&w);
}

int mc_pil_decode_flash(const uint8_t *buf, size_t n, uint32_t *p_offset, const uint8_t **p_data,
                        uint32_t *p_n)
{
    reader_t r;
    if (p_offset == NULL || p_data == NULL || p_n == NULL) {
        return MC_PIL_ERR_ARG;
    }
    const int t = mc_pil_frame_type(buf, n);
    if (t < 0) {
        return t;
    }
    if (t != (int)MC_PIL_TYPE_FLASH) {
        return MC_PIL_ERR_TYPE;
    }
    const uint32_t len = (uint32_t)buf[2];
    if (len < 8u || (len % 4u) != 0u || len - 4u > MC_PIL_FLASH_CHUNK) {
        return MC_PIL_ERR_LEN;
    }
    const int rc = open_frame(&r, buf, n, MC_PIL_TYPE_FLASH, len / 4u);
    if (rc != MC_PIL_OK) {
        return rc;
    }
    *p_offset = get_u32(&r);
    *p_data = &buf[r.pos];
    *p_n = len - 4u;
    return MC_PIL_OK;
}

/* ---- APP --------------------------------------------------------------- */

size_t mc_pil_encode_app(const mc_pil_app_t *a, uint8_t *buf, size_t cap)
{
    writer_t w;
    if (a == NULL || !begin(&w, buf, cap, MC_PIL_TYPE_APP, APP_WORDS)) {
        return 0u;
    }
    put_f32(&w, a->tm_budget_frac);
    for (uint32_t i = 0u; i < MC_PIL_TM_EXT_RATES; ++i) {
        put_u32(&w, a->tm_ext_rate_hz[i]);
    }
    put_u32(&w, a->pwm_hz_fixed);
    put_u32(&w, a->slow_loop_div_fixed);
    put_u32(&w, a->tick_hz);
    put_u32(&w, a->caps);
    return finish(&w);
}

int mc_pil_decode_app(const uint8_t *buf, size_t n, mc_pil_app_t *out)
{
    reader_t r;
    if (out == NULL) {
        return MC_PIL_ERR_ARG;
    }
    const int rc = open_frame(&r, buf, n, MC_PIL_TYPE_APP, APP_WORDS);
    if (rc != MC_PIL_OK) {
        return rc;
    }
    mc_pil_app_t a;
    a.tm_budget_frac = get_f32(&r);
    for (uint32_t i = 0u; i < MC_PIL_TM_EXT_RATES; ++i) {
        a.tm_ext_rate_hz[i] = get_u32(&r);
    }
    a.pwm_hz_fixed = get_u32(&r);
    a.slow_loop_div_fixed = get_u32(&r);
    a.tick_hz = get_u32(&r);
    a.caps = get_u32(&r);
    *out = a;
    return MC_PIL_OK;
}

/* ---- CAN_RX / CAN_TX ----------------------------------------------------- */

static uint32_t can_data_words(uint8_t len)
{
    return ((uint32_t)len + 3u) / 4u;
}

static void put_can(writer_t *w, const mc_hal_can_frame_t *f)
{
    put_u32(w, f->id);
    put_u32(w, f->timestamp_ticks);
    put_u32(w, (uint32_t)f->len | ((uint32_t)f->flags << 8));
    for (uint32_t k = 0u; k < can_data_words(f->len); ++k) {
        uint32_t v = 0u;
        for (uint32_t b = 0u; b < 4u; ++b) {
            const uint32_t at = 4u * k + b;
            if (at < (uint32_t)f->len) {
                v |= (uint32_t)f->data[at] << (8u * b);
            }
        }
        put_u32(w, v);
    }
}

/* The frame's data length from the payload size and the length word; false
 * if they disagree or the length is not a CAN (FD) length. */
static bool get_can(reader_t *r, size_t payload_bytes, mc_hal_can_frame_t *f)
{
    mc_hal_can_frame_t c;
    memset(&c, 0, sizeof c);
    c.id = get_u32(r);
    c.timestamp_ticks = get_u32(r);
    const uint32_t lf = get_u32(r);
    const uint32_t len = lf & 0xFFu;
    if (len > MC_HAL_CAN_FD_MAX_LEN || !mc_hal_can_fd_len_valid((uint8_t)len) ||
        payload_bytes != 4u * ((size_t)CAN_HEAD_WORDS + can_data_words((uint8_t)len))) {
        return false;
    }
    c.len = (uint8_t)len;
    c.flags = (uint8_t)((lf >> 8) & 0xFFu);
    for (uint32_t k = 0u; k < can_data_words(c.len); ++k) {
        const uint32_t v = get_u32(r);
        for (uint32_t b = 0u; b < 4u; ++b) {
            const uint32_t at = 4u * k + b;
            if (at < len) {
                c.data[at] = (uint8_t)((v >> (8u * b)) & 0xFFu);
            }
        }
    }
    *f = c;
    return true;
}

/* Open a CAN frame of either type: check CRC and type; the payload size is
 * checked by get_can. */
static int open_can(reader_t *r, const uint8_t *buf, size_t n, mc_pil_type_t type)
{
    const int t = mc_pil_frame_type(buf, n);
    if (t < 0) {
        return t;
    }
    if (t != (int)type) {
        return MC_PIL_ERR_TYPE;
    }
    r->buf = buf;
    r->pos = MC_PIL_HEADER_LEN;
    return MC_PIL_OK;
}

size_t mc_pil_encode_can_rx(const mc_hal_can_frame_t *f, uint8_t *buf, size_t cap)
{
    writer_t w;
    if (f == NULL || f->len > MC_HAL_CAN_FD_MAX_LEN ||
        !begin(&w, buf, cap, MC_PIL_TYPE_CAN_RX, CAN_HEAD_WORDS + can_data_words(f->len))) {
        return 0u;
    }
    put_can(&w, f);
    return finish(&w);
}

int mc_pil_decode_can_rx(const uint8_t *buf, size_t n, mc_hal_can_frame_t *out)
{
    reader_t r;
    if (out == NULL) {
        return MC_PIL_ERR_ARG;
    }
    const int rc = open_can(&r, buf, n, MC_PIL_TYPE_CAN_RX);
    if (rc != MC_PIL_OK) {
        return rc;
    }
    if ((size_t)buf[2] < (size_t)4u * CAN_HEAD_WORDS || !get_can(&r, (size_t)buf[2], out)) {
        return MC_PIL_ERR_LEN;
    }
    return MC_PIL_OK;
}

size_t mc_pil_encode_can_tx(uint32_t seq, const mc_hal_can_frame_t *f, uint8_t *buf, size_t cap)
{
    writer_t w;
    if (f == NULL || f->len > MC_HAL_CAN_FD_MAX_LEN ||
        !begin(&w, buf, cap, MC_PIL_TYPE_CAN_TX, 1u + CAN_HEAD_WORDS + can_data_words(f->len))) {
        return 0u;
    }
    put_u32(&w, seq);
    put_can(&w, f);
    return finish(&w);
}

int mc_pil_decode_can_tx(const uint8_t *buf, size_t n, uint32_t *p_seq, mc_hal_can_frame_t *out)
{
    reader_t r;
    if (out == NULL || p_seq == NULL) {
        return MC_PIL_ERR_ARG;
    }
    const int rc = open_can(&r, buf, n, MC_PIL_TYPE_CAN_TX);
    if (rc != MC_PIL_OK) {
        return rc;
    }
    if ((size_t)buf[2] < (size_t)4u * (1u + CAN_HEAD_WORDS)) {
        return MC_PIL_ERR_LEN;
    }
    const uint32_t seq = get_u32(&r);
    if (!get_can(&r, (size_t)buf[2] - 4u, out)) {
        return MC_PIL_ERR_LEN;
    }
    *p_seq = seq;
    return MC_PIL_OK;
}
