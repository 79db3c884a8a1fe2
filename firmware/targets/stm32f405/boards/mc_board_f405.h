/**
 * @file mc_board_f405.h
 * @brief A board description (mc_board_desc.h) bound to the hal/stm32f405
 *        drivers: clocks, GPIO, TIM1 PWM, TIM5 tick, fault pins, ADC1,
 *        TIM3 encoder, CAN1, SPI3 and the DRV8301.
 *
 * Every register is reached through mc_board_f405_periph_t, so the same
 * set-up runs on the MCU (peripheral addresses) and on the host against
 * register files in RAM (tests/target/boards).
 *
 * Order (gate driver boards): clocks; GPIO from the table (EN_GATE low,
 * chip selects released, unused gate inputs low); tick; PWM (outputs off,
 * MOE = 0); EN_GATE low for at least 40 us (the DRV8301's full reset needs
 * 20 us, ODrive board.cpp); EN_GATE high (the fault driver's enabled
 * level); 20 ms for the chip's SPI to come up (ODrive waits 20 ms, its
 * drv8301.cpp names t_spi_ready <= 10 ms); ADC, encoder, CAN, SPI. The
 * DRV8301 registers are then written and verified by
 * mc_board_f405_gate_driver_setup() over an SPI handle (the SPI3 driver on
 * the MCU, a model of the chip in the tests).
 *
 * Position sensor (desc enc_type; the drive reads hal.encoder):
 *   abi      TIM3 encoder; with an enc_z pin its index on EXTI (SYSCFG
 *            clock on, EXTICR, rising edge): the board's EXTI interrupt
 *            calls mc_f405_encoder_index_isr(&enc) (mc_board_f405_exti_irq
 *            names the IRQ to enable);
 *   as5047p, an absolute encoder on SPI3 (its own device: enc_spi, chip
 *   ma732    select enc_spi_cs, the chip's mode and rate; the MA732 in
 *            32-clock frames with parity), probed at set-up, read by the
 *            drive's fast step (hal.encoder = the chip driver's). The
 *            DRV8301 on the same bus goes through the schedule (sched):
 *            hand sched.dev to mc_board_f405_gate_driver_setup and _supervise,
 *            call mc_board_f405_fast_slot() once per fast period outside the
 *            drive's step, and mc_spisched_defer(&sched) before the fast loop
 *            starts;
 *   hall     the Hall GPIO table over the encoder's pins; the inputs as
 *            mc_f405_hall (hall.dev); hal.encoder NULL here: the image binds
 *            hall.dev as mc_app_cfg_t.hall, and the application makes the
 *            Hall kernel on it the drive's encoder (encoder_type 1, the
 *            board's default: firmware/app/drive/mc_drive_hall.h).
 *
 * Brake chopper (desc has_brake): TIM2 on the description's channels,
 * period and dead time (mc_f405_brake.h), set up with both switches off
 * before the fault driver, whose gate kill turns it off again (kill hook);
 * hal.brake = brake.dev. Without one hal.brake is NULL and TIM2 untouched.
 */
#ifndef MC_BOARD_F405_H
#define MC_BOARD_F405_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/hal.h"
#include "hal/hall.h"
#include "mc_as5047p.h"
#include "mc_board_desc.h"
#include "mc_f405_brake.h"
#include "mc_ma732.h"
#include "mc_spisched.h"

