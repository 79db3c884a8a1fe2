/**
 * @file bench_isr.c
 * @brief Instruction counts of the drive image's interrupts on the emulated
 *        Cortex-M4F (QEMU netduinoplus2, -icount shift=0): the whole fast
 *        interrupt (ADC read to duties written, application included), the
 *        CAN receive interrupt per frame and the slow loop (PendSV).
 *
 * The image's own code, unchanged: this file includes the image's main.c
 * (its `main` renamed, since the bench replays its set-up) and the board
 * binding board_stm32f405.c, so ADC_IRQHandler, PendSV_Handler,
 * CAN1_RX0_IRQHandler and the board hooks counted here are the image's,
 * with its statics (drive, application, board) reachable. Built once per
 * board (MC_BOARD_DESC: example, odrive36, vesc6) with the board's
 * generated description, the hal/stm32f405 drivers, firmware/app and the
 * kernels.
 *
 * Registers: the board's peripherals (GPIO, RCC enables, TIM1 PWM, TIM3
 * encoder, TIM5 tick, ADC1, CAN1, SPI3) are RAM stand-ins handed to the
 * board's set-up (mc_board_f405_setup through mc_board_f405_periph_t, as the
 * host tests do); the bench plays the hardware between interrupts (injected
 * conversions in JDR with JEOC set, the encoder count in TIM3_CNT, a
 * received frame in CAN FIFO 0, every transmit mailbox empty). A register
 * access to RAM is one load or store, as to the peripheral. The flash
 * store and the IWDG keep the image's addresses (QEMU maps them as
 * unimplemented devices: the store is empty, the defaults boot). The
 * DRV8301 is not emulated: its set-up over SPI (boot, not the interrupts)
 * is skipped and the board marked ready.
 *
 * Interrupts: the bench runs with PRIMASK set and calls the handlers as
 * functions between two reads of TIM2_CNT (TIM2 at PSC = 0 counts one tick
 * per executed instruction); the pended PendSV is read back from ICSR,
 * cleared and PendSV_Handler called and counted on its own. The exception
 * entry and exit (stacking, not instructions) are not in the counts
 * (run_isr_bench.py adds them to the CPU budget).
 *
 * Runs (one image per board, both runs in it, each from a fresh set-up):
 *   sensored    CAN: control mode SPEED (the application's speed loop on
 *               the encoder, the drive in CURRENT mode), speed reference,
 *               enable, host heartbeats; encoder turning.
 *   sensorless  the same with the sensorless law (firmware/app/ctrl/
 *               mc_ctrl_sensorless) plugged as the SPEED law (CTRL mode),
 *               held in its closed-loop phase (observer, PLL, speed PI,
 *               current loop: the costly one) by the bench.
 * The phase currents are a 2 A vector turning with the encoder's angle.
 * Each run: a warm-up, then RUN_PERIODS periods counted (the ADC interrupt
 * every period, PendSV every slow_loop_div, a host heartbeat frame every
 * 10 ms through the CAN interrupt); then per part (ADC read, the speed
 * law, the drive's FOC step, application mark, duties write) on copies of
 * the state; then the CAN
 * receive interrupt per frame and the slow loop with a full ring of
 * MC_APP_RX_PER_STEP command frames (parameter reads) over every phase of
 * the telemetry schedule, the reply limiter's bucket full before each (its
 * worst case: MC_TM_REPLY_BURST reads answered, one more served and its
 * reply held, the rest not served). The sensored run then counts the
 * anticogging lookup alone and RUN_PERIODS interrupts with a map attached
 * and anticogging on (cog_lookup, isr_anticogging; its "isr" has it off).
 *
 * Output: one JSON object per line over semihosting (run_isr_bench.py).
 */
#include <stdbool.h>
#include <stdint.h>
#include <errno.h>
#include <string.h>

#include "bench_isr.h"
#include "bench_out.h"
#include "m4f/semihost.h"
#include "math/mc_math.h"
#include "mc_can_dbc.h"
#include "mc_can_proto.h"
#include "mc_cortexm.h"
#include "mc_ctrl_sensorless.h"

