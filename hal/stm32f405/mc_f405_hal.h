/**
 * @file mc_f405_hal.h
 * @brief Register-level HAL for the STM32F405: the capabilities of
 *        hal/hal.h on TIM1, TIM8, ADC1, a timer in encoder mode, bxCAN and
 *        a 32-bit timer as tick counter.
 *
 * Peripheral use (one 3-phase drive or one stepper drive per board):
 *   pwm3     TIM1 centre-aligned, CH1..CH3 + CH1N..CH3N complementary with
 *            hardware dead time, preloaded CCRx, MOE = enable, BKIN = kill.
 *            CH4 (no output) in PWM mode 2 marks the ADC trigger near the
 *            counter peak, where all low-side switches are on.
 *   pwm2     TIM8 centre-aligned, CH1..CH4 one per half-bridge of the dual
 *            H-bridge (CH1/CH2 = bridge a +/-, CH3/CH4 = bridge b +/-). TIM8
 *            has only three complementary pairs, so the low sides are not
 *            driven by CHxN: the gate driver generates them with its own
 *            dead time (PWM-input H-bridge drivers such as DRV8412 class).
 *   adc      ADC1 injected group (ia, ib, [ic], vbus), hardware-triggered by
 *            TIM1 TRGO (= OC4REF) or TIM1 CC4, end-of-injected-conversion
 *            interrupt runs the fast loop; temperatures as software-started
 *            regular conversions. A second axis (ODrive v3.6 M1): pwm3 on
 *            TIM8, its adc on ADC2 triggered by TIM8 CC4 (the three ADCs
 *            share one interrupt: mc_f405_adc_jeoc_pending), the two timers
 *            started half a period apart (mc_f405_pwm3_start_phased).
 *   encoder  TIM2..TIM5 in encoder mode 3 (x4), ARR = counts_per_rev - 1,
 *            index pulse on an EXTI line latching the count
 *            (mc_f405_encoder_index_isr() from its EXTI ISR).
 *   can      bxCAN (CAN1), classic frames, 3 tx mailboxes sent in request
 *            order, rx FIFO 0 (+ an optional software ring filled from the
 *            FIFO 0 interrupt), 32-bit mask filters, automatic bus-off
 *            recovery.
 *   tick     TIM2 or TIM5 (32-bit) free running. (The DWT cycle counter is
 *            not used: it reads 0 under QEMU.)
 *   spi      SPI1..3 master with a GPIO chip select, 16-bit and 32-clock
 *            frames (the gate driver's register interface, an absolute
 *            encoder; hal/spi.h); devices sharing one SPI each restore
 *            their settings.
 *   hall     three GPIO inputs as one 3-bit code (hal/hall.h).
 *   fault    BKIN of TIM1/TIM8 (hardware kill), gate-driver nFAULT and
 *            over-current comparator levels on GPIO, gate-driver enable pin;
 *            gate kill = EGR.BG on both timers + MOE cleared + enable low.
 *
 * Host testing: every driver reaches its registers only through the
 * pointers in its config, so on the host the same code runs against
 * register structs in RAM. Hardware behaviour the RAM cannot show (a flag
 * the hardware sets, a rc_w0 flag the hardware clears) is written by the
 * test into the register file.
 *
 * Not done here (board bring-up, the target port's job): RCC clock enables,
 * GPIO alternate-function muxing of the timer/CAN/ADC pins, NVIC set-up.
 *
 * Conventions: init validates the whole config first and returns -EINVAL
 * (nothing written, *p_drv unchanged) on a bad one; after a successful init
 * `p_drv->dev` is the HAL handle (ctx = p_drv). No heap, no globals. The
 * driver structs contain pointers to themselves: do not copy after init.
 */
#ifndef MC_F405_HAL_H
#define MC_F405_HAL_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/hal.h"
#include "hal/hall.h"
#include "hal/spi.h"
#include "mc_f405_regs.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ======================================================================== */
/* Dead time                                                                */
/* ======================================================================== */

