/**
 * @file mc_commission.c
 * @brief Commissioning sequence (see mc_commission.h and README.md).
 */
#include "commission/mc_commission.h"

#include <stddef.h>

#include "math/mc_math.h"
#include "transforms/mc_svpwm.h"
#include "transforms/mc_transforms.h"

/* Durations [s] of the phases (README.md: why these). */
#define T_OFF_SETTLE     0.01f
#define T_OFF_AVG        0.10f
#define SQ_SKIP          32u  /* periods of each square-wave try before correlating */
#define SQ_LEN           128u /* periods of each try */
#define T_ALIGN_RAMP     0.10f
#define T_ALIGN_HOLD     0.15f
#define T_PRE_RAMP       0.10f
#define T_PRE_CONST      0.10f
#define T_SWP_RAMP       0.25f
#define T_SWP_CONST      0.75f
#define T_HOLD           0.10f
#define T_R_SETTLE       0.10f
#define T_R_AVG          0.10f
#define T_L_SETTLE       0.03f
#define T_L_AVG          0.10f
#define T_SPIN_MAX       2.00f
#define T_SPIN_BLOCK     0.30f
#define T_COAST_SKIP     0.02f
#define T_COAST          0.25f
#define T_COAST_QUIET    0.01f /* the coast's current below I_COAST_GATE this long: fit */
#define T_COAST_SKIP_MAX 0.20f
#define I_COAST_GATE     0.03f /* of i_test (about 7 sigma of the library's sensor noise) */
#define V_SPIN_FRAC      0.8f  /* spin-up ends at this fraction of the voltage limit */
/* The voltage checks of the spin-up wait this long: the current loop moves
 * the inductance step's current (along d) to the spin's (along q) first; on
 * an angle up to 30 degrees el. off (Hall sensors at rest, mc_drive_hall.h)
 * that step took 0.8 of the voltage (and half of it along q) in the first
 * sample. */
#define T_SPIN_SETTLE 0.005f
#define W_E_BW_MAX    1.5f /* ... or at this electrical speed per current-loop bandwidth */

/* Sub-phases of the encoder step. */
enum {
    ENC_ALIGN_RAMP = 0,
    ENC_ALIGN_HOLD,
    ENC_PRE,
    ENC_PRE_HOLD,
    ENC_FWD1,
    ENC_FWD1_HOLD,
    ENC_BACK,
    ENC_BACK_HOLD,
    ENC_FWD2,
    ENC_FWD2_HOLD,
    /* the Hall table, before the sweeps above (cfg.hall) */
    ENC_HALL_RAMP,
    ENC_HALL_HOLD,
    ENC_HALL_UP,
    ENC_HALL_UP_HOLD,
    ENC_HALL_DOWN,
    ENC_HALL_DOWN_HOLD
};

/* The Hall sweep: a turn and two sectors each way (every edge seen at the
 * constant speed once the ramp, 0.6 rad, is over), at 0.9 turn per second
 * (the encoder step's sweeps: one), 5.6 rad/s el.: the rotor follows the
 * vector at a constant lag (the same both ways, so it cancels in each
 * edge), and the drive's Hall angle stays below its interpolation speed
 * (hall_omega_min_e_rad_s, default 50). */
#define HALL_SWEEP_RAD (MC_TWO_PI_F32 * (4.0f / 3.0f))
#define T_HALL_RAMP    MC_COMM_HALL_T_RAMP_S
#define T_HALL_CONST   MC_COMM_HALL_T_CONST_S
#define HALL_NONE      8u

static uint32_t steps_of(const mc_comm_t *c, float t_s)
{
    return (uint32_t)(t_s / c->cfg.dt_s + 0.5f);
}

/* A phase's first period sees n = 0: the fast step increments n after the
 * phase function, so entering sets it one below (wrapping). */
#define N_FIRST UINT32_MAX

static void enter(mc_comm_t *c, mc_comm_step_t step, uint32_t sub)
{
    c->step = step;
    c->sub = sub;
    c->n = N_FIRST;
}

static void next_sub(mc_comm_t *c)
{
    c->sub++;
    c->n = N_FIRST;
}

uint32_t mc_comm_init(mc_comm_t *c, const mc_comm_cfg_t *cfg)
{
    if (c == NULL || cfg == NULL) {
        return MC_COMM_CFG_ERR_NULL;
    }
    const float pos[6] = {cfg->dt_s,         cfg->i_test_a,     cfg->v_test_max_v,
                          cfg->offset_max_a, cfg->cur_bw_rad_s, cfg->speed_max_m_rad_s};
    for (unsigned k = 0u; k < 6u; ++k) {
        if (!mc_isfinite_f32(pos[k]) || !(pos[k] > 0.0f)) {
            return MC_COMM_CFG_ERR_VALUE;
        }
    }
    if (!mc_isfinite_f32(cfg->dead_time_s) || cfg->dead_time_s < 0.0f ||
        cfg->dead_time_s >= 0.25f * cfg->dt_s || !(cfg->bemf_frac > 0.0f) ||
        !(cfg->bemf_frac < 1.0f) || cfg->cur_bw_rad_s * cfg->dt_s > 0.2f ||
        cfg->pole_pairs_max < 1u || cfg->pole_pairs_max > 64u ||
        !mc_isfinite_f32(cfg->speed_tau_s) || cfg->speed_tau_s < 0.0f || cfg->speed_tau_s > 0.1f ||
        cfg->pole_pairs_given > cfg->pole_pairs_max ||
        (cfg->pole_pairs_given != 0u && cfg->hall != NULL)) {
        return MC_COMM_CFG_ERR_VALUE;
    }
    *c = (mc_comm_t){0};
    c->cfg = *cfg;
    c->step = MC_COMM_STEP_IDLE;
    return MC_COMM_CFG_OK;
}

void mc_comm_restart(mc_comm_t *c)
{
    const mc_comm_cfg_t cfg = c->cfg;
    const mc_drive_ctrl_t ops = c->ops;
    *c = (mc_comm_t){0};
    c->cfg = cfg;
    c->ops = ops;
    c->step = MC_COMM_STEP_IDLE;
}

void mc_comm_abort(mc_comm_t *c)
{
    c->err |= MC_COMM_ERR_ABORTED;
}

/* Current loop of the tests: kp = L bw; ki = R bw (from_r) or kp bw / zdiv.
 * Without R, a PI zero at bw / zdiv keeps the loop stable for any R >= 0
 * (a pure inductance: phase margin 76 deg at zdiv = 4). zdiv = 40 while
 * the rotor is positioned: below its swing frequency the loop then acts as
 * the resistance kp, and the back-EMF of a swinging rotor drives a current
 * that damps it (1.5 p^2 psi^2 / (R + kp)); a stiff current loop leaves an
 * undamped rotor (a 0.1 kg m^2 machine rings for seconds). */
#define ZDIV_STIFF 4.0f
#define ZDIV_DAMP  40.0f
static uint32_t foc_setup(mc_comm_t *c, float r_ohm, float ld_h, float lq_h, bool from_r,
                          float zdiv)
{
    const float bw = c->cfg.cur_bw_rad_s;
    mc_foc_f32_cfg_t fc = {0};
    fc.r_ohm = r_ohm;
    fc.ld_h = ld_h;
    fc.lq_h = lq_h;
    fc.flux_wb = 0.0f;
    fc.kp_d_v_per_a = ld_h * bw;
    fc.kp_q_v_per_a = lq_h * bw;
    fc.ki_d_v_per_as = from_r ? r_ohm * bw : fc.kp_d_v_per_a * bw / zdiv;
    fc.ki_q_v_per_as = from_r ? r_ohm * bw : fc.kp_q_v_per_a * bw / zdiv;
    fc.dt_s = c->cfg.dt_s;
    fc.aw = MC_PI_AW_CLAMP;
    fc.limit_mode = MC_SVPWM_LIMIT_CIRCLE;
    fc.v_limit_ratio = 0.95f;
    fc.v_abs_max_v = c->cfg.v_test_max_v;
    fc.decouple = false;
    return mc_foc_f32_init(&c->foc, &fc) != 0u ? MC_COMM_ERR_RANGE : 0u;
}

static uint32_t reset_cb(void *ctx)
{
    mc_comm_t *c = (mc_comm_t *)ctx;
    mc_comm_restart(c);
    enter(c, MC_COMM_STEP_OFFSETS, 0u);
    c->n = 0u;
    for (unsigned k = 0u; k < 3u; ++k) {
        mc_ident_avg_f32_reset(&c->corr[k]);
    }
    return 0u;
}