#define TIM2_CR1       (*(volatile uint32_t *)0x40000000u)
#define TIM2_EGR       (*(volatile uint32_t *)0x40000014u)
#define TIM2_CNT       (*(volatile uint32_t *)0x40000024u)
#define TIM2_PSC       (*(volatile uint32_t *)0x40000028u)
#define TIM2_ARR       (*(volatile uint32_t *)0x4000002Cu)
#define ICSR_PENDSVCLR (1u << 27)

#ifndef WARMUP_PERIODS
#define WARMUP_PERIODS 2000u /* 100 ms: commands handled, loops settled */
#endif
#ifndef RUN_PERIODS
#define RUN_PERIODS 2000u /* 100 ms: 100 slow loops, 10 heartbeats */
#endif
#ifndef PROFILE_PERIOD
#define PROFILE_PERIOD 1000u /* the counted period run_isr_profile.py single-steps */
#endif
#define PART_CALLS 64u
#define RX_FRAMES  64u
#ifndef SLOW_RUNS
#define SLOW_RUNS 200u /* slow loops with a full ring: every telemetry phase */
#endif
#define I_VEC_A  2.0f
#define ENC_STEP 3u /* counts per period: 0.37 rev/s at 2000 counts, 20 kHz */

/* ---- output ------------------------------------------------------------- */

typedef struct {
    uint32_t n, min, max, sum;
} stat_t;

static void stat_add(stat_t *s, uint32_t v)
{
    if (s->n == 0u || v < s->min) {
        s->min = v;
    }
    if (v > s->max) {
        s->max = v;
    }
    s->sum += v;
    s->n++;
}

/* {"board": .., "run": .., "part": .., "n": .., "min": .., "sum": .., "max": ..} */
static void out_stat(const char *run, const char *part, const stat_t *s)
{
    bench_out_str("{\"board\": \"");
    bench_out_str(MC_BENCH_BOARD);
    bench_out_str("\", \"run\": \"");
    bench_out_str(run);
    bench_out_str("\", \"part\": \"");
    bench_out_str(part);
    bench_out_str("\", \"n\": ");
    bench_out_u32(s->n);
    bench_out_str(", \"min\": ");
    bench_out_u32(s->min);
    bench_out_str(", \"sum\": ");
    bench_out_u32(s->sum);
    bench_out_str(", \"max\": ");
    bench_out_u32(s->max);
    bench_out_str("}");
    bench_out_flush();
}

static void out_kv(const char *key, uint32_t v)
{
    bench_out_str("{\"board\": \"");
    bench_out_str(MC_BENCH_BOARD);
    bench_out_str("\", \"");
    bench_out_str(key);
    bench_out_str("\": ");
    bench_out_u32(v);
    bench_out_str("}");
    bench_out_flush();
}

/* ---- counting ----------------------------------------------------------- */

static uint32_t g_overhead;

typedef void (*fn_t)(void);

/* noipa (noinline, noclone, no identical-code folding): the image links
 * with LTO like the drive image, which would otherwise specialise count()
 * per handler or fold the empty functions below into one body (the profile
 * mark then stops at every overhead measurement). */
static __attribute__((noipa)) uint32_t count(fn_t fn)
{
    const uint32_t t0 = TIM2_CNT;
    fn();
    const uint32_t t1 = TIM2_CNT;
    const uint32_t d = t1 - t0;
    return (d > g_overhead) ? d - g_overhead : 0u;
}

static __attribute__((noipa)) void empty_fn(void)
{
    __asm__ volatile("" ::: "memory");
}

/* ---- the hardware between interrupts ------------------------------------ */

static bench_regs_t g_regs;
static mc_drive_t *D;
static mc_app_t *A;
static mc_board_f405_t *B;
static const mc_board_desc_t *DESC;
static uint32_t g_enc;

static float g_temp_v[2];

/* Sensor temperature at pin voltage v (the board's table or cubic, as
 * hal/stm32f405/mc_f405_adc.c converts it). */
static float sensor_temp_c(const mc_f405_adc_temp_sensor_t *ts, float v)
{
    if (ts->n_table != 0u) {
        const mc_f405_adc_temp_point_t *t = ts->p_table;
        uint32_t k = 1u;
        while (k < ts->n_table - 1u && v > t[k].v) {
            k++;
        }
        return t[k - 1u].t_c +
               (v - t[k - 1u].v) * (t[k].t_c - t[k - 1u].t_c) / (t[k].v - t[k - 1u].v);
    }
    return ts->offset_c + v * (ts->slope_c_per_v + v * (ts->c2_c_per_v2 + v * ts->c3_c_per_v3));
}