#ifdef __cplusplus
extern "C" {
#endif

/** DRV8301 reset pulse on EN_GATE [us] and its SPI start-up wait [us]. */
#define MC_BOARD_F405_GATE_RESET_US   40u
#define MC_BOARD_F405_GATE_STARTUP_US 20000u

/** RCC enable bits the set-up writes (RM0090 §7.3.10, §7.3.13, §7.3.14). */
#define MC_BOARD_F405_APB1ENR_TIM2EN   (1u << 0)
#define MC_BOARD_F405_APB1ENR_TIM3EN   (1u << 1)
#define MC_BOARD_F405_APB1ENR_TIM5EN   (1u << 3)
#define MC_BOARD_F405_APB1ENR_SPI3EN   (1u << 15)
#define MC_BOARD_F405_APB1ENR_CAN1EN   (1u << 25)
#define MC_BOARD_F405_APB2ENR_TIM1EN   (1u << 0)
#define MC_BOARD_F405_APB2ENR_ADC1EN   (1u << 8)
#define MC_BOARD_F405_APB2ENR_SYSCFGEN (1u << 14)

/** An absolute encoder on SPI3: the chip's SCK limit and mode
 *  (mc_as5047p.h, mc_ma732.h; 42 MHz APB1 / 8 = 5.25 MHz for the AS5047P's
 *  10 MHz, / 2 = 21 MHz for the MA732's 25 MHz), its chip-select high time
 *  (16 SR reads >= 380 ns, the AS5047P needs 350 ns), bad reads in a row
 *  that fault the drive and the diagnostic period [reads]. */
#define MC_BOARD_F405_SPIENC_CS_GAP_READS 16u
#define MC_BOARD_F405_SPIENC_BAD_READS    MC_SPIENC_BAD_READS_DEFAULT
#define MC_BOARD_F405_SPIENC_DIAG_PERIOD  1000u

typedef struct mc_board_f405_periph {
    mc_f405_gpio_regs_t *p_gpio[MC_F405_GPIO_PORTS]; /**< A..I */
    volatile uint32_t *p_rcc_ahb1enr;
    volatile uint32_t *p_rcc_apb1enr;
    volatile uint32_t *p_rcc_apb2enr;
    mc_f405_tim_regs_t *p_tim1;
    mc_f405_tim_regs_t *p_tim2; /**< the brake chopper (boards with one) */
    mc_f405_tim_regs_t *p_tim3;
    mc_f405_tim_regs_t *p_tim5;
    mc_f405_adc_regs_t *p_adc1;
    mc_f405_adc_common_regs_t *p_adc_common;
    mc_f405_can_regs_t *p_can1;
    mc_f405_spi_regs_t *p_spi3;
    mc_f405_syscfg_regs_t *p_syscfg; /**< the index's EXTI routing (boards with enc_z) */
    mc_f405_exti_regs_t *p_exti;
    /** Busy wait of at least `us` microseconds (the tick driver on the MCU). */
    void (*delay_us)(void *ctx, uint32_t us);
    void *delay_ctx;
} mc_board_f405_periph_t;

/** Why a set-up failed (kept in mc_board_f405_t.err for the debugger and
 *  the bring-up guide). */
typedef enum mc_board_f405_err {
    MC_BOARD_F405_OK = 0,
    MC_BOARD_F405_ERR_ARG, /**< NULL description or peripheral */
    MC_BOARD_F405_ERR_TICK,
    MC_BOARD_F405_ERR_PWM,
    MC_BOARD_F405_ERR_FAULT,
    MC_BOARD_F405_ERR_ADC,
    MC_BOARD_F405_ERR_ENCODER,
    MC_BOARD_F405_ERR_SPI,
    MC_BOARD_F405_ERR_GATE_DRIVER, /**< DRV8301 set-up failed: drv.status says why */
    MC_BOARD_F405_ERR_CAN_BITRATE, /**< CAN bit rate not 125k, 250k, 500k or 1M
                                        bit/s, or not exact on the APB1 clock */
    MC_BOARD_F405_ERR_SPIENC,      /**< the absolute encoder the board names does
                                        not answer as it should (enc_probe_rc) */
    MC_BOARD_F405_ERR_HALL,        /**< the Hall inputs could not be set up */
    MC_BOARD_F405_ERR_BRAKE        /**< the brake chopper's timer description
                                        is out of range */
} mc_board_f405_err_t;

typedef struct mc_board_f405 {
    mc_f405_tick_t tick;
    mc_f405_pwm3_t pwm3;
    mc_f405_fault_t fault;
    mc_f405_adc_t adc;
    mc_f405_encoder_t enc;
    mc_f405_can_t can;
    mc_f405_spi_t spi;
    mc_drv8301_t drv;
    mc_spisched_t sched;   /**< SPI3 shared by the fast loop (encoder) and the
                              slow loop (DRV8301): hand sched.dev, not
                              spi.dev, to the gate-driver calls */
    mc_f405_spi_t enc_spi; /**< the absolute encoder's device on SPI3 */
    mc_as5047p_t as5047p;
    mc_ma732_t ma732;
    int enc_probe_rc;      /**< the absolute encoder's probe (0 ok) */
    mc_f405_hall_t hall;   /**< the Hall inputs (enc_type hall) */
    mc_f405_brake_t brake; /**< TIM2 brake chopper (has_brake) */
    mc_hal_t hal;
    bool can_ok; /**< CAN left init mode (else hal.can NULL) */
    mc_board_f405_err_t err;
    /* Gate-driver supervision (mc_board_f405_gate_driver_supervise). */
    volatile bool drv_ready; /**< the DRV8301 holds its set-up (always true
                                       on a board without one) */
    uint32_t rearm_wait_us;  /**< time since the gates were released */
    bool nfault_seen;        /**< nFAULT asserted at the last call */
    bool drv_latch_reset;    /**< GATE_RESET sent for this assertion */
} mc_board_f405_t;

/**
 * Configure clocks, pins and drivers for a board. Timer clocks from
 * sysclk_hz (APB2 timers = sysclk, APB1 timers = sysclk / 2, APB1 =
 * sysclk / 4; RM0090 §6.2 with the clock set-up's prescalers).
 * @return MC_BOARD_F405_OK and p_board->hal filled (gate driver not yet set
 *         up), or the failing step (p_board->err); the gate enable is then
 *         left at its disabled level where the fault driver did not run.
 */
mc_board_f405_err_t mc_board_f405_setup(mc_board_f405_t *p_board, const mc_board_desc_t *p_desc,
                                        const mc_board_f405_periph_t *p_periph, uint32_t sysclk_hz,
                                        uint32_t pwm_hz);

/**
 * Write and verify the DRV8301 registers over `p_spi` (no-op on a board
 * without one). On failure the gates are killed (mc_hal_fault_gate_kill:
 * PWM outputs off, EN_GATE low) and p_board->drv.status names the reason.
 */
mc_board_f405_err_t mc_board_f405_gate_driver_setup(mc_board_f405_t *p_board,
                                                    const mc_board_desc_t *p_desc,
                                                    const mc_hal_spi_t *p_spi);

/**
 * Gate-driver supervision, from the slow loop every period_us (a few SPI
 * frames when something happens, nothing otherwise):
 *  - gates killed: EN_GATE low resets the DRV8301, its settings are lost:
 *    not ready;
 *  - released again (EN_GATE high): after MC_BOARD_F405_GATE_STARTUP_US the
 *    DRV8301 is set up and verified again; if that fails the gates are
 *    killed again (drv.status names why);
 *  - nFAULT newly asserted: the status registers are read (drv.faults,
 *    mc_drv8301_fault_name); once the drive has recorded its hardware-input
 *    fault (drive_hw_fault) the chip's latch is reset (GATE_RESET, once per
 *    assertion), so that clearing the drive's fault can then succeed. The
 *    drive stays stopped until it is cleared.
 * The caller keeps the drive from running while this returns false (the
 * image raises an external fault).
 * @return p_board->drv_ready.
 */
bool mc_board_f405_gate_driver_supervise(mc_board_f405_t *p_board, const mc_board_desc_t *p_desc,
                                         const mc_hal_spi_t *p_spi, uint32_t period_us,
                                         bool drive_hw_fault);

/**
 * Re-program the CAN controller for bitrate_bps (the configuration's
 * can_bitrate_bps, after boot): 125000, 250000, 500000 or 1000000, the bit
 * timing (BTR) computed from the APB1 clock of the set-up (sysclk / 4) by
 * mc_f405_can_bit_timing at the board's sample point. Another rate, or one
 * the clock cannot time exactly, is refused with
 * MC_BOARD_F405_ERR_CAN_BITRATE and nothing is written (the controller
 * keeps its rate). On a board whose CAN did not start, MC_BOARD_F405_OK and
 * nothing done. If the controller does not re-enter init mode, CAN is
 * turned off (can_ok false, hal.can NULL), as at set-up.
 */
mc_board_f405_err_t mc_board_f405_can_set_bitrate(mc_board_f405_t *p_board, uint32_t bitrate_bps);

/** Fast loop, once per period (the ADC interrupt, outside the drive's
 *  step): a slow-loop frame for the DRV8301, if one waits (mc_spisched.h).
 *  @return true when one ran. */
bool mc_board_f405_fast_slot(mc_board_f405_t *p_board);

/** NVIC interrupt of the board's index line (mc_f405_exti_irq of its pin),
 *  or 0xFFFFFFFF when it has none. */
uint32_t mc_board_f405_exti_irq(const mc_board_desc_t *p_desc);

/**
 * The ADC driver's configuration of one axis from the board's description:
 * the description's channels, amplifier, bus divider and temperature
 * sensors, and what every axis shares (the sample times, the ADC clock:
 * ADCPRE is one field of the common registers). The set-up uses it for M0
 * (ADC1 on TIM1 TRGO); the ODrive's M1 (mc_board_f405_m1.c) for ADC2 on
 * TIM8 CC4, then sets its own channels.
 */
void mc_board_f405_adc_config(const mc_board_desc_t *p_desc, mc_f405_adc_regs_t *p_adc,
                              mc_f405_adc_common_regs_t *p_common, const mc_hal_tick_t *p_tick,
                              mc_f405_adc_trigger_t trigger, mc_f405_adc_config_t *p_cfg);

/** Name of a set-up result ("ok", "gate driver", ...). */
const char *mc_board_f405_err_name(mc_board_f405_err_t err);

#ifdef __cplusplus
}
#endif

#endif /* MC_BOARD_F405_H */