/* Zero voltage: equal duties. */
static void zero_out(mc_drive_out_t *out)
{
    out->duty_a = 0.5f;
    out->duty_b = 0.5f;
    out->duty_c = 0.5f;
}

/* Voltage vector (alpha, beta) to duties, limited to v_test_max and the
 * modulator; returns true if it had to be limited. */
static bool volts_out(const mc_comm_t *c, float va, float vb, float vbus, mc_drive_out_t *out)
{
    bool limited = false;
    const float m2 = va * va + vb * vb;
    const float vmax = c->cfg.v_test_max_v;
    if (m2 > vmax * vmax) {
        const float s = vmax / mc_sqrt_f32(m2);
        va *= s;
        vb *= s;
        limited = true;
    }
    const uint32_t f = mc_svpwm_limit_duty_f32(&va, &vb, vbus, MC_SVPWM_LIMIT_CIRCLE, &out->duty_a,
                                               &out->duty_b, &out->duty_c);
    return limited || ((f & MC_SVPWM_FLAG_LIMITED) != 0u);
}

/* Encoder count tracking: unwrapped signed counts, and a speed estimate
 * (counts per period through a first-order low-pass of 2 ms: its lag under
 * the coast-down's deceleration a is a * 2 ms, negligible against the
 * speed). The drive's own speed is not used: its sign depends on the
 * direction it was configured with. */
#define TAU_SPEED_S 0.002f
static void track_count(mc_comm_t *c, const mc_drive_meas_t *m)
{
    const uint32_t cpr = m->enc_cpr;
    const uint32_t cnt = m->enc_raw_count % cpr;
    if (c->have_count) {
        int32_t d = (int32_t)cnt - (int32_t)c->last_count;
        if (d > (int32_t)(cpr / 2u)) {
            d -= (int32_t)cpr;
        } else if (d < -(int32_t)(cpr / 2u)) {
            d += (int32_t)cpr;
        }
        const float w = (float)d * (MC_TWO_PI_F32 / (float)cpr) / c->cfg.dt_s;
        const float tau = (c->cfg.speed_tau_s > 0.0f) ? c->cfg.speed_tau_s : TAU_SPEED_S;
        const float k = c->cfg.dt_s / tau;
        c->w_m_rad_s += (w - c->w_m_rad_s) * ((k < 1.0f) ? k : 1.0f);
        c->count_acc += d;
    }
    c->last_count = cnt;
    c->have_count = true;
}

/* Electrical angle from the raw count with the identified pole pairs,
 * direction and offset, computed as the drive does (mc_drive.c). */
static float enc_theta_e(const mc_comm_t *c, const mc_drive_meas_t *m, float offset_rad)
{
    const uint32_t cpr = m->enc_cpr;
    const uint32_t raw = m->enc_raw_count % cpr;
    const uint32_t cnt = (c->res.encoder_direction < 0 && raw != 0u) ? cpr - raw : raw;
    const uint32_t e = (uint32_t)(((uint64_t)cnt * (uint64_t)c->res.pole_pairs) % (uint64_t)cpr);
    return mc_wrap_2pi_f32((float)e * (MC_TWO_PI_F32 / (float)cpr) + offset_rad);
}

/* Speed of a move: ramps of (1 - cos) shape, a constant part between.
 * Returns the velocity [rad/s] at period k; *p_const: in the constant part;
 * *p_end: the move is over. */
static float move_velocity(const mc_comm_t *c, float dist_rad, float t_ramp_s, float t_const_s,
                           uint32_t k, bool *p_const, bool *p_end)
{
    const float t = (float)k * c->cfg.dt_s;
    const float w = dist_rad / (t_ramp_s + t_const_s);
    *p_const = false;
    *p_end = false;
    if (t < t_ramp_s) {
        float s;
        float co;
        mc_sincos_f32(MC_PI_F32 * t / t_ramp_s, &s, &co);
        return w * 0.5f * (1.0f - co);
    }
    if (t < t_ramp_s + t_const_s) {
        *p_const = true;
        return w;
    }
    if (t < 2.0f * t_ramp_s + t_const_s) {
        float s;
        float co;
        mc_sincos_f32(MC_PI_F32 * (t - t_ramp_s - t_const_s) / t_ramp_s, &s, &co);
        return w * 0.5f * (1.0f + co);
    }
    *p_end = true;
    return 0.0f;
}

/* One FOC step at the given angle and references; duties to out. */
static uint32_t foc_out(mc_comm_t *c, const float i[3], float theta, float omega_e, float id_ref,
                        float iq_ref, mc_drive_out_t *out, mc_foc_f32_out_t *fo)
{
    const mc_foc_f32_in_t in = {
        .ia_a = i[0],
        .ib_a = i[1],
        .ic_a = i[2],
        .three_phase = c->cfg.three_shunts,
        .theta_e_rad = theta,
        .omega_e_rad_s = omega_e,
        .vbus_v = c->vbus_v,
        .id_ref_a = id_ref,
        .iq_ref_a = iq_ref,
    };
    if (mc_foc_f32_step(&c->foc, &in, fo) != MC_FOC_ERR_NONE) {
        return MC_COMM_ERR_RANGE;
    }
    out->duty_a = fo->duty_a;
    out->duty_b = fo->duty_b;
    out->duty_c = fo->duty_c;
    return 0u;
}

/* ------------------------------------------------------------ offsets */
static uint32_t step_offsets(mc_comm_t *c, const float raw[3], mc_drive_out_t *out)
{
    zero_out(out);
    if (c->n == steps_of(c, T_OFF_SETTLE)) {
        for (unsigned k = 0u; k < 3u; ++k) {
            mc_ident_avg_f32_reset(&c->corr[k]);
        }
    }
    if (c->n >= steps_of(c, T_OFF_SETTLE)) {
        for (unsigned k = 0u; k < 3u; ++k) {
            (void)mc_ident_avg_f32_step(&c->corr[k], raw[k]);
        }
    }
    if (c->n >= steps_of(c, T_OFF_SETTLE + T_OFF_AVG)) {
        for (unsigned k = 0u; k < 3u; ++k) {
            (void)mc_ident_avg_f32_get(&c->corr[k], &c->res.adc_offset_a[k]);
            if (!(mc_abs_f32(c->res.adc_offset_a[k]) <= c->cfg.offset_max_a)) {
                return MC_COMM_ERR_OFFSET;
            }
        }
        if (!c->cfg.three_shunts) {
            c->res.adc_offset_a[2] = 0.0f;
        }
        c->res.valid |= MC_COMM_HAVE_OFFSETS;
        enter(c, MC_COMM_STEP_L_ROUGH, 0u);
        c->vh_v = 8.0f * c->vbus_v * c->cfg.dead_time_s / c->cfg.dt_s;
        if (c->vh_v < 0.004f * c->vbus_v) {
            c->vh_v = 0.004f * c->vbus_v;
        }
    }
    return 0u;
}

/* ---------------------------------------------- square-wave ripple (L) */
/* Correlate the per-period current change with the alternating sign: the
 * mean |di| per period is the peak-to-peak ripple, whatever the delay. */
static void sq_correlate(mc_comm_t *c, const float i[3], uint32_t skip)
{
    if (c->n > skip) {
        for (unsigned k = 0u; k < 3u; ++k) {
            (void)mc_ident_avg_f32_step(&c->corr[k], c->sq_sign * (i[k] - c->prev_i[k]));
        }
    }
    for (unsigned k = 0u; k < 3u; ++k) {
        c->prev_i[k] = i[k];
    }
}

static void sq_reset(mc_comm_t *c)
{
    for (unsigned k = 0u; k < 3u; ++k) {
        mc_ident_avg_f32_reset(&c->corr[k]);
    }
}

/* Ripple of the try along an axis (ua, ub unit vector): |corr| projected. */
static float sq_ripple(const mc_comm_t *c, float ua, float ub, float d_phase[3])
{
    float m[3];
    for (unsigned k = 0u; k < 3u; ++k) {
        (void)mc_ident_avg_f32_get(&c->corr[k], &m[k]);
        d_phase[k] = mc_abs_f32(m[k]);
    }
    float a;
    float b;
    mc_clarke_f32(m[0], m[1], &a, &b);
    return mc_abs_f32(a * ua + b * ub);
}