/**
 * Encode a dead time for TIMx_BDTR.DTG (RM0090 §17.4.18) with tDTS = one
 * timer clock (CKD = 00). The dead time is rounded UP to the next
 * representable value (never shorter than asked):
 *   DTG[7]   = 0   : DT = DTG[6:0] x tDTS            (0..127 tDTS)
 *   DTG[7:6] = 10  : DT = (64 + DTG[5:0]) x 2 tDTS   (128..254 tDTS)
 *   DTG[7:5] = 110 : DT = (32 + DTG[4:0]) x 8 tDTS   (256..504 tDTS)
 *   DTG[7:5] = 111 : DT = (32 + DTG[4:0]) x 16 tDTS  (512..1008 tDTS)
 * @param deadtime_ns  requested dead time [ns], > 0
 * @param tim_clk_hz   timer kernel clock [Hz], > 0 (168e6 for TIM1)
 * @param p_dtg        out: DTG[7:0]
 * @param p_actual_ns  out (may be NULL): dead time DTG gives [ns], rounded
 *                     to the nearest ns
 * @return 0; -EINVAL zero/NULL input or more than 1008 tDTS (6 us at
 *         168 MHz): outputs untouched.
 */
int mc_f405_deadtime_encode(uint32_t deadtime_ns, uint32_t tim_clk_hz, uint32_t *p_dtg,
                            uint32_t *p_actual_ns);

/* ======================================================================== */
/* Fault inputs and gate kill                                               */
/* ======================================================================== */

/** One GPIO pin; p_port == NULL means "not wired on this board". */
typedef struct mc_f405_pin {
    mc_f405_gpio_regs_t *p_port;
    uint8_t pin;     /**< 0..15 */
    bool active_low; /**< asserted (or enabled, for an output) at 0 V */
} mc_f405_pin_t;

typedef struct mc_f405_fault_config {
    mc_f405_tim_regs_t *p_tim1;      /**< TIM1 (pwm3) or NULL */
    mc_f405_tim_regs_t *p_tim8;      /**< TIM8 (pwm2) or NULL; one of the
                                          two is required */
    mc_f405_pin_t gate_driver_fault; /**< nFAULT input (optional) */
    mc_f405_pin_t overcurrent;       /**< comparator input (optional) */
    mc_f405_pin_t gate_enable;       /**< gate-driver enable output
                                          (optional) */
    uint32_t bkin_mask;              /**< MC_HAL_FAULT_* inputs wired to the
                                          timers' BKIN (hardware kill) */
    void (*kill_hook)(void *ctx);    /**< called by the gate kill after the
                                          timers' outputs are off (the brake
                                          chopper's off: mc_f405_brake_off), or NULL */
    void *kill_hook_ctx;
} mc_f405_fault_config_t;

typedef struct mc_f405_fault {
    mc_f405_fault_config_t cfg;
    volatile bool killed; /**< gate kill latched (software view) */
    volatile uint32_t latched_mask;
    mc_hal_fault_t dev;
} mc_f405_fault_t;

/**
 * Configure the fault pins (inputs as inputs, gate enable as output, driven
 * to its enabled level) and clear the latches. Timer break configuration
 * (BKE/BKP) belongs to the PWM drivers.
 * @return 0; -EINVAL NULL, no timer, pin > 15, unknown bkin_mask bits.
 */
int mc_f405_fault_init(mc_f405_fault_t *p_drv, const mc_f405_fault_config_t *p_cfg);

/* ======================================================================== */
/* pwm3: TIM1 complementary 3-phase                                          */
/* ======================================================================== */

/**
 * ADC trigger source. TRGO (the default) is the internal OC4REF signal and
 * fires whether or not the outputs are enabled, so the fast loop (and
 * current-offset calibration) keeps running with the bridge off. The CC4
 * event path needs CC4E, and ST application notes and forum reports say a
 * channel-output trigger is also gated by the output enable logic (MOE):
 * with CC4 the ADC may stop while the PWM is disabled.
 */
typedef enum mc_f405_adc_trigger {
    MC_F405_ADC_TRIG_TIM1_TRGO = 0, /**< TRGO = OC4REF (MMS = 111), JEXTSEL 0001 */
    MC_F405_ADC_TRIG_TIM1_CC4 = 1,  /**< CC4 event, JEXTSEL 0000 (sets CC4E) */
    MC_F405_ADC_TRIG_TIM8_CC4 = 2   /**< TIM8 CC4 event, JEXTSEL 1110 (sets
                                         CC4E): the second axis' pwm3 on TIM8.
                                         TIM8's TRGO is not among the injected
                                         triggers (RM0090 §13.6, external
                                         trigger for injected channels: TIM8
                                         offers CC2, CC3 and CC4 only). */
} mc_f405_adc_trigger_t;