/* The pin voltage of a sensor nearest 25 degC within its window. */
static float room_temp_v(const mc_f405_adc_temp_sensor_t *ts)
{
    const float lo = (ts->n_table != 0u) ? ts->p_table[0].v : ts->v_min_v;
    const float hi = (ts->n_table != 0u) ? ts->p_table[ts->n_table - 1u].v : ts->v_max_v;
    float best = 0.5f * (lo + hi);
    float err = 1e9f;
    for (uint32_t k = 1u; k < 256u; k++) {
        const float v = lo + (hi - lo) * (float)k / 256.0f;
        const float e = mc_abs_f32(sensor_temp_c(ts, v) - 25.0f);
        if (e < err) {
            err = e;
            best = v;
        }
    }
    return best;
}

/* One conversion: phase currents of a 2 A vector at the encoder's electrical
 * angle plus 90 degrees, the bus at the middle of the board's window. */
static void hw_sample(bool advance)
{
    const mc_f405_adc_t *a = &B->adc;
    const uint32_t cpr = DESC->enc_counts_per_rev;
    g_enc = (g_enc + (advance ? ENC_STEP : 0u)) % cpr;
    g_regs.tim3.CNT = g_enc;
    const float th = MC_TWO_PI_F32 * (float)((g_enc * 4u) % cpr) / (float)cpr;
    float s;
    float c;
    mc_sincos_f32(th, &s, &c);
    const float ph[3] = {-I_VEC_A * s, I_VEC_A * (0.5f * s + 0.8660254f * c),
                         I_VEC_A * (0.5f * s - 0.8660254f * c)};
    for (uint32_t k = 0u; k < a->n_phase; k++) {
        const uint32_t p = a->phase_of_rank[k];
        g_regs.adc.JDR[k] = (uint32_t)(a->offset_counts[p] + ph[p] / a->a_per_count[p] + 0.5f);
    }
    const float vbus = 0.5f * (DESC->vbus_min_v + DESC->vbus_max_v);
    g_regs.adc.JDR[a->rank_vbus] = (uint32_t)(vbus / (a->v_per_count * a->cfg.vbus_divider) + 0.5f);
    g_regs.adc.SR |= MC_F405_ADC_SR_JEOC;
    /* The regular conversion of the thermistor being read: done, at a
     * room temperature. */
    const float tv = (a->temp_slot == 0u) ? g_temp_v[0] : g_temp_v[1];
    g_regs.adc.DR = (uint32_t)(tv / a->v_per_count + 0.5f);
    g_regs.adc.SR |= MC_F405_ADC_SR_EOC;
}

/* Every fault input at its idle level (nFAULT of the gate driver). */
static void hw_idle_inputs(void)
{
    const mc_board_pin_t f = DESC->gate_fault;
    if (f.port < MC_F405_GPIO_PORTS) {
        if (f.active_low) {
            g_regs.gpio[f.port].IDR |= 1u << f.pin;
        } else {
            g_regs.gpio[f.port].IDR &= ~(1u << f.pin);
        }
    }
}

/* A frame of this node into CAN FIFO 0 (FMP0 = 1). */
static void hw_can_frame(uint32_t msg, const float *v, uint32_t n)
{
    mc_hal_can_frame_t f;
    (void)mc_can_proto_pack(msg, A->params.can_node_id, v, n, &f);
    g_regs.can.RX[0].RIR = f.id << MC_F405_CAN_IR_STID_SHIFT;
    g_regs.can.RX[0].RDTR = f.len;
    g_regs.can.RX[0].RDLR = (uint32_t)f.data[0] | ((uint32_t)f.data[1] << 8) |
                            ((uint32_t)f.data[2] << 16) | ((uint32_t)f.data[3] << 24);
    g_regs.can.RX[0].RDHR = (uint32_t)f.data[4] | ((uint32_t)f.data[5] << 8) |
                            ((uint32_t)f.data[6] << 16) | ((uint32_t)f.data[7] << 24);
    g_regs.can.RF0R = 1u;
    g_regs.can.TSR = MC_F405_CAN_TSR_TME(0) | MC_F405_CAN_TSR_TME(1) | MC_F405_CAN_TSR_TME(2);
}

