/**
 * @file hal.h
 * @brief The drive's hardware abstraction layer: one board = one mc_hal_t.
 *
 * The drive (firmware/app) reaches hardware only through these headers. Each
 * capability is an ops table plus a context pointer (Zephyr style), so the
 * STM32F405 register drivers (hal/stm32f405), the simulator binding
 * (hal/host) and the test fake (hal/fake) each supply one in the same build:
 *
 *   capability      header            handle type
 *   ADC sampling    "hal/adc.h"       mc_hal_adc_t
 *   3-phase PWM     "hal/pwm3.h"      mc_hal_pwm3_t
 *   2-phase PWM     "hal/pwm2.h"      mc_hal_pwm2_t      (dual H-bridge)
 *   position        "hal/encoder.h"   mc_hal_encoder_t
 *   CAN             "hal/can.h"       mc_hal_can_t
 *   tick counter    "hal/tick.h"      mc_hal_tick_t
 *   fault/gate kill "hal/fault.h"     mc_hal_fault_t
 *   flash store     "hal/flash.h"     mc_hal_flash_t     (not in mc_hal_t: the
 *                                                        configuration store
 *                                                        takes it directly)
 *   brake chopper   "hal/brake.h"     mc_hal_brake_t     (optional)
 *   SPI device      "hal/spi.h"       mc_hal_spi_t       (not in mc_hal_t: a
 *                                                        board's gate-driver
 *                                                        set-up takes it)
 *
 * Conventions shared by every capability
 * - A handle is `{ const ops *ops; void *ctx; }`. The ops table is const
 *   (lives in flash on the MCU); ctx points at the implementation's own
 *   statically allocated state. No heap anywhere.
 * - Call a capability through its static inline wrapper
 *   (`mc_hal_<capability>_<verb>(handle, ...)`). The wrapper returns -ENODEV
 *   when the handle, its ops table or the op is NULL (capability absent on
 *   this board), and -EINVAL when a required pointer argument is NULL;
 *   otherwise it calls the op once.
 * - Every call returns 0 on success or a negative errno value from
 *   <errno.h>:
 *     -EINVAL   bad argument (NaN, out of range, bad frame); nothing changed
 *     -EAGAIN   nothing available right now (no new sample, rx empty)
 *     -EIO      hardware fault (peripheral does not respond, conversion error)
 *     -ENODEV   capability not present
 *     -EBUSY    refused in the present state (e.g. enable while gate-killed)
 *     -ENOBUFS  transmit queue full
 *     -ENETDOWN CAN controller is bus-off
 *     -ENOTSUP  feature not supported by this implementation (e.g. CAN FD)
 *   A call that returns an error has no effect on the hardware and leaves
 *   its output arguments untouched, unless its documentation says otherwise.
 * - Physical units are in every field name (_a, _v, _s, _hz, _c, _ticks).
 * - Timing classes used in the per-call documentation:
 *     FAST  callable from the fast-loop ISR (PWM rate, 10..40 kHz); bounded,
 *           never blocks, no locks; budget about 1 us on a 168 MHz M4F
 *           (a few register accesses).
 *     SLOW  slow loop / thread context (about 1 kHz); never blocks either,
 *           budget about 10 us; must not be called concurrently with
 *           another call on the same handle.
 *     ANY   any context including fault handlers and NMI; reentrant.
 * - Implementations are not reentrant unless a call is marked ANY: the drive
 *   calls each handle from one context (fast loop or slow loop) at a time.
 */
#ifndef MC_HAL_HAL_H
#define MC_HAL_HAL_H

#include "hal/adc.h"
#include "hal/brake.h"
#include "hal/can.h"
#include "hal/encoder.h"
#include "hal/fault.h"
#include "hal/flash.h"
#include "hal/pwm2.h"
#include "hal/pwm3.h"
#include "hal/tick.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * A board: one handle per capability, NULL when the board does not have it
 * (a 3-phase drive has no pwm2, a stepper drive no pwm3, a sensorless drive
 * no encoder). The drive checks at start-up that the capabilities its mode
 * needs are present and refuses to start otherwise.
 */
typedef struct mc_hal {
    const mc_hal_adc_t *adc;
    const mc_hal_pwm3_t *pwm3;
    const mc_hal_pwm2_t *pwm2;
    const mc_hal_encoder_t *encoder;
    const mc_hal_can_t *can;
    const mc_hal_tick_t *tick;
    const mc_hal_fault_t *fault;
    const mc_hal_brake_t *brake; /**< brake-resistor chopper; NULL: none */
} mc_hal_t;

#ifdef __cplusplus
}
#endif

#endif /* MC_HAL_HAL_H */