/** Which advanced-control timer a pwm3 drives (both on APB2, 168 MHz
 *  timer clock, same register layout): its ADC trigger must be its own.
 *  The register file is reached through p_tim, so on the host the driver
 *  cannot tell the timers apart by address: the config names it. */
typedef enum mc_f405_adv_tim {
    MC_F405_ADV_TIM1 = 0, /**< axis M0 (the default of a zeroed config) */
    MC_F405_ADV_TIM8 = 1  /**< axis M1 of the ODrive v3.6 */
} mc_f405_adv_tim_t;

typedef struct mc_f405_pwm3_config {
    mc_f405_tim_regs_t *p_tim;         /**< TIM1 or TIM8 (tim says which) */
    mc_f405_adv_tim_t tim;             /**< the timer p_tim points to */
    uint32_t tim_clk_hz;               /**< 168e6 (APB2 timer clock) */
    uint32_t pwm_freq_hz;              /**< PWM (carrier) frequency, e.g. 20000 */
    uint32_t deadtime_ns;              /**< see mc_f405_deadtime_encode() */
    uint32_t adc_trigger_lead_ticks;   /**< CCR4 = ARR - lead: ADC trigger this
                                          many counter ticks before the peak,
                                          1 .. ARR - 1 */
    mc_f405_adc_trigger_t adc_trigger; /**< CC4 needs CC4E set */
    bool break_enable;                 /**< BKE: BKIN kills the outputs */
    bool break_active_high;            /**< BKP */
    bool high_side_active_low;         /**< CCxP: inverted high-side gate input */
    bool low_side_active_low;          /**< CCxNP: inverted low-side gate input */
    mc_f405_fault_t *p_fault;          /**< software kill latch to honour, or
                                         NULL (BIF is always honoured) */
} mc_f405_pwm3_config_t;

typedef struct mc_f405_pwm3 {
    mc_f405_pwm3_config_t cfg;
    uint32_t arr;      /**< auto-reload: half period in counter ticks */
    uint32_t psc;      /**< prescaler register value */
    uint32_t bdtr_off; /**< BDTR with MOE clear */
    float period_s;
    float duty_a;
    float duty_b;
    float duty_c;
    mc_hal_pwm3_t dev;
} mc_f405_pwm3_t;

/**
 * Configure TIM1 (or TIM8) and start its counter with the outputs off (MOE =
 * 0), duties MC_HAL_PWM3_DUTY_INIT. Period = 2 (PSC + 1) ARR / tim_clk_hz
 * (centre-aligned mode 1), the smallest PSC that fits ARR in 16 bits.
 * @return 0; -EINVAL NULL, zero clock/frequency, ARR < 100 (too coarse) or
 *         dead time not encodable, lead outside 1..ARR-1, enum out of range,
 *         an ADC trigger of the other timer (a TIM1 trigger on TIM8 or the
 *         TIM8 one on TIM1).
 */
int mc_f405_pwm3_init(mc_f405_pwm3_t *p_drv, const mc_f405_pwm3_config_t *p_cfg);

/**
 * Restart two pwm3 timers (axis M0 on TIM1 and M1 on TIM8) together, the
 * lagging one lag_ticks counter ticks behind the leading one: both counters
 * stopped, an update event on each (prescaler and repetition counters
 * reset, the counter counting up), CNT = lag_ticks on the leader and 0 on
 * the lagger, then both CEN set by two consecutive stores (the lagger
 * starts one or two bus cycles later, a skew of a few ticks). Each axis'
 * ADC trigger (CCR4 = ARR - lead, counting up) then fires lag_ticks apart.
 * Outputs (MOE), duties and the triggers' set-up are not touched; call it
 * with the outputs off, before the ADC interrupts are enabled (the update
 * events load the preloaded duties).
 *
 * Phase chosen for the ODrive v3.6 (board): lag_ticks = ARR - 1, half a
 * PWM period less one tick (both counters start counting up, so ARR - 1 is
 * the largest lag that can be loaded). Each axis samples once per period,
 * near its counter peak; half a period apart, each sample falls near the
 * other bridge's counter valley, where that bridge switches only at duties
 * below the trigger lead, and each fast loop has half a period before the
 * other's conversion ends. (ODrive samples at both counter extremes, TRGO
 * = update with RCR = 2, so it starts TIM1 a quarter period minus 128
 * ticks ahead of TIM8: Firmware/Board/v3/board.cpp start_timers() and
 * Inc/board.h TIM1_INIT_COUNT at commit f9b5419c.)
 * @return 0; -EINVAL NULL, the same timer twice, different PSC or ARR (the
 *         phase would drift), lag_ticks >= ARR (nothing written).
 */