static uint32_t g_hb;
static stat_t g_rx;

static void send_cmd(uint32_t msg, const float *v, uint32_t n)
{
    hw_can_frame(msg, v, n);
    stat_add(&g_rx, count(CAN1_RX0_IRQHandler));
}

static void send_heartbeat(void)
{
    const float v[1] = {(float)(g_hb++ & 0xFFu)};
    send_cmd(MC_CAN_MSG_HOST_HEARTBEAT, v, 1u);
}

/* ---- one PWM period ------------------------------------------------------ */

static stat_t g_isr, g_isr_slow, g_slow, g_profiled;

/* tools/bench/run_isr_profile.py stops here (a breakpoint) and
 * single-steps the next ADC interrupt; a no-op otherwise, called outside
 * the counts. */
__attribute__((noipa)) void bench_profile_mark(void);
__attribute__((noipa)) void bench_profile_mark(void)
{
    __asm volatile("" ::: "memory");
}

/* The ADC interrupt, then PendSV if it pended it; the interrupt's count. */
static uint32_t period(bool counted)
{
    hw_sample(true);
    const uint32_t n = count(ADC_IRQHandler);
    const bool slow = (MC_SCB_ICSR & MC_SCB_ICSR_PENDSVSET) != 0u;
    if (counted) {
        stat_add(&g_isr, n);
        if (slow) {
            stat_add(&g_isr_slow, n);
        }
    }
    if (slow) {
        MC_SCB_ICSR = ICSR_PENDSVCLR;
        const uint32_t m = count(PendSV_Handler);
        if (counted) {
            stat_add(&g_slow, m);
        }
    }
    return n;
}

/* ---- parts on copies of the state ---------------------------------------- */

static mc_ctrl_sls_t g_sls;
static mc_ctrl_sls_t g_sls_copy;
static mc_ctrl_speed_t g_spd_copy;
static mc_foc_f32_t g_foc_copy;
static mc_foc_f32_out_t g_foc_out;
static mc_hal_adc_sample_t g_adc_s;
static mc_drive_out_t g_law_out;
static volatile int g_sink;

static void part_adc(void)
{
    g_sink = mc_hal_adc_read(B->hal.adc, &g_adc_s);
}
static void part_pwm(void)
{
    g_sink =
        mc_hal_pwm3_set_duty(B->hal.pwm3, D->tm.foc.duty_a, D->tm.foc.duty_b, D->tm.foc.duty_c);
}
/* The brake chopper's duty write (boards with one): what the drive's fast
 * step adds when brake_enable is 1 (the runs' tables leave it 0). */
static void part_brake(void)
{
    g_sink = mc_hal_brake_set_duty(B->hal.brake, 0.5f);
}
static void part_mark(void)
{
    mc_app_fast_mark(A);
}
static void part_enc(void)
{
    mc_hal_encoder_sample_t e;
    g_sink = mc_hal_encoder_read(B->hal.encoder, &e);
}
static void part_foc(void)
{
    const mc_foc_f32_in_t in = {
        .ia_a = D->tm.ia_a,
        .ib_a = D->tm.ib_a,
        .ic_a = D->tm.ic_a,
        .three_phase = false,
        .theta_e_rad = D->tm.theta_e_rad,
        .omega_e_rad_s = D->enc_trk.omega_rad_s * (float)D->cfg.pole_pairs,
        .vbus_v = D->tm.vbus_v,
        .id_ref_a = D->tm.id_ref_a,
        .iq_ref_a = D->tm.iq_ref_a,
    };
    g_sink = (int)mc_foc_f32_step(&g_foc_copy, &in, &g_foc_out);
}
/* The measurement the drive hands a law (mc_drive_fast_step), from the
 * state the run left: the shaped speed reference, the limit in force. */