/* Connection check after both tries. A try that moves no current along its
 * own axis: nothing conducts (both) or one phase is open (one; an open
 * phase a leaves alpha without a path, b or c leave beta weak).
 *
 * Per phase, the ripple is judged over BOTH tries, not the alpha try alone.
 * The per-volt ripple of phase k in try j is |e_k' G u_j|, with G = L^-1 of
 * the stationary frame, L(theta) = (Ld+Lq)/2 I + (Ld-Lq)/2 R(2 theta)
 * (R the reflection [cos, sin; sin, -cos]), e_k phase k's direction.
 * With Ld = Lq, G is a multiple of I and the alpha try alone sends |d| to a
 * and |d|/2 to b and c; with saliency the alpha try's current leans off
 * alpha by up to asin((Lq-Ld)/(Lq+Ld)) toward the d axis, and at some rotor
 * angles b or c carries under 0.2 of a's ripple although it is connected
 * (Lq/Ld = 2, theta_e = 1 rad: 0.195): the old alpha-only test reported
 * OPEN_PHASE on a healthy IPM (issue 31). The root-sum-square over the two
 * tries is |G e_k|, between |e_k|/max(Ld, Lq) and |e_k|/min(Ld, Lq) at any
 * angle, so a connected phase keeps at least min/max(Ld, Lq) of the largest
 * (0.5 at Lq/Ld = 2): the 0.2 bound holds for saliency up to 5, an open
 * phase carries none in either try (noise only). */
static uint32_t connection_check(const mc_comm_t *c)
{
    const float thr = 0.02f * c->cfg.i_test_a;
    const bool a_ok = c->d_axis[0] >= thr;
    const bool b_ok = c->d_axis[1] >= thr;
    if (!a_ok && !b_ok) {
        return MC_COMM_ERR_NO_MOTOR;
    }
    if (!a_ok || !b_ok) {
        return MC_COMM_ERR_OPEN_PHASE;
    }
    float g[3];
    float big = 0.0f;
    for (unsigned k = 0u; k < 3u; ++k) {
        const float pa = c->d_phase[0][k];
        const float pb = c->d_phase[1][k];
        g[k] = mc_sqrt_f32(pa * pa + pb * pb);
        big = (g[k] > big) ? g[k] : big;
    }
    for (unsigned k = 0u; k < 3u; ++k) {
        if (!(g[k] >= 0.2f * big)) {
            return MC_COMM_ERR_OPEN_PHASE;
        }
    }
    return 0u;
}

static uint32_t step_l_rough(mc_comm_t *c, const float i[3], mc_drive_out_t *out)
{
    const unsigned ax = c->sub; /* 0: alpha, 1: beta */
    const float ua = (ax == 0u) ? 1.0f : 0.0f;
    const float ub = (ax == 0u) ? 0.0f : 1.0f;
    if (c->n == 0u) {
        sq_reset(c);
        c->sq_sign = 1.0f;
    }
    sq_correlate(c, i, SQ_SKIP);
    if (c->n >= SQ_LEN) {
        float dph[3];
        const float d = sq_ripple(c, ua, ub, dph);
        const bool at_max = c->vh_v >= 0.999f * c->cfg.v_test_max_v;
        if (d < 0.1f * c->cfg.i_test_a && !at_max) {
            c->vh_v *= 2.0f;
            if (c->vh_v > c->cfg.v_test_max_v) {
                c->vh_v = c->cfg.v_test_max_v;
            }
            c->n = N_FIRST;
            zero_out(out);
            return 0u;
        }
        c->d_axis[ax] = d;
        for (unsigned k = 0u; k < 3u; ++k) {
            c->d_phase[ax][k] = dph[k] / c->vh_v; /* per volt: the tries' amplitudes differ */
        }
        if (d >= 0.02f * c->cfg.i_test_a) {
            float l = 0.0f;
            (void)mc_ident_l_square_wave_f32(c->vh_v, c->cfg.dt_s, d, 0.0f, &l);
            c->l0_h = (ax == 0u || c->l0_h == 0.0f) ? l : 0.5f * (c->l0_h + l);
        }
        if (ax == 0u) {
            next_sub(c);
            c->vh_v = 8.0f * c->vbus_v * c->cfg.dead_time_s / c->cfg.dt_s;
            if (c->vh_v < 0.004f * c->vbus_v) {
                c->vh_v = 0.004f * c->vbus_v;
            }
            zero_out(out);
            return 0u;
        }
        const uint32_t conn = connection_check(c);
        if (conn != 0u) {
            return conn;
        }
        if (!(c->l0_h > 0.0f)) {
            return MC_COMM_ERR_RANGE;
        }
        enter(c, MC_COMM_STEP_ENCODER, (c->cfg.hall != NULL) ? ENC_HALL_RAMP : ENC_ALIGN_RAMP);
        c->hall_code = HALL_NONE;
        c->have_count = false;
        c->enc_coarse = false;
        c->count_acc = 0;
        mc_ident_avg_f32_reset(&c->v_acc);
        zero_out(out);
        return foc_setup(c, 0.0f, c->l0_h, c->l0_h, false, ZDIV_DAMP);
    }
    /* First period at half amplitude: the ripple starts centred on 0. */
    const float v = c->sq_sign * c->vh_v * ((c->n == 0u) ? 0.5f : 1.0f);
    (void)volts_out(c, v * ua, v * ub, c->vbus_v, out);
    c->sq_sign = -c->sq_sign;
    return 0u;
}

/* ------------------------------------------------- encoder and poles */
/* Damping of the positioned rotor. With the soft PI zero the loop acts, at
 * the rotor's swing frequency, as the resistance kp in series with the
 * winding: the back-EMF of the swing drives a damping torque
 * 1.5 p^2 psi^2 / (R + kp) per rad/s. kp = L0 bw can be many times R (a
 * high-L/R winding at a low PWM rate: L bw / R = 0.08 tau / T), and a
 * low-flux, many-pole rotor then swings for seconds, which corrupts the
 * pole-pair count. The voltage that holds i_test (mean vd over the align
 * hold) bounds R from above (dead time and switch drops add to it):
 * kp = min(L0 bw, vd / i_test) keeps the series resistance within about
 * twice the winding's, the PI zero (bw / ZDIV_DAMP) where it was. Bumpless
 * (mc_pi_f32_set_gains keeps the output). */
static void damp_loop(mc_comm_t *c)
{
    float vd = 0.0f;
    if (mc_ident_avg_f32_get(&c->v_acc, &vd) != 0u) {
        return;
    }
    mc_ident_avg_f32_reset(&c->v_acc);
    const float kp_full = c->l0_h * c->cfg.cur_bw_rad_s;
    const float r_up = vd / c->cfg.i_test_a;
    if (!(r_up > 0.0f) || !(r_up < kp_full)) {
        return;
    }
    const float ki = r_up * c->cfg.cur_bw_rad_s / ZDIV_DAMP;
    (void)mc_pi_f32_set_gains(&c->foc.pi_d, r_up, ki);
    (void)mc_pi_f32_set_gains(&c->foc.pi_q, r_up, ki);
}

/* The Hall table (mc_comm_hall.h): the vector (i_test, the damped loop of
 * the encoder step) aligned at 0, swept a turn and two sectors up at a
 * constant speed, then back; every code change at the constant speed is
 * recorded with the vector's angle, every code read counts (000, 111). */
static uint32_t hall_table_done(mc_comm_t *c)
{
    const uint32_t e = mc_comm_hall_table_f32(&c->hall_rec, &c->res.hall);
    if ((e & MC_COMM_HALL_ERR_CODES) != 0u) {
        return MC_COMM_ERR_HALL_CODES;
    }
    if ((e & MC_COMM_HALL_ERR_ORDER) != 0u) {
        return MC_COMM_ERR_HALL_ORDER;
    }
    if ((e & MC_COMM_HALL_ERR_WIDTH) != 0u) {
        return MC_COMM_ERR_RANGE;
    }
    if (e != 0u) {
        return MC_COMM_ERR_ROTOR_BLOCKED;
    }
    c->res.have_hall = true;
    enter(c, MC_COMM_STEP_ENCODER, ENC_ALIGN_RAMP);
    return 0u;
}