int mc_f405_pwm3_start_phased(mc_f405_pwm3_t *p_lead, mc_f405_pwm3_t *p_lag, uint32_t lag_ticks);

/* ======================================================================== */
/* pwm2: TIM8 dual H-bridge                                                 */
/* ======================================================================== */

typedef struct mc_f405_pwm2_config {
    mc_f405_tim_regs_t *p_tim; /**< TIM8 */
    uint32_t tim_clk_hz;       /**< 168e6 */
    uint32_t pwm_freq_hz;
    bool break_enable;
    bool break_active_high;
    bool outputs_active_low;  /**< CCxP on all four channels */
    mc_f405_fault_t *p_fault; /**< or NULL */
} mc_f405_pwm2_config_t;

typedef struct mc_f405_pwm2 {
    mc_f405_pwm2_config_t cfg;
    uint32_t arr;
    uint32_t psc;
    uint32_t bdtr_off;
    float period_s;
    float duty_a;
    float duty_b;
    mc_hal_pwm2_t dev;
} mc_f405_pwm2_t;

/**
 * Configure TIM8: CH1..CH4 PWM mode 1, centre-aligned, outputs off.
 * Bipolar modulation: leg + duty = (1 + d) / 2, leg - duty = (1 - d) / 2.
 * @return 0; -EINVAL as mc_f405_pwm3_init().
 */
int mc_f405_pwm2_init(mc_f405_pwm2_t *p_drv, const mc_f405_pwm2_config_t *p_cfg);

/* ======================================================================== */
/* adc: ADC1 (or ADC2) injected conversions triggered by TIM1 (or TIM8)     */
/* ======================================================================== */

/** Channel number meaning "not measured on this board". */
#define MC_F405_ADC_CH_NONE 0xFFu
/** Highest ADC1 channel (16 temperature sensor, 17 VREFINT, 18 VBAT). */
#define MC_F405_ADC_CH_MAX 18u

/** Sample time SMPx[2:0] (RM0090 §13.13.4/5) [ADC clock cycles]. */
typedef enum mc_f405_adc_smp {
    MC_F405_ADC_SMP_3 = 0,
    MC_F405_ADC_SMP_15 = 1,
    MC_F405_ADC_SMP_28 = 2,
    MC_F405_ADC_SMP_56 = 3,
    MC_F405_ADC_SMP_84 = 4,
    MC_F405_ADC_SMP_112 = 5,
    MC_F405_ADC_SMP_144 = 6,
    MC_F405_ADC_SMP_480 = 7
} mc_f405_adc_smp_t;

/** One point of a temperature table: ADC pin voltage and temperature. */
typedef struct mc_f405_adc_temp_point {
    float v;
    float t_c;
} mc_f405_adc_temp_point_t;

/** Most points of a temperature table. */
#define MC_F405_ADC_TEMP_TABLE_MAX 64u

/** A temperature sensor on one ADC channel, either
 *  - a cubic in the ADC pin voltage v (n_table = 0):
 *    T = offset_c + slope_c_per_v v + c2_c_per_v2 v^2 + c3_c_per_v3 v^3
 *    (a linear sensor has c2 = c3 = 0), valid for v_min_v <= v <= v_max_v;
 *  - or a table (n_table >= 2 points, v strictly increasing), linearly
 *    interpolated, valid from the first to the last point's voltage (a
 *    thermistor network: points spaced in temperature follow its curve
 *    where it is steep); the cubic and window fields are then unused.
 *  Outside the valid window: open or short circuit. */
typedef struct mc_f405_adc_temp_sensor {
    uint8_t channel; /**< ADC channel or MC_F405_ADC_CH_NONE */
    float offset_c;
    float slope_c_per_v;
    float v_min_v;
    float v_max_v;
    float c2_c_per_v2;
    float c3_c_per_v3;
    const mc_f405_adc_temp_point_t *p_table; /**< or NULL */
    uint32_t n_table;                        /**< 0 (cubic) or 2 .. MC_F405_ADC_TEMP_TABLE_MAX */
} mc_f405_adc_temp_sensor_t;