static mc_drive_meas_t law_meas(void)
{
    const mc_drive_meas_t m = {
        .ia_a = D->tm.ia_a,
        .ib_a = D->tm.ib_a,
        .ic_a = D->tm.ic_a,
        .vbus_v = D->tm.vbus_v,
        .have_encoder = true,
        .theta_m_rad = D->tm.theta_m_rad,
        .theta_e_rad = D->tm.theta_e_rad,
        .omega_m_rad_s = D->enc_trk.omega_rad_s,
        .enc_count = g_enc,
        .enc_raw_count = g_enc,
        .enc_cpr = DESC->enc_counts_per_rev,
        .dt_s = D->cfg.foc.dt_s,
        .fast_count = D->fast_count,
        .i_max_a = D->cfg.i_max_a,
        .iq_applied_a = D->tm.iq_ref_a,
        .regen_scale = D->tm.regen_scale,
        .v_alpha_prev_v = D->v_ab_prev_v[0],
        .v_beta_prev_v = D->v_ab_prev_v[1],
        .have_speed_ref = true,
        .omega_ref_rad_s = D->speed_ref_rad_s,
        .alpha_ref_rad_s2 = D->speed_alpha_rad_s2,
    };
    return m;
}
/* Built once before the law's part is counted: the part is the law's fast
 * step alone (the drive's own building of the record is in its rest, and
 * a record built inside the count would measure the compiler's way of
 * zeroing a struct, which changes with the struct's size). */
static mc_drive_meas_t g_law_meas;
static void part_law(void)
{
    g_sink = (int)mc_ctrl_sls_fast(&g_sls_copy, &g_law_meas, &g_law_out);
}
static void part_speed_law(void)
{
    g_sink = (int)mc_ctrl_speed_fast(&g_spd_copy, &g_law_meas, &g_law_out);
}

/* The anticogging map (mc_drive_cog.h): the feed-forward alone as the
 * drive makes it (mc_drive.c cog_ff: the loop's leads, mc_cog_loop_t), from
 * the bins (a map of every order, mc_cog_ff_adv_a) and from the series (a
 * map of an order, mc_cog_series_ff_adv_a, with the most terms a map keeps,
 * MC_COG_KEEP_MAX); the series' derivation from the map once (the slow
 * context's, when a map is attached); and the whole interrupt with the
 * series feed-forward on (the sensored run). Any shape: the costs do not
 * depend on the values. */
static mc_cog_map_t g_cog;
static mc_cog_series_t g_cog_ser;
static float g_cog_i[MC_COG_N];
static volatile float g_sinkf;
static const mc_cog_loop_t g_cog_loop = {3.3e-5f, 5.0e-5f, 4.0e-4f};
static void part_cog(void)
{
    float i_a;
    g_sinkf =
        mc_cog_ff_adv_a(&g_cog, D->tm.theta_m_rad, D->tm.omega_m_rad_s, &g_cog_loop, &i_a) + i_a;
}
static void part_cog_series(void)
{
    float i_a;
    g_sinkf = mc_cog_series_ff_adv_a(&g_cog_ser, D->tm.theta_m_rad, D->tm.omega_m_rad_s,
                                     &g_cog_loop, &i_a) +
              i_a;
}
static void part_cog_series_init(void)
{
    mc_cog_series_init(&g_cog_ser, &g_cog);
}

static stat_t parts(fn_t fn, bool adc)
{
    stat_t s = {0};
    for (uint32_t i = 0u; i < PART_CALLS; i++) {
        if (adc) {
            hw_sample(false); /* the encoder stands: the drive's next step sees no jump */
        }
        stat_add(&s, count(fn));
    }
    return s;
}

/* ---- the sensorless law, plugged as the SPEED law ------------------------ */

static int sls_set_ref(void *ctx, float ref)
{
    return (mc_ctrl_sls_set_speed_ref(ctx, ref) == 0u) ? 0 : -EINVAL;
}

/* The law from the board's defaults (the paper-002 motor), gains by the
 * table's derivation (mc_params_resolve, as the image and the simulator
 * derive them: firmware/app/config/mc_gains.h); the divergence monitor wide
 * open, since the bench has no plant (the observer sees synthetic currents). */