static uint32_t step_hall(mc_comm_t *c, const float i[3], mc_drive_out_t *out)
{
    uint32_t code = 0u;
    if (mc_hal_hall_read(c->cfg.hall, &code) != 0 || code > 7u) {
        return MC_COMM_ERR_MEAS;
    }
    c->hall_rec.seen_mask |= 1u << code;
    bool in_const = false;
    bool end = false;
    float w = 0.0f;
    switch (c->sub) {
    case ENC_HALL_RAMP:
        c->theta_cmd_rad = 0.0f;
        c->i_cmd_a = c->cfg.i_test_a * (float)c->n / (float)steps_of(c, T_ALIGN_RAMP);
        if (c->n >= steps_of(c, T_ALIGN_RAMP)) {
            c->i_cmd_a = c->cfg.i_test_a;
            next_sub(c);
        }
        break;
    case ENC_HALL_HOLD:
    case ENC_HALL_UP_HOLD:
    case ENC_HALL_DOWN_HOLD:
        if (c->n >= steps_of(c, T_HOLD)) {
            if (c->sub == ENC_HALL_HOLD) {
                damp_loop(c);
            } else if (c->sub == ENC_HALL_UP_HOLD && c->hall_rec.n_up == 0u) {
                return MC_COMM_ERR_ROTOR_BLOCKED; /* no change over the turn */
            } else if (c->sub == ENC_HALL_DOWN_HOLD) {
                c->hall_code = code;
                return hall_table_done(c);
            }
            next_sub(c);
        }
        break;
    case ENC_HALL_UP:
        w = move_velocity(c, HALL_SWEEP_RAD, T_HALL_RAMP, T_HALL_CONST, c->n, &in_const, &end);
        break;
    case ENC_HALL_DOWN:
        w = move_velocity(c, -HALL_SWEEP_RAD, T_HALL_RAMP, T_HALL_CONST, c->n, &in_const, &end);
        break;
    default:
        break;
    }
    if (in_const && c->hall_code != HALL_NONE && code != c->hall_code) {
        mc_comm_hall_record(&c->hall_rec, (w > 0.0f) ? 1 : -1, c->hall_code, code,
                            c->theta_cmd_rad);
    }
    c->hall_code = code;
    c->theta_cmd_rad = mc_wrap_2pi_f32(c->theta_cmd_rad + w * c->cfg.dt_s);
    mc_foc_f32_out_t fo;
    const uint32_t e = foc_out(c, i, c->theta_cmd_rad, 0.0f, c->i_cmd_a, 0.0f, out, &fo);
    if (c->sub == ENC_HALL_HOLD) {
        (void)mc_ident_avg_f32_step(&c->v_acc, fo.vd_v);
    }
    if (end) {
        next_sub(c);
    }
    return e;
}

/* The rotor aligned (the d axis where the vector stands): the resistance
 * and inductance steps run along it. */
static uint32_t to_resistance(mc_comm_t *c)
{
    c->theta0_rad = c->theta_cmd_rad;
    enter(c, MC_COMM_STEP_RESISTANCE, 0u);
    mc_ident_avg_f32_reset(&c->v_acc);
    mc_ident_avg_f32_reset(&c->i_acc);
    return foc_setup(c, 0.0f, c->l0_h, c->l0_h, false, ZDIV_STIFF);
}

static uint32_t step_encoder(mc_comm_t *c, const float i[3], const mc_drive_meas_t *m,
                             mc_drive_out_t *out)
{
    /* Without an encoder (cfg.pole_pairs_given) the alignment alone: the
     * hold at -pi/2, the quarter turn to 0 and its hold; the rotor's d axis
     * is then the commanded angle (the resistance and inductance steps run
     * on the commanded angle either way). */
    const bool sls = c->cfg.pole_pairs_given != 0u;
    if (!sls) {
        track_count(c, m);
    }
    if (c->sub >= ENC_HALL_RAMP) {
        return step_hall(c, i, out);
    }
    const float dt = c->cfg.dt_s;
    bool in_const = false;
    bool end = false;
    float w = 0.0f;
    const float it = c->cfg.i_test_a;
    switch (c->sub) {
    case ENC_ALIGN_RAMP:
        /* Align at -pi/2: the quarter turn forward ends at 0, and every
         * sweep there, so the resistance and inductance steps run along
         * phase a (all three phase currents away from zero). */
        c->theta_cmd_rad = 1.5f * MC_PI_F32;
        c->i_cmd_a = it * (float)c->n / (float)steps_of(c, T_ALIGN_RAMP);
        if (c->n >= steps_of(c, T_ALIGN_RAMP)) {
            c->i_cmd_a = it;
            next_sub(c);
        }
        break;
    case ENC_ALIGN_HOLD:
        if (c->n >= steps_of(c, T_HOLD)) {
            damp_loop(c);
            next_sub(c);
        }
        break;
    case ENC_PRE_HOLD:
    case ENC_FWD1_HOLD:
    case ENC_BACK_HOLD:
    case ENC_FWD2_HOLD:
        if (c->n >= steps_of(c, T_HOLD)) {
            const uint32_t s = c->sub;
            if (s == ENC_PRE_HOLD && sls) {
                c->res.pole_pairs = c->cfg.pole_pairs_given;
                if (to_resistance(c) != 0u) {
                    return MC_COMM_ERR_RANGE;
                }
                break;
            }
            if (s == ENC_PRE_HOLD) {
                c->count_acc = 0;
                mc_ident_avg_f32_reset(&c->vq_acc);
            } else if (s == ENC_FWD1_HOLD) {
                c->count_fwd = c->count_acc;
                const int32_t cpr = (int32_t)m->enc_cpr;
                const int32_t a = (c->count_fwd < 0) ? -c->count_fwd : c->count_fwd;
                if (a < cpr / (4 * (int32_t)c->cfg.pole_pairs_max) || a < 4) {
                    /* No motion: did the rotor turn? Its back-EMF shows in the
                     * voltage ahead of the current (the winding's own part
                     * is omega L i). */
                    float vq = 0.0f;
                    (void)mc_ident_avg_f32_get(&c->vq_acc, &vq);
                    const float w_s = MC_TWO_PI_F32 / (T_SWP_RAMP + T_SWP_CONST);
                    const float psi_app = vq / w_s - c->l0_h * it;
                    return (psi_app > 0.5f * c->l0_h * it) ? MC_COMM_ERR_ENCODER_NO_MOTION
                                                           : MC_COMM_ERR_ROTOR_BLOCKED;
                }
                const float p_est = (float)cpr / (float)a;
                const uint32_t p = (uint32_t)(p_est + 0.5f);
                if (p < 1u || p > c->cfg.pole_pairs_max ||
                    mc_abs_f32(p_est - (float)p) > 0.05f * (float)p) {
                    return MC_COMM_ERR_ENCODER_BAD;
                }
                c->res.pole_pairs = p;
                c->enc_coarse = (uint32_t)cpr < MC_COMM_COUNTS_PER_E_TURN_MIN * p;
                c->res.encoder_direction = (c->count_fwd > 0) ? 1 : -1;
                c->count_acc = 0;
                mc_ident_circ_f32_reset(&c->off_acc);
            } else if (s == ENC_BACK_HOLD) {
                c->count_back = c->count_acc;
                c->count_acc = 0;
            } else if (s == ENC_FWD2_HOLD) {
                const int32_t f = c->count_fwd;
                const int32_t sum1 = c->count_back + f;
                const int32_t sum2 = c->count_acc - f;
                const int32_t tol = ((f < 0) ? -f : f) / 10 + 2;
                if (sum1 > tol || sum1 < -tol || sum2 > tol || sum2 < -tol) {
                    return MC_COMM_ERR_ENCODER_BAD;
                }
                float off = 0.0f;
                float rr = 0.0f;
                if (mc_ident_circ_f32_get(&c->off_acc, &off, &rr) != 0u || rr < 0.9f) {
                    return MC_COMM_ERR_ENCODER_BAD;
                }
                c->res.encoder_offset_rad = mc_wrap_2pi_f32(off);
                c->res.valid |= MC_COMM_HAVE_ENCODER;
                if (to_resistance(c) != 0u) {
                    return MC_COMM_ERR_RANGE;
                }
                break;
            }
            next_sub(c);
        }
        break;
    case ENC_PRE:
        w = move_velocity(c, MC_HALF_PI_F32, T_PRE_RAMP, T_PRE_CONST, c->n, &in_const, &end);
        break;
    case ENC_FWD1:
    case ENC_FWD2:
        w = move_velocity(c, MC_TWO_PI_F32, T_SWP_RAMP, T_SWP_CONST, c->n, &in_const, &end);
        break;
    case ENC_BACK:
        w = move_velocity(c, -MC_TWO_PI_F32, T_SWP_RAMP, T_SWP_CONST, c->n, &in_const, &end);
        break;
    default:
        break;
    }
    if (c->step != MC_COMM_STEP_ENCODER) {
        /* moved on to the resistance: hold the vector this period */
        w = 0.0f;
    }
    c->theta_cmd_rad = mc_wrap_2pi_f32(c->theta_cmd_rad + w * dt);
    mc_foc_f32_out_t fo;
    const uint32_t e = foc_out(c, i, c->theta_cmd_rad, 0.0f, c->i_cmd_a, 0.0f, out, &fo);
    if (c->sub == ENC_ALIGN_HOLD) {
        (void)mc_ident_avg_f32_step(&c->v_acc, fo.vd_v);
    }
    if (in_const) {
        if (c->sub == ENC_FWD1) {
            (void)mc_ident_avg_f32_step(&c->vq_acc, fo.vq_v);
        } else if (c->sub == ENC_BACK || c->sub == ENC_FWD2) {
            (void)mc_ident_circ_f32_step(&c->off_acc, c->theta_cmd_rad - enc_theta_e(c, m, 0.0f));
        }
    }
    if (end) {
        next_sub(c);
    }
    return e;
}