typedef struct mc_f405_adc_config {
    mc_f405_adc_regs_t *p_adc;           /**< ADC1 (ADC2 for a second axis) */
    mc_f405_adc_common_regs_t *p_common; /**< ADC common registers */
    const mc_hal_tick_t *p_tick;         /**< timestamps; NULL: 0 */
    uint8_t ch_ia;                       /**< channel of phase a amplifier,
                                                or MC_F405_ADC_CH_NONE when
                                                phases b and c are measured */
    uint8_t ch_ib;
    uint8_t ch_ic; /**< or MC_F405_ADC_CH_NONE (2 shunts
                                                on a and b) */
    uint8_t ch_vbus;
    mc_f405_adc_smp_t smp_current;
    mc_f405_adc_smp_t smp_vbus;
    mc_f405_adc_smp_t smp_temp;
    mc_f405_adc_trigger_t trigger; /**< must match pwm3's config */
    uint8_t clk_div;               /**< ADCPRE: 2, 4, 6 or 8 */
    bool jeoc_irq;                 /**< JEOCIE: fast loop in the ADC ISR */
    float vref_v;                  /**< ADC reference (0, 3.6] V */
    float shunt_ohm;               /**< > 0 */
    float amp_gain_v_per_v;        /**< current amplifier gain, != 0;
                                                negative when a positive
                                                (inverter -> motor) current
                                                lowers the amplifier output */
    float ia_offset_v;             /**< amplifier output at 0 A [V] */
    float ib_offset_v;
    float ic_offset_v;
    float vbus_divider;          /**< Vbus / ADC pin voltage, >= 1 */
    uint16_t rail_margin_counts; /**< raw <= margin or >= 4095 -
                                                margin: channel invalid */
    mc_f405_adc_temp_sensor_t temp_power_stage;
    mc_f405_adc_temp_sensor_t temp_motor;
} mc_f405_adc_config_t;

typedef struct mc_f405_adc {
    mc_f405_adc_config_t cfg;
    uint32_t n_inj;            /**< injected conversions (3 or 4) */
    uint32_t n_phase;          /**< measured phases (2 or 3) */
    uint32_t phase_of_rank[3]; /**< phase index (0 a, 1 b, 2 c) of JDR k */
    bool derive_ia;            /**< b and c measured: ia = -(ib + ic) */
    uint32_t rank_vbus;        /**< JDR index of vbus */
    float a_per_count[3];      /**< current scale per phase [A/count] */
    float offset_counts[3];    /**< zero-current raw value per phase */
    float v_per_count;         /**< ADC pin volts per count */
    uint32_t seq;
    uint32_t temp_slot; /**< 0 power stage, 1 motor: conversion running */
    bool temp_running;
    mc_hal_adc_temp_t temp;
    mc_hal_adc_t dev;
} mc_f405_adc_t;

/**
 * Configure ADC1: 12-bit, scan, injected sequence of the measured phase
 * currents in phase order (a, b, [c], or b, c) then vbus, on the TIM1
 * trigger (rising edge), sample times, ADC clock divider; power on.
 *
 * Phases measured: a and b (ic from the drive, ia + ib + ic = 0), a, b and
 * c, or b and c (ODrive v3.6). With b and c the driver reports ia as
 * -(ib + ic), valid when both are, so the sample always carries ia and ib
 * (what the drive requires) and the measured ic.
 * @return 0; -EINVAL NULL pointer, channel > 18 (or NONE where required:
 *         ib and vbus always, ic when ia is NONE), enum out of range,
 *         clk_div not 2/4/6/8, non-finite or out-of-range analog parameter.
 */
int mc_f405_adc_init(mc_f405_adc_t *p_drv, const mc_f405_adc_config_t *p_cfg);

/**
 * ADC1, ADC2 and ADC3 share one interrupt (ADC_IRQn, 18): the dual-axis
 * ISR asks each axis' driver whether its injected sequence ended. True when
 * JEOC is set with JEOCIE enabled (this driver raised the interrupt); the
 * flag is left set (adc_read clears it). NULL: false.
 */
bool mc_f405_adc_jeoc_pending(const mc_f405_adc_t *p_drv);

/* ======================================================================== */
/* encoder: TIMx encoder mode                                                */
/* ======================================================================== */