static uint32_t sls_setup(const mc_params_t *raw)
{
    mc_ctrl_sls_cfg_t c;
    mc_params_eff_t e;
    const mc_params_t *p = &e.p; /* the derived bandwidths resolved */
    (void)mc_params_resolve(raw, &e);
    memset(&c, 0, sizeof c);
    c.r_ohm = p->r_ohm;
    c.l_h = p->lq_h;
    c.flux_wb = p->flux_wb;
    c.pole_pairs = p->pole_pairs;
    c.dt_s = 1.0f / (float)p->pwm_hz;
    c.pwm_delay_periods = 1u;
    c.speed_div = p->slow_loop_div;
    c.dead_time_s = p->dead_time_s;
    c.dead_band_a = 0.05f;
    c.dead_comp_duty = true;
    c.omega_crit_m_rad_s = 5.0f;
    c.resid_tol = 1e6f;
    c.resid_time_s = 1.0f;
    c.pll_bw_rad_s = p->speed_pll_bw_rad_s;
    c.cur_bw_rad_s = p->current_bw_rad_s;
    c.v_limit_ratio = p->v_limit_ratio;
    c.vbus_max_v = p->vbus_max_v;
    c.speed_kp_a_s_rad = 0.01f;
    c.speed_ki_a_rad = 0.1f;
    c.iq_max_a = 0.8f * p->i_max_a;
    c.speed_slew_rad_s2 = 1000.0f;
    c.speed_max_rad_s = 500.0f;
    c.if_current_a = 2.0f;
    c.align_time_s = 0.05f;
    c.if_accel_rad_s2 = 200.0f;
    c.handover_speed_rad_s = 40.0f;
    c.handover_hyst = 0.3f;
    c.lock_tol = 0.2f;
    c.if_lock_timeout_s = 0.5f;
    c.blend_time_s = 0.05f;
    c.lowspeed_fallback = false;
    c.if_damping = true;
    c.align_any_angle = true;
    return mc_ctrl_sls_init(&g_sls, &c);
}

/* ---- the image's set-up, as main() does it -------------------------------- */

static int image_setup(bool sensorless)
{
    memset(&g_regs, 0, sizeof g_regs);
    const mc_hal_t *hal = bench_board_init(&g_regs);
    if (hal == NULL || hal->can == NULL) {
        return 10;
    }
    mc_app_cfg_t *app_cfg = bench_board_app_cfg();
    if (sensorless) {
        if (sls_setup(app_cfg->defaults) != 0u) {
            return 11;
        }
        /* this bench's own sensorless configuration, not the one the
         * image builds from its parameters (speed_law) */
        app_cfg->laws_from_params = false;
        app_cfg->speed_law.ctrl = mc_ctrl_sls_ops(&g_sls);
        app_cfg->speed_law.set_ref = sls_set_ref;
        app_cfg->speed_law.ctx = &g_sls;
    }
    return (bench_image_start(hal, app_cfg) == 0) ? 0 : 12;
}

/* The hardware node filter (RM0090 32-bit mask mode, bank 0): how many of
 * the 2048 standard ids it passes, and how many of them are this node's. */
static void check_filter(void)
{
    const uint32_t fr1 = g_regs.can.FB[0].FR1;
    const uint32_t fr2 = g_regs.can.FB[0].FR2;
    uint32_t pass = 0u;
    uint32_t own = 0u;
    for (uint32_t id = 0u; id < 2048u; id++) {
        const uint32_t w = id << MC_F405_CAN_IR_STID_SHIFT;
        if ((g_regs.can.FA1R & 1u) != 0u && ((w ^ fr1) & fr2) == 0u) {
            pass++;
            own += (mc_can_id_node(id) == A->params.can_node_id) ? 1u : 0u;
        }
    }
    out_kv("filter_banks_active", g_regs.can.FA1R);
    out_kv("filter_pass_ids", pass);
    out_kv("filter_pass_own_ids", own);
}

/* The sensored run's anticogging cost: the lookup, then RUN_PERIODS
 * interrupts with a map attached and anticogging on (the run's own
 * interrupt, before, has it off: the default). */