/* ------------------------------------------------------- resistance */
static uint32_t step_resistance(mc_comm_t *c, const float i[3], mc_drive_out_t *out)
{
    const float lvl = (c->sub == 0u) ? 0.5f * c->cfg.i_test_a : c->cfg.i_test_a;
    mc_foc_f32_out_t fo;
    const uint32_t e = foc_out(c, i, c->theta0_rad, 0.0f, lvl, 0.0f, out, &fo);
    if (e != 0u) {
        return e;
    }
    if ((fo.svpwm_flags & MC_SVPWM_FLAG_LIMITED) != 0u ||
        fo.vd_v * fo.vd_v + fo.vq_v * fo.vq_v >=
            0.9f * c->cfg.v_test_max_v * 0.9f * c->cfg.v_test_max_v) {
        if (c->n > steps_of(c, T_R_SETTLE)) {
            return MC_COMM_ERR_VOLTAGE;
        }
    }
    if (c->n >= steps_of(c, T_R_SETTLE)) {
        (void)mc_ident_avg_f32_step(&c->v_acc, fo.vd_v);
        (void)mc_ident_avg_f32_step(&c->i_acc, fo.id_a);
    }
    if (c->n >= steps_of(c, T_R_SETTLE + T_R_AVG)) {
        float v;
        float ia;
        (void)mc_ident_avg_f32_get(&c->v_acc, &v);
        (void)mc_ident_avg_f32_get(&c->i_acc, &ia);
        mc_ident_avg_f32_reset(&c->v_acc);
        mc_ident_avg_f32_reset(&c->i_acc);
        if (c->sub == 0u) {
            c->v1_v = v;
            c->i1_a = ia;
            next_sub(c);
            return 0u;
        }
        c->v2_v = v;
        c->i2_a = ia;
        if (mc_ident_r_two_level_f32(c->v1_v, c->i1_a, c->v2_v, c->i2_a, &c->res.r_ohm) != 0u) {
            return MC_COMM_ERR_RANGE;
        }
        /* The constant part: along an axis through phase a, the three legs'
         * errors add up to 4/3 of one leg's (amplitude-invariant Clarke). */
        c->res.dead_time_v = 0.75f * (c->v2_v - c->res.r_ohm * c->i2_a);
        c->res.valid |= MC_COMM_HAVE_R;
        /* Hold this DC vector for the inductance step. */
        c->vdc_alpha_v = fo.v_alpha_v;
        c->vdc_beta_v = fo.v_beta_v;
        enter(c, MC_COMM_STEP_INDUCTANCE, 0u);
    }
    return 0u;
}

/* The spin-ups' voltage limit: the modulator's (0.95 of vbus / sqrt 3)
 * within v_test_max. */
static float v_limit(const mc_comm_t *c)
{
    const float v = 0.95f * c->vbus_v * MC_INV_SQRT3_F32;
    return (v > c->cfg.v_test_max_v) ? c->cfg.v_test_max_v : v;
}

/* ------------------------------------------- flux without an encoder */
/* The I-f spin (README.md "Without an encoder"): i_test along a commanded
 * angle turning at omega; a rotor that follows turns at omega exactly, and
 * in the spin's frame the voltage is v = R i + j omega L i + the back-EMF,
 * omega psi along the rotor's q axis. Sub-phases: */
enum {
    IF_UP = 0,
    IF_EASE,
    IF_HI,
    IF_DOWN,
    IF_LO,
    IF_KEEP
};
#define T_IF_RAMP   1.0f               /* from rest to W_E_BW_MAX bandwidths (the largest speed) */
#define T_IF_JERK   0.2f               /* the acceleration rises and falls in this (1 - cos) */
#define T_IF_SETTLE 0.3f               /* each hold's settling before its average */
#define T_IF_AVG    0.2f               /* each hold's average */
#define T_IF_DOWN   1.0f               /* from the higher speed to half of it, (1 - cos) */
#define IF_SYNC_MIN 0.9f               /* |mean back-EMF| / mean |back-EMF| at least */
#define IF_COS_MIN  0.5f               /* the rotor's d axis within 60 deg el. of the current */
#define IF_PHI_MAX  (MC_PI_F32 / 3.0f) /* ... the same as an angle */
#define IF_PSI_MIN  0.2f /* psi at least this much of Ld i_test (an L error's share) */
/* The holds' fluxes agree within this besides the dead time's share: half
 * the 3 % flux bound (the library's largest disagreement: see README). */
#define IF_FLUX_TOL 0.015f

/* The spin's loop: the stiff loop of the flux step (kp = L bw, ki = R bw),
 * the current held at i_test while the back-EMF ramps. */
static uint32_t if_setup(mc_comm_t *c)
{
    c->w_if_rad_s = 0.0f;
    c->theta_cmd_rad = c->theta0_rad;
    return foc_setup(c, c->res.r_ohm, c->res.ld_h, c->res.lq_h, true, ZDIV_STIFF);
}

/* The back-EMF in a frame at angle phi of the spin's (v, i the means in
 * the spin's frame; Ld along that frame's d, Lq along its q). */
static void if_emf(const mc_comm_t *c, const float vi[4], float w, float phi, float *p_ed,
                   float *p_eq)
{
    float s;
    float co;
    mc_sincos_f32(phi, &s, &co);
    /* the inverter's error (dead time, drops): each phase's +-dead_time_v
     * with its current's sign, the fundamental (4 / pi) of it along i */
    const float im = mc_sqrt_f32(vi[2] * vi[2] + vi[3] * vi[3]);
    const float k = (im > 0.0f) ? (4.0f / MC_PI_F32) * c->res.dead_time_v / im : 0.0f;
    const float v0 = vi[0] - k * vi[2];
    const float v1 = vi[1] - k * vi[3];
    const float vd = v0 * co + v1 * s;
    const float vq = v1 * co - v0 * s;
    const float id = vi[2] * co + vi[3] * s;
    const float iq = vi[3] * co - vi[2] * s;
    *p_ed = vd - c->res.r_ohm * id + w * c->res.lq_h * iq;
    *p_eq = vq - c->res.r_ohm * iq - w * c->res.ld_h * id;
}

/* One hold's flux: the rotor's d axis phi in the spin's frame found where
 * the back-EMF has no d part (a few steps: with Ld = Lq the first is exact,
 * with saliency each shrinks the error by about (Lq - Ld) i / psi), then
 * psi = |e| / omega; refused IF_SYNC when the rotor does not follow. */