/**
 * The encoder's index pulse on a GPIO pin through EXTI (RM0090 §12.2): the
 * pin's EXTI line (= pin number) is routed to its port by SYSCFG_EXTICR,
 * triggered on one edge, its interrupt unmasked. The EXTI interrupt
 * (mc_f405_exti_irq(pin): EXTI0..4, EXTI9_5 or EXTI15_10) calls
 * mc_f405_encoder_index_isr(), which latches the counter at the first
 * index after init or a re-arm and masks the line. From then on the driver
 * reports the count relative to that latch, (CNT - index_count) mod cpr,
 * with MC_HAL_ENCODER_FLAG_INDEX: count 0 is the index. The counter itself
 * is never written (a software write of CNT would lose the edges counted
 * between the index and the write). The latch is read in the ISR, so it
 * lags the edge by the interrupt's latency: at most (latency x count
 * rate) counts, e.g. 0.2 us at 8192 counts/rev and 50 rev/s = 0.08 counts
 * with the index interrupt at the highest priority (see the board
 * binding).
 */
typedef struct mc_f405_encoder_index {
    mc_f405_exti_regs_t *p_exti;     /**< EXTI, or NULL: no index input */
    mc_f405_syscfg_regs_t *p_syscfg; /**< SYSCFG (EXTICR); required with p_exti */
    uint8_t port;                    /**< the pin's port, 0 = A .. 8 = I */
    uint8_t pin;                     /**< 0..15, also its EXTI line */
    bool falling_edge;               /**< trigger on the falling edge (else rising:
                                          ODrive v3.6 and VESC 6, a high pulse) */
} mc_f405_encoder_index_t;

typedef struct mc_f405_encoder_config {
    mc_f405_tim_regs_t *p_tim;     /**< TIM3/TIM4 (16 bit) or TIM2/TIM5 */
    uint32_t counts_per_rev;       /**< x4 counts, 1 .. 65536 (16-bit timer)
                                          or 1 .. 2^32-1 with counter_32bit */
    bool counter_32bit;            /**< p_tim is TIM2 or TIM5 */
    uint8_t input_filter;          /**< ICxF 0..15 on TI1 and TI2 */
    bool invert;                   /**< count the other way (CC1P) */
    const mc_hal_tick_t *p_tick;   /**< timestamps; NULL: 0 */
    mc_f405_encoder_index_t index; /**< index input; p_exti NULL: none */
} mc_f405_encoder_config_t;

typedef struct mc_f405_encoder {
    mc_f405_encoder_config_t cfg;
    volatile bool index_seen;       /**< the index has been latched */
    volatile uint32_t index_count;  /**< CNT at the index (raw, relative to init) */
    volatile uint32_t index_events; /**< index interrupts handled since init */
    mc_hal_encoder_t dev;
} mc_f405_encoder_t;

/**
 * Configure the timer (encoder mode 3, ARR = cpr - 1, CNT = 0, counting)
 * and, with cfg.index.p_exti, the index line: IMR masked while EXTICR
 * (port), RTSR/FTSR (the edge; the other edge cleared) and PR (a stale
 * pending bit cleared) are written, then unmasked. EMR is left alone.
 * @return 0; -EINVAL NULL, counts_per_rev out of range, filter > 15, an
 *         index with no SYSCFG, port > 8 or pin > 15 (nothing written).
 */
int mc_f405_encoder_init(mc_f405_encoder_t *p_drv, const mc_f405_encoder_config_t *p_cfg);

/**
 * EXTI interrupt body (ISR context; several lines may share the vector):
 * when the index line is pending, clears it (PR, write 1) and, at the first
 * index since init or re-arm, latches CNT into index_count, sets index_seen
 * and masks the line (the index is found; later pulses raise no
 * interrupt). @return true when the index line was pending (handled).
 */
bool mc_f405_encoder_index_isr(mc_f405_encoder_t *p_drv);

/**
 * Forget the index and wait for the next one (a new index search): the
 * count is reported relative to power-up again until it is latched anew.
 * @return 0; -EINVAL NULL or no index configured.
 */
int mc_f405_encoder_index_rearm(mc_f405_encoder_t *p_drv);

/**
 * NVIC interrupt number of EXTI line 0..15 (RM0090 table 61): lines 0..4
 * have their own (6..10), 5..9 share EXTI9_5 (23), 10..15 EXTI15_10 (40).
 * @return the IRQ number, or 0xFFFFFFFF for a line above 15.
 */
uint32_t mc_f405_exti_irq(uint32_t line);

/* ======================================================================== */
/* hall: three GPIO inputs                                                   */
/* ======================================================================== */

typedef struct mc_f405_hall_config {
    mc_f405_pin_t pin[3]; /**< sensors A, B, C (code bits 0, 1, 2); active_low
                               inverts a pin (an inverting input stage) */
} mc_f405_hall_config_t;