static int cog_costs(const char *name)
{
    const mc_cog_ident_t id = {0u, DESC->enc_counts_per_rev, 0u, D->cfg.pole_pairs, 0.0f};
    for (uint32_t k = 0u; k < MC_COG_N; k++) {
        g_cog_i[k] = (0.05f * (float)((k * 37u) % 17u)) - 0.4f;
    }
    if (mc_cog_build(&g_cog, g_cog_i, MC_COG_N, &id, 10.0f, 0u) != MC_COG_ST_OK) {
        return 23;
    }
    stat_t s = parts(part_cog, false);
    out_stat(name, "cog_lookup", &s);
    /* order 12 (12 slots, 2 or 3 pole pairs...): MC_COG_KEEP_MAX terms kept */
    if ((mc_cog_build(&g_cog, g_cog_i, MC_COG_N, &id, 10.0f, 12u) != MC_COG_ST_OK) ||
        (mc_cog_keep_count(12u) != MC_COG_KEEP_MAX)) {
        return 25;
    }
    stat_t one = {0};
    stat_add(&one, count(part_cog_series_init));
    out_stat(name, "cog_series_init", &one);
    s = parts(part_cog_series, false);
    out_stat(name, "cog_series", &s);
    if (mc_drive_attach_cog(D, &g_cog) != 0) {
        return 24;
    }
    D->cfg.anticogging = true;
    memset(&g_isr, 0, sizeof g_isr);
    for (uint32_t k = 0u; k < RUN_PERIODS; k++) {
        if (k % 200u == 7u) {
            send_heartbeat();
        }
        (void)period(true);
    }
    out_stat(name, "isr_anticogging", &g_isr);
    D->cfg.anticogging = false;
    (void)mc_drive_attach_cog(D, NULL);
    return 0;
}