static uint32_t if_point(mc_comm_t *c, float w, float *p_psi, float *p_e)
{
    float vi[4];
    float emean = 0.0f;
    for (unsigned k = 0u; k < 3u; ++k) {
        (void)mc_ident_avg_f32_get(&c->corr[k], &vi[k]);
    }
    (void)mc_ident_avg_f32_get(&c->v_acc, &vi[3]);
    (void)mc_ident_avg_f32_get(&c->i_acc, &emean);
    float ed;
    float eq;
    float phi = 0.0f;
    if_emf(c, vi, w, 0.0f, &ed, &eq);
    const float sync = mc_sqrt_f32(ed * ed + eq * eq) / ((emean > 0.0f) ? emean : 1.0f);
    for (unsigned k = 0u; k < 4u; ++k) {
        phi += mc_atan2_f32(-ed, eq);
        if_emf(c, vi, w, phi, &ed, &eq);
    }
    /* A rotor swinging about the spin's angle by a (sync = J0(a), the mean
     * of the unit back-EMF) still turns at omega on average: the mean of
     * |e| is omega psi, the mean vector's magnitude J0(a) of it. */
    *p_e = mc_sqrt_f32(ed * ed + eq * eq) / ((sync > 0.0f) ? sync : 1.0f);
    *p_psi = *p_e / w;
    if (!(w > 0.0f) || !(sync >= IF_SYNC_MIN) || !(mc_abs_f32(phi) <= IF_PHI_MAX) || !(eq > 0.0f) ||
        !(*p_psi >= IF_PSI_MIN * c->res.ld_h * c->cfg.i_test_a)) {
        return MC_COMM_ERR_IF_SYNC;
    }
    return 0u;
}

/* The two holds' fluxes agree within the dead time's voltage over each
 * hold's back-EMF, as the encoder's two bands (the counts do not enter). */
static uint32_t if_end(mc_comm_t *c, float psi_lo, float e_lo)
{
    const float v_dead = (4.0f / 3.0f) * c->vbus_v * c->cfg.dead_time_s / c->cfg.dt_s;
    mc_comm_flux_chk_t *f = &c->flux_chk;
    f->psi_lo_wb = psi_lo;
    f->dev = mc_abs_f32(f->psi_hi_wb - psi_lo) / (0.5f * (f->psi_hi_wb + psi_lo));
    f->tol = IF_FLUX_TOL + v_dead / e_lo + v_dead / (f->psi_hi_wb * c->w_hi_rad_s);
    if (!(f->dev <= f->tol)) {
        return MC_COMM_ERR_FLUX_SPEEDS;
    }
    c->res.flux_wb = f->psi_hi_wb;
    c->res.valid |= MC_COMM_HAVE_FLUX | MC_COMM_SENSORLESS;
    enter(c, MC_COMM_STEP_DONE, IF_KEEP);
    return 0u;
}

static uint32_t step_if(mc_comm_t *c, const float i[3], mc_drive_out_t *out)
{
    const float dt = c->cfg.dt_s;
    const float w_cap = W_E_BW_MAX * c->cfg.cur_bw_rad_s;
    float w = c->w_if_rad_s;
    /* Smooth speed: the rotor follows the angle on the stiffness of i_test
     * alone (undamped), and a step of the acceleration leaves it swinging
     * by a / omega_n^2; over T_IF_JERK (longer than a swing) almost not. */
    const float k = (float)c->n * dt / ((c->sub == IF_DOWN) ? T_IF_DOWN : T_IF_JERK);
    float sk;
    float ck;
    mc_sincos_f32(MC_PI_F32 * ((k < 1.0f) ? k : 1.0f), &sk, &ck);
    if (c->sub == IF_UP) {
        c->a_acc = (w_cap / T_IF_RAMP) * 0.5f * (1.0f - ck);
        w += c->a_acc * dt;
    } else if (c->sub == IF_EASE) {
        w += c->a_acc * 0.5f * (1.0f + ck) * dt;
    } else if (c->sub == IF_DOWN) {
        w = c->w_hi_rad_s * (1.0f - 0.25f * (1.0f - ck));
    }
    c->w_if_rad_s = w;
    c->theta_cmd_rad = mc_wrap_2pi_f32(c->theta_cmd_rad + w * dt);
    mc_foc_f32_out_t fo;
    const uint32_t e = foc_out(c, i, c->theta_cmd_rad, w, c->cfg.i_test_a, 0.0f, out, &fo);
    if (e != 0u || c->sub == IF_KEEP) {
        return e;
    }
    const float vi[4] = {fo.vd_v, fo.vq_v, fo.id_a, fo.iq_a};
    float ed;
    float eq;
    if_emf(c, vi, w, 0.0f, &ed, &eq);
    const float em = mc_sqrt_f32(ed * ed + eq * eq);
    /* Out of step: a back-EMF clear of the inductance's error share turned
     * more than 60 deg el. off the current's q axis (the rotor slipping
     * behind: the loop, whose angle it no longer is, loses the current
     * soon after; refused first). Not in the ramp's first T_IF_JERK: at
     * the lowest speeds R's and the dead time's residues are as large. */
    if ((c->sub != IF_UP || k >= 1.0f) && em >= IF_PSI_MIN * c->res.ld_h * c->cfg.i_test_a * w &&
        eq < IF_COS_MIN * em) {
        return MC_COMM_ERR_IF_SYNC;
    }
    if (c->sub == IF_UP) {
        /* judged once the acceleration is whole (the easing's gain then at
         * most the speed reached: the loop has long settled) */
        if (k < 1.0f) {
            return 0u;
        }
        const float v_lim = v_limit(c);
        /* judged at the speed the easing ends on (its gain a T_IF_JERK / 2) */
        const float w_end = w + 0.5f * c->a_acc * T_IF_JERK;
        const float g = w_end / w;
        if (em * g >= c->cfg.bemf_frac * c->cfg.v_test_max_v ||
            (fo.vd_v * fo.vd_v + fo.vq_v * fo.vq_v) * g * g >=
                V_SPIN_FRAC * V_SPIN_FRAC * v_lim * v_lim ||
            (fo.svpwm_flags & MC_SVPWM_FLAG_LIMITED) != 0u || w_end >= w_cap ||
            w_end >= c->cfg.speed_max_m_rad_s * (float)c->res.pole_pairs) {
            next_sub(c);
        }
    } else if (c->sub == IF_EASE || c->sub == IF_DOWN) {
        if (k >= 1.0f) {
            c->w_hi_rad_s = (c->sub == IF_EASE) ? w : c->w_hi_rad_s;
            next_sub(c);
        }
    } else {
        if (c->n == steps_of(c, T_IF_SETTLE)) {
            sq_reset(c);
            mc_ident_avg_f32_reset(&c->v_acc);
            mc_ident_avg_f32_reset(&c->i_acc);
        }
        (void)mc_ident_avg_f32_step(&c->corr[0], fo.vd_v);
        (void)mc_ident_avg_f32_step(&c->corr[1], fo.vq_v);
        (void)mc_ident_avg_f32_step(&c->corr[2], fo.id_a);
        (void)mc_ident_avg_f32_step(&c->v_acc, fo.iq_a);
        (void)mc_ident_avg_f32_step(&c->i_acc, em);
        if (c->n >= steps_of(c, T_IF_SETTLE + T_IF_AVG)) {
            float psi;
            float eh;
            const uint32_t ep = if_point(c, w, &psi, &eh);
            if (ep != 0u || c->sub == IF_LO) {
                return (ep != 0u) ? ep : if_end(c, psi, eh);
            }
            c->flux_chk.psi_hi_wb = psi;
            next_sub(c);
        }
    }
    return 0u;
}