typedef struct mc_f405_hall {
    mc_f405_hall_config_t cfg;
    mc_hal_hall_t dev;
} mc_f405_hall_t;

/**
 * The Hall inputs read from their ports' IDR (the pins' mode, pulls and
 * filter are the board's GPIO set-up). Reading IDR has no side effect.
 * @return 0; -EINVAL NULL, a pin without a port or above 15.
 */
int mc_f405_hall_init(mc_f405_hall_t *p_drv, const mc_f405_hall_config_t *p_cfg);

/* ======================================================================== */
/* spi: SPI1..3 master, one device on a GPIO chip select                     */
/* ======================================================================== */

/** Status-flag polls before a transfer gives up (-EIO). A 16-bit frame at
 *  the slowest setting (PCLK / 256, 42 MHz APB1) lasts about 100 us; one
 *  poll is at least one APB clock (24 ns), so 20000 polls cover it. */
#define MC_F405_SPI_POLLS 20000u
/** SR reads after the chip select is released: at least one APB clock each
 *  (24 ns at 42 MHz), so 64 reads keep the chip select high for at least
 *  1.5 us between frames (the ODrive firmware waits 1 us after each DRV8301
 *  frame). */
#define MC_F405_SPI_CS_GAP_READS 64u

typedef struct mc_f405_spi_config {
    mc_f405_spi_regs_t *p_spi; /**< SPI1, SPI2 or SPI3 */
    uint32_t pclk_hz;          /**< its APB clock: 84e6 (SPI1), 42e6 (SPI2/3) */
    uint32_t max_sck_hz;       /**< fastest SCK the device allows: the
                                      driver takes the smallest divider
                                      2, 4, .. 256 that stays at or below it */
    uint8_t mode;              /**< SPI mode 0..3: CPOL = bit 1, CPHA = bit 0 */
    mc_f405_pin_t cs;          /**< chip select (output; active_low as the
                                      device wants); required */
    uint32_t cs_gap_reads;     /**< SR reads with the chip select released
                                      after a frame (its high time before
                                      the next one); 0: MC_F405_SPI_CS_GAP_READS
                                      (the DRV8301's 1.5 us) */
} mc_f405_spi_config_t;

typedef struct mc_f405_spi {
    mc_f405_spi_config_t cfg;
    uint32_t cr1;    /**< CR1 with SPE */
    uint32_t sck_hz; /**< SCK frequency the divider gives */
    mc_hal_spi_t dev;
} mc_f405_spi_t;

/**
 * Master, 16-bit frames, MSB first, software chip select (SSM = SSI = 1),
 * full duplex, no CRC; chip select driven to its released level and made an
 * output; then SPE. Pin alternate functions (SCK, MISO, MOSI) and the
 * peripheral clock are the board's.
 *
 * Devices sharing one SPI (the ODrive v3.6's SPI3: two DRV8301 and an
 * absolute encoder, each with its own mode and bit rate): one driver per
 * device on the same registers. A transfer that finds CR1 set for another
 * device rewrites it with SPE clear, then with SPE (RM0090 §28.3.3: BR,
 * CPOL and CPHA change only while the SPI is disabled; the previous frame
 * has ended, BSY clear). The transfers must never overlap (hal/spisched).
 * transfer32 (hal/spi.h) shifts two 16-bit words under one chip select.
 * @return 0; -EINVAL NULL, zero clock, mode > 3, no chip-select pin or pin
 *         > 15, max_sck_hz below PCLK / 256 (nothing written).
 */
int mc_f405_spi_init(mc_f405_spi_t *p_drv, const mc_f405_spi_config_t *p_cfg);

/* ======================================================================== */
/* tick: 32-bit timer                                                        */
/* ======================================================================== */

typedef struct mc_f405_tick_config {
    mc_f405_tim_regs_t *p_tim; /**< TIM2 or TIM5 (32-bit counter) */
    uint32_t tim_clk_hz;       /**< 84e6 (APB1 timer clock) */
    uint32_t prescaler;        /**< PSC: tick = tim_clk_hz / (PSC + 1) */
} mc_f405_tick_config_t;

typedef struct mc_f405_tick {
    mc_f405_tick_config_t cfg;
    uint32_t freq_hz;
    mc_hal_tick_t dev;
} mc_f405_tick_t;

/** @return 0; -EINVAL NULL, zero clock, prescaler > 0xFFFF. */
int mc_f405_tick_init(mc_f405_tick_t *p_drv, const mc_f405_tick_config_t *p_cfg);