static int run(bool sensorless)
{
    const char *name = sensorless ? "sensorless" : "sensored";
    D = bench_image_drive();
    A = bench_image_app();
    B = bench_board_f405();
    DESC = bench_board_desc();
    const int rc = image_setup(sensorless);
    if (rc != 0) {
        return rc;
    }
    hw_idle_inputs();
    g_temp_v[0] = room_temp_v(&B->adc.cfg.temp_power_stage);
    g_temp_v[1] = room_temp_v(&B->adc.cfg.temp_motor);
    if (!sensorless) {
        check_filter();
    }
    /* The host's commands: SPEED mode, a speed reference, enable. */
    const float mode[1] = {(float)MC_CAN_VAL_CONTROL_MODE_SPEED};
    const float ref[1] = {sensorless ? 100.0f : 20.0f};
    const float on[1] = {1.0f};
    send_heartbeat();
    send_cmd(MC_CAN_MSG_SET_CONTROL_MODE, mode, 1u);
    send_cmd(MC_CAN_MSG_SET_SPEED_REF, ref, 1u);
    for (uint32_t k = 0u; k < WARMUP_PERIODS; k++) {
        if (k == 4u * D->cfg.slow_loop_div) {
            /* after the mode has been handled (and its law attached) */
            send_cmd(MC_CAN_MSG_SET_ENABLE, on, 1u);
        }
        if (k % 200u == 0u) {
            send_heartbeat();
        }
        if (sensorless && g_sls.phase != MC_CTRL_SLS_CLOSED) {
            g_sls.phase = MC_CTRL_SLS_CLOSED; /* the closed loop: see the file comment */
        }
        (void)period(false);
    }
    const mc_drive_mode_t want = MC_DRIVE_MODE_CTRL; /* every speed law */
    if (D->mode != want) {
        out_kv("stop_reason", A->cmd.stop_reason);
        out_kv("last_error", A->cmd.last_error);
        out_kv("last_error_cmd", A->cmd.last_error_cmd);
        out_kv("ctrl_err", D->tm.ctrl_err);
        out_kv("bad_mode", (uint32_t)D->mode);
        out_kv("faults", D->faults);
        return 20;
    }
    memset(&g_rx, 0, sizeof g_rx);
    memset(&g_isr, 0, sizeof g_isr);
    memset(&g_isr_slow, 0, sizeof g_isr_slow);
    memset(&g_slow, 0, sizeof g_slow);
    for (uint32_t k = 0u; k < RUN_PERIODS; k++) {
        if (k % 200u == 7u) {
            send_heartbeat();
        }
        if (k == PROFILE_PERIOD) {
            bench_profile_mark();
            g_profiled = (stat_t){0};
            stat_add(&g_profiled, period(true));
        } else {
            (void)period(true);
        }
    }
    if (D->mode != want || D->faults != 0u || (sensorless && g_sls.phase != MC_CTRL_SLS_CLOSED)) {
        out_kv("bad_mode", (uint32_t)D->mode);
        out_kv("faults", D->faults);
        return 21;
    }
    out_stat(name, "isr", &g_isr);
    out_stat(name, "isr_slow_due", &g_isr_slow);
    out_stat(name, "slow", &g_slow);
    out_stat(name, "can_rx_heartbeat", &g_rx);
    out_stat(name, "isr_profiled_period", &g_profiled);

    /* Parts, each alone on the state the run left. */
    stat_t s = parts(part_adc, true);
    out_stat(name, "adc_read", &s);
    s = parts(part_enc, false);
    out_stat(name, "encoder_read", &s);
    /* every speed law hands its currents to the drive's FOC step */
    g_law_meas = law_meas();
    if (sensorless) {
        g_sls_copy = g_sls;
        s = parts(part_law, false);
    } else {
        g_spd_copy = *(const mc_ctrl_speed_t *)D->ctrl->ctx;
        s = parts(part_speed_law, false);
    }
    out_stat(name, "law", &s);
    g_foc_copy = D->foc;
    s = parts(part_foc, false);
    out_stat(name, "foc", &s);
    s = parts(part_pwm, false);
    out_stat(name, "duties_write", &s);
    s = parts(part_mark, false);
    out_stat(name, "app_mark", &s);
    if (B->hal.brake != NULL) {
        s = parts(part_brake, false);
        out_stat(name, "brake_write", &s);
    }

    /* CAN receive interrupt, one frame per call (parameter reads). */
    stat_t rx = {0};
    const float req[3] = {0.0f, 1.0f, 0.0f}; /* READ, id 1 */
    for (uint32_t k = 0u; k < RX_FRAMES; k++) {
        hw_can_frame(MC_CAN_MSG_PARAM_REQ, req, 3u);
        stat_add(&rx, count(CAN1_RX0_IRQHandler));
        if ((k % MC_APP_RX_PER_STEP) == MC_APP_RX_PER_STEP - 1u) {
            /* drain the ring in the periods of one slow loop */
            for (uint32_t j = 0u; j < D->cfg.slow_loop_div; j++) {
                (void)period(false);
            }
        }
    }
    out_stat(name, "can_rx", &rx);

    /* Slow loop with a full ring: MC_APP_RX_PER_STEP frames (a heartbeat
     * and parameter reads) before every slow step, with the reply
     * limiter's bucket full (as after a quiet quarter second): the most
     * requests one slow step serves. */
    memset(&g_slow, 0, sizeof g_slow);
    for (uint32_t r = 0u; r < SLOW_RUNS; r++) {
        A->cmd.reply.tokens = MC_TM_REPLY_BURST;
        A->cmd.held_have = false;
        send_heartbeat();
        for (uint32_t k = 1u; k < MC_APP_RX_PER_STEP; k++) {
            hw_can_frame(MC_CAN_MSG_PARAM_REQ, req, 3u);
            CAN1_RX0_IRQHandler();
        }
        for (uint32_t j = 0u; j < D->cfg.slow_loop_div; j++) {
            (void)period(true);
        }
    }
    out_stat(name, "slow_full_ring", &g_slow);
    if (!sensorless) {
        const int crc = cog_costs(name);
        if (crc != 0) {
            return crc;
        }
    }
    if (D->mode != want || D->faults != 0u) {
        out_kv("bad_mode", (uint32_t)D->mode);
        out_kv("faults", D->faults);
        return 22;
    }
    return 0;
}

static void tim2_start(void)
{
    TIM2_CR1 = 0u;
    TIM2_PSC = 0u;
    TIM2_ARR = 0xFFFFFFFFu;
    TIM2_EGR = 1u;
    TIM2_CR1 = 1u;
}

int main(void)
{
    __asm__ volatile("cpsid i" ::: "memory"); /* handlers are called, never taken */
    tim2_start();
    /* Overhead: the smallest count of an empty handler (g_overhead 0). */
    g_overhead = 0u;
    uint32_t mn = 0xFFFFFFFFu;
    for (uint32_t i = 0u; i < 16u; ++i) {
        const uint32_t d = count(empty_fn);
        mn = (d < mn) ? d : mn;
    }
    g_overhead = mn;
    if (TIM2_CNT == 0u) {
        mc_sh_write0("bench_isr: TIM2 does not count (run under -icount shift=0)\n");
        return 2;
    }
    out_kv("overhead_instr", g_overhead);
    int rc = run(false);
    if (rc == 0) {
        rc = run(true);
    }
    if (rc != 0) {
        out_kv("error", (uint32_t)rc);
    }
    return rc;
}