/* ------------------------------------------------------- inductance */
static uint32_t step_inductance(mc_comm_t *c, const float i[3], mc_drive_out_t *out)
{
    float s;
    float co;
    /* sub 0: settle, 1: d ripple, 2: settle, 3: q ripple */
    const float ang = c->theta0_rad + ((c->sub >= 2u) ? MC_HALF_PI_F32 : 0.0f);
    mc_sincos_f32(ang, &s, &co);
    if (c->n == 0u) {
        sq_reset(c);
        c->sq_sign = 1.0f;
        /* Ripple 30 % of i_test peak to peak, within the voltage left. */
        const float vdc =
            mc_sqrt_f32(c->vdc_alpha_v * c->vdc_alpha_v + c->vdc_beta_v * c->vdc_beta_v);
        float vh = 0.3f * c->cfg.i_test_a * c->l0_h / c->cfg.dt_s;
        const float room = 0.95f * c->cfg.v_test_max_v - vdc;
        if (vh > room) {
            vh = room;
        }
        if (!(vh > 0.0f)) {
            return MC_COMM_ERR_VOLTAGE;
        }
        c->vh_v = vh;
    }
    const bool ripple = (c->sub == 1u) || (c->sub == 3u);
    const float v = ripple ? c->sq_sign * c->vh_v * ((c->n == 0u) ? 0.5f : 1.0f) : 0.0f;
    (void)volts_out(c, c->vdc_alpha_v + v * co, c->vdc_beta_v + v * s, c->vbus_v, out);
    if (ripple) {
        sq_correlate(c, i, SQ_SKIP);
        c->sq_sign = -c->sq_sign;
    }
    const uint32_t len = ripple ? steps_of(c, T_L_AVG) : steps_of(c, T_L_SETTLE);
    if (c->n >= len) {
        if (ripple) {
            float dph[3];
            const float d = sq_ripple(c, co, s, dph);
            float l = 0.0f;
            if (d < 0.01f * c->cfg.i_test_a ||
                mc_ident_l_square_wave_f32(c->vh_v, c->cfg.dt_s, d, c->res.r_ohm, &l) != 0u) {
                return MC_COMM_ERR_RANGE;
            }
            if (c->sub == 1u) {
                c->res.ld_h = l;
            } else {
                c->res.lq_h = l;
                c->res.valid |= MC_COMM_HAVE_L;
                if (c->enc_coarse) {
                    return MC_COMM_ERR_ENCODER_COARSE;
                }
                enter(c, MC_COMM_STEP_FLUX, 0u);
                if (c->cfg.pole_pairs_given != 0u) {
                    return if_setup(c);
                }
                c->count_acc = 0;
                mc_ident_line_f32_reset(&c->acc_fit);
                mc_ident_line_f32_reset(&c->fit_band[0]);
                mc_ident_line_f32_reset(&c->fit_band[1]);
                mc_comm_blk_reset(&c->spin_rec);
                mc_comm_blk_reset(&c->coast_rec);
                c->iq_spin_a = 0.5f * c->cfg.i_test_a;
                c->t_s = 0.0f;
                return foc_setup(c, c->res.r_ohm, c->res.ld_h, c->res.lq_h, true, ZDIV_STIFF);
            }
        }
        next_sub(c);
    }
    return 0u;
}

/* ------------------------------------------------ flux and mechanics */
/* The flux fit's band resolution (mc_comm_flux_band_res_f32) of band k. */
static float band_res(const mc_comm_t *c, uint32_t cpr, unsigned k)
{
    const mc_ident_line_f32_t *f = &c->fit_band[k];
    const float n = (float)((f->sx.n > 0u) ? f->sx.n : 1u);
    const float w_m = f->sx.sum / n / (float)c->res.pole_pairs;
    const float v = mc_abs_f32(f->sy.sum / n);
    const float tau = (c->cfg.speed_tau_s > 0.0f) ? c->cfg.speed_tau_s : TAU_SPEED_S;
    const float v_dead = (4.0f / 3.0f) * c->vbus_v * c->cfg.dead_time_s / c->cfg.dt_s;
    return mc_comm_flux_band_res_f32(cpr, 0.5f * T_COAST, tau, w_m, v_dead, v);
}

/* The end of the coast: the flux, its two-band check, J and B from the
 * spin-up and the coast, their checks (README.md "Checks of the flux
 * step"); a refusal returns its bit and stores nothing. */
static uint32_t coast_end(mc_comm_t *c, uint32_t cpr)
{
    /* the whole window's through-origin fit: the two bands' sums */
    const mc_ident_line_f32_t *fb = c->fit_band;
    const float sxx = fb[0].sxx.sum + fb[1].sxx.sum;
    const float psi = (fb[0].sxy.sum + fb[1].sxy.sum) / ((sxx > 0.0f) ? sxx : 1.0f);
    if (!(psi > 0.0f) || fb[0].sx.n < 2u || fb[1].sx.n < 2u) {
        return MC_COMM_ERR_RANGE;
    }
    const float tol = band_res(c, cpr, 0u) + band_res(c, cpr, 1u);
    const uint32_t ef = mc_comm_flux_check_f32(&c->fit_band[0], &c->fit_band[1], tol, &c->flux_chk);
    if (ef != 0u) {
        return ef;
    }
    c->res.flux_wb = psi;
    c->res.valid |= MC_COMM_HAVE_FLUX;
    float ac = 0.0f;
    const float wc = c->acc_fit.sy.sum / (float)(c->acc_fit.sy.n ? c->acc_fit.sy.n : 1u);
    if (c->a_acc > 0.0f && mc_ident_line_f32_get(&c->acc_fit, true, &ac, NULL) == 0u && wc > 0.0f) {
        const float kt = 1.5f * (float)c->res.pole_pairs * psi;
        const float den = c->a_acc - ac * c->w_acc_mean / wc;
        if (den > 0.0f) {
            const float j = kt * c->iq_spin_a / den;
            const float b = -ac * j / wc;
            if (j > 0.0f && b >= 0.0f) {
                const uint32_t em = mc_comm_mech_check_f32(&c->spin_rec, &c->coast_rec, c->cfg.dt_s,
                                                           cpr, kt * c->iq_spin_a, &c->mech_chk);
                if (em != 0u) {
                    return em;
                }
                c->res.j_kgm2 = j;
                c->res.b_nm_s_rad = b;
                c->res.valid |= MC_COMM_HAVE_MECH;
            }
        }
    }
    return 0u;
}

static uint32_t step_flux(mc_comm_t *c, const float i[3], const mc_drive_meas_t *m,
                          mc_drive_out_t *out)
{
    track_count(c, m);
    const uint32_t cpr = m->enc_cpr;
    const float p = (float)c->res.pole_pairs;
    const float dir = (float)c->res.encoder_direction;
    const float w_m = dir * c->w_m_rad_s; /* positive: forward */
    const float w_e = p * w_m;
    const float theta = enc_theta_e(c, m, c->res.encoder_offset_rad);
    const float turned_e = dir * (float)c->count_acc * p * MC_TWO_PI_F32 / (float)cpr;
    const float dt = c->cfg.dt_s;
    c->t_s += dt;
    mc_foc_f32_out_t fo;
    const bool spin = (c->sub == 0u);
    uint32_t e = foc_out(c, i, theta, w_e, 0.0f, spin ? c->iq_spin_a : 0.0f, out, &fo);
    if (e != 0u) {
        return e;
    }
    if (turned_e < -MC_HALF_PI_F32) {
        return MC_COMM_ERR_WRONG_DIRECTION;
    }
    const float vmag = mc_sqrt_f32(fo.vd_v * fo.vd_v + fo.vq_v * fo.vq_v);
    if (spin) {
        if (c->t_s >= T_SPIN_BLOCK && turned_e < MC_HALF_PI_F32) {
            return MC_COMM_ERR_ROTOR_BLOCKED;
        }
        if (c->t_s >= 0.02f) {
            (void)mc_ident_line_f32_step(&c->acc_fit, c->t_s, w_m);
            mc_comm_blk_step(&c->spin_rec, w_m);
        }
        /* The back-EMF part of the voltage (the resistive drop removed). */
        const float emf = fo.vq_v - c->res.r_ohm * fo.iq_a;
        /* The whole voltage as well: at a high electrical speed the
         * winding's own omega_e Lq iq (along d) can take the voltage before
         * the back-EMF reaches its fraction; a loop at its limit no longer
         * controls the current, and the coast would start from nonsense. */
        const float v_lim = v_limit(c);
        if ((c->t_s >= T_SPIN_SETTLE &&
             (mc_abs_f32(emf) >= c->cfg.bemf_frac * c->cfg.v_test_max_v ||
              vmag >= V_SPIN_FRAC * v_lim || (fo.svpwm_flags & MC_SVPWM_FLAG_LIMITED) != 0u)) ||
            w_e >= W_E_BW_MAX * c->cfg.cur_bw_rad_s || w_m >= c->cfg.speed_max_m_rad_s ||
            c->t_s >= T_SPIN_MAX) {
            if (w_m <= 0.0f) {
                return MC_COMM_ERR_ROTOR_BLOCKED;
            }
            float a = 0.0f;
            if (mc_ident_line_f32_get(&c->acc_fit, true, &a, NULL) == 0u &&
                c->acc_fit.sx.n >= 20u) {
                c->a_acc = a;
                c->w_acc_mean = c->acc_fit.sy.sum / (float)c->acc_fit.sy.n;
            } else {
                c->a_acc = 0.0f;
            }
            mc_ident_line_f32_reset(&c->acc_fit);
            next_sub(c);
            c->t_s = 0.0f;
            c->quiet_n = 0u;
            c->t_fit0_s = -1.0f;
        }
        return 0u;
    }
    if (c->sub == 1u) {
        /* The fit starts once the current has settled at zero (a loop
         * whose bandwidth is below the electrical speed rings after the
         * step of iq; during that the voltage is not the back-EMF), at the
         * latest T_COAST_SKIP_MAX into the coast. */
        const float gate = I_COAST_GATE * c->cfg.i_test_a;
        if (fo.id_a * fo.id_a + fo.iq_a * fo.iq_a < gate * gate) {
            c->quiet_n++;
        } else {
            c->quiet_n = 0u;
        }
        if (c->t_fit0_s < 0.0f && c->t_s >= T_COAST_SKIP &&
            (c->quiet_n >= steps_of(c, T_COAST_QUIET) || c->t_s >= T_COAST_SKIP_MAX)) {
            c->t_fit0_s = c->t_s;
        }
        if (c->t_fit0_s >= 0.0f) {
            /* Zero current: the voltage is the back-EMF alone, omega_e psi
             * along q; its magnitude does not depend on the angle error of
             * the one-period delay. */
            const float y = (fo.vq_v >= 0.0f) ? vmag : -vmag;
            (void)mc_ident_line_f32_step(
                &c->fit_band[(c->t_s < c->t_fit0_s + 0.5f * T_COAST) ? 0 : 1], w_e, y);
            (void)mc_ident_line_f32_step(&c->acc_fit, c->t_s, w_m);
            mc_comm_blk_step(&c->coast_rec, w_m);
        }
        if (c->t_fit0_s >= 0.0f && c->t_s >= c->t_fit0_s + T_COAST) {
            /* the checks' count resolution: with Hall sensors a sector (the
             * drive's Hall counts, MC_DRIVE_HALL_COUNTS_E an electrical turn,
             * are interpolated between the edges) */
            e = coast_end(c, (c->cfg.hall != NULL) ? 6u * c->res.pole_pairs : cpr);
            if (e == 0u) {
                enter(c, MC_COMM_STEP_DONE, 0u);
            }
            return e;
        }
    }
    return 0u;
}