/* ======================================================================== */
/* can: bxCAN                                                               */
/* ======================================================================== */

/** Software rx ring length [frames] (used with rx_irq). */
#define MC_F405_CAN_RX_RING_LEN 16u
/** Polls of MSR.INAK before init gives up (-EIO). */
#define MC_F405_CAN_INIT_POLLS 100000u

/** Accept a frame when (frame id & mask) == (id & mask), same id type. */
typedef struct mc_f405_can_filter {
    uint32_t id;
    uint32_t mask;
    bool ext; /**< 29-bit identifiers (else 11-bit) */
} mc_f405_can_filter_t;

typedef struct mc_f405_can_config {
    mc_f405_can_regs_t *p_can;             /**< CAN1 (owns the filter banks) */
    uint32_t pclk_hz;                      /**< APB1 clock, 42e6 */
    uint32_t bitrate_bps;                  /**< e.g. 500000, 1000000 */
    uint16_t sample_point_permille;        /**< wanted sample point, 500..950 */
    uint8_t sjw_tq;                        /**< resync jump width 1..4 tq */
    bool auto_bus_off_recovery;            /**< ABOM */
    bool no_auto_retransmit;               /**< NART */
    const mc_f405_can_filter_t *p_filters; /**< NULL/0: accept every frame */
    uint8_t n_filters;                     /**< 0 .. 28 - filter_bank_start */
    uint8_t filter_bank_start;             /**< first bank (0 for CAN1) */
    bool rx_irq;                           /**< FIFO 0 drained by
                                           mc_f405_can_rx_isr(); receive
                                           then only pops the ring */
    const mc_hal_tick_t *p_tick;           /**< rx timestamps; NULL: 0 */
} mc_f405_can_config_t;

typedef struct mc_f405_can {
    mc_f405_can_config_t cfg;
    uint32_t btr;
    mc_hal_can_frame_t ring[MC_F405_CAN_RX_RING_LEN];
    volatile uint32_t ring_head; /**< written by the consumer only */
    volatile uint32_t ring_tail; /**< written by the producer only */
    volatile uint32_t rx_overrun_count;
    mc_hal_can_t dev;
} mc_f405_can_t;

/**
 * Bit timing register value for a bit rate (RM0090 §32.7.7):
 * bit = (1 + BS1 + BS2) tq, tq = (BRP + 1) / pclk. Searches the prescalers
 * that give an exact bit rate with 8..25 tq per bit, BS1 1..16, BS2 1..8,
 * SJW <= BS2, and keeps the one whose sample point (1 + BS1) / N is nearest
 * to sample_point_permille (on a tie the one with more tq).
 * @return 0 and *p_btr; -EINVAL no exact setting or bad argument.
 */
int mc_f405_can_bit_timing(uint32_t pclk_hz, uint32_t bitrate_bps, uint16_t sample_point_permille,
                           uint8_t sjw_tq, uint32_t *p_btr);

/**
 * Enter initialisation mode (wait for MSR.INAK), program BTR, filters (32-bit
 * mask mode, FIFO 0), MCR options (TXFP: frames leave in request order),
 * then request normal mode (not waited for: it needs 11 recessive bits).
 * @return 0; -EINVAL bad config (nothing written); -EIO INAK never set.
 */
int mc_f405_can_init(mc_f405_can_t *p_drv, const mc_f405_can_config_t *p_cfg);

/**
 * Replace the acceptance filters at run time (the application's node filter,
 * known only once the configuration is loaded): FMR.FINIT while the banks
 * are written (reception pauses for those few writes), the banks of the old
 * set deactivated, the new ones programmed as at init. p_filters must
 * outlive the driver. @return 0; -EINVAL (nothing written) as at init.
 */
int mc_f405_can_set_filters(mc_f405_can_t *p_drv, const mc_f405_can_filter_t *p_filters,
                            uint8_t n_filters);

/** CAN1 RX0 ISR body (rx_irq mode): move FIFO 0 into the ring. */
void mc_f405_can_rx_isr(mc_f405_can_t *p_drv);

/** All three transmit mailboxes empty: every frame queued has left (or
 *  was aborted). A board waits for it before a reset. */
bool mc_f405_can_tx_idle(const mc_f405_can_t *p_drv);

#ifdef __cplusplus
}
#endif

#endif /* MC_F405_HAL_H */