static uint32_t fast_cb(void *ctx, const mc_drive_meas_t *m, mc_drive_out_t *out)
{
    mc_comm_t *c = (mc_comm_t *)ctx;
    zero_out(out);
    if (c->err != 0u) {
        c->step = MC_COMM_STEP_FAILED;
        return c->err;
    }
    const bool sls = c->cfg.pole_pairs_given != 0u;
    if ((!sls && (!m->have_encoder || m->enc_cpr == 0u)) || !mc_isfinite_f32(m->vbus_v) ||
        !(m->vbus_v > 0.0f)) {
        c->err |= MC_COMM_ERR_MEAS;
        c->step = MC_COMM_STEP_FAILED;
        return c->err;
    }
    c->vbus_v = m->vbus_v;
    const float raw[3] = {m->ia_a, m->ib_a, m->ic_a};
    float i[3];
    i[0] = raw[0] - c->res.adc_offset_a[0];
    i[1] = raw[1] - c->res.adc_offset_a[1];
    i[2] = c->cfg.three_shunts ? raw[2] - c->res.adc_offset_a[2] : -(i[0] + i[1]);
    uint32_t e = 0u;
    if (c->step != MC_COMM_STEP_OFFSETS) {
        const float lim = 1.5f * c->cfg.i_test_a;
        if (mc_abs_f32(i[0]) > lim || mc_abs_f32(i[1]) > lim || mc_abs_f32(i[2]) > lim) {
            e |= MC_COMM_ERR_OVERCURRENT;
        }
    }
    if (e == 0u) {
        switch (c->step) {
        case MC_COMM_STEP_OFFSETS:
            e = step_offsets(c, raw, out);
            break;
        case MC_COMM_STEP_L_ROUGH:
            e = step_l_rough(c, i, out);
            break;
        case MC_COMM_STEP_ENCODER:
            e = step_encoder(c, i, m, out);
            break;
        case MC_COMM_STEP_RESISTANCE:
            e = step_resistance(c, i, out);
            break;
        case MC_COMM_STEP_INDUCTANCE:
            e = step_inductance(c, i, out);
            break;
        case MC_COMM_STEP_FLUX:
        case MC_COMM_STEP_DONE: {
            if (sls) {
                /* the spin held at its lower speed until the application
                 * opens the bridge: zero current needs the angle */
                e = step_if(c, i, out);
                break;
            }
            if (c->step == MC_COMM_STEP_DONE) {
                /* zero current on the identified values */
                c->sub = 2u;
            }
            e = step_flux(c, i, m, out);
            break;
        }
        default:
            break;
        }
    }
    c->n++;
    c->progress_pct = (uint8_t)((c->step >= MC_COMM_STEP_DONE) ? 100u : (uint32_t)c->step * 14u);
    if (e != 0u) {
        c->err |= e;
        c->step = MC_COMM_STEP_FAILED;
        c->res.valid = 0u;
        c->res.have_hall = false;
        zero_out(out);
        return c->err;
    }
    return 0u;
}

uint32_t mc_comm_hall_fault_reason(const mc_comm_t *c, uint32_t drive_faults)
{
    uint32_t code = 0u;
    if (c == NULL || c->cfg.hall == NULL || c->step != MC_COMM_STEP_ENCODER ||
        c->sub < ENC_HALL_RAMP || (drive_faults & MC_DRIVE_FAULT_ENCODER) == 0u ||
        mc_hal_hall_read(c->cfg.hall, &code) != 0) {
        return 0u;
    }
    return (code == 0u || code == 7u) ? MC_COMM_ERR_HALL_CODES : MC_COMM_ERR_HALL_ORDER;
}

const mc_drive_ctrl_t *mc_comm_ops(mc_comm_t *c)
{
    c->ops = (mc_drive_ctrl_t){
        .outputs = MC_DRIVE_OUT_PWM3,
        .needs_encoder = (c->cfg.pole_pairs_given == 0u),
        .finds_angle = true, /* it measures the encoder offset */
        .reset = reset_cb,
        .fast = fast_cb,
        .slow = NULL,
        .ctx = c,
    };
    return &c->ops;
}

uint32_t mc_comm_apply(const mc_comm_result_t *r, float cur_bw_rad_s, mc_drive_cfg_t *dc)
{
    /* without an encoder (MC_COMM_SENSORLESS) no offset or direction */
    const bool enc = (r->valid & MC_COMM_SENSORLESS) == 0u;
    const uint32_t need = MC_COMM_HAVE_OFFSETS | MC_COMM_HAVE_R | MC_COMM_HAVE_L |
                          MC_COMM_HAVE_FLUX | (enc ? MC_COMM_HAVE_ENCODER : 0u);
    if ((r->valid & need) != need || !(r->r_ohm > 0.0f) || !(r->ld_h > 0.0f) || !(r->lq_h > 0.0f) ||
        !(r->flux_wb > 0.0f) || r->pole_pairs < 1u ||
        (enc && (!mc_isfinite_f32(r->encoder_offset_rad) ||
                 (r->encoder_direction != 1 && r->encoder_direction != -1)))) {
        return MC_COMM_ERR_RANGE;
    }
    float kpd;
    float kid;
    float kpq;
    float kiq;
    if (mc_foc_f32_gains_from_bandwidth(r->r_ohm, r->ld_h, cur_bw_rad_s, &kpd, &kid) != 0u ||
        mc_foc_f32_gains_from_bandwidth(r->r_ohm, r->lq_h, cur_bw_rad_s, &kpq, &kiq) != 0u) {
        return MC_COMM_ERR_RANGE;
    }
    dc->foc.r_ohm = r->r_ohm;
    dc->foc.ld_h = r->ld_h;
    dc->foc.lq_h = r->lq_h;
    dc->foc.flux_wb = r->flux_wb;
    dc->foc.kp_d_v_per_a = kpd;
    dc->foc.ki_d_v_per_as = kid;
    dc->foc.kp_q_v_per_a = kpq;
    dc->foc.ki_q_v_per_as = kiq;
    dc->pole_pairs = r->pole_pairs;
    if (enc) {
        dc->encoder_offset_rad = r->encoder_offset_rad;
        dc->encoder_reversed = (r->encoder_direction < 0);
    }
    for (unsigned k = 0u; k < 3u; ++k) {
        dc->i_offset_a[k] += r->adc_offset_a[k];
    }
    return 0u;
}
