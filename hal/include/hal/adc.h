/**
 * @file adc.h
 * @brief HAL capability: phase-current, DC-bus and temperature sampling.
 *
 * On the STM32F405 the phase currents and the bus voltage are ADC injected
 * conversions triggered by TIM1 at the centre of the PWM period (all low-side
 * switches on, shunt currents readable); the end-of-conversion interrupt runs
 * the fast loop, which calls mc_hal_adc_read() first. Temperatures are slow
 * regular conversions. The implementation owns gains and offsets (shunt
 * resistance, amplifier gain, divider ratio, thermistor curve) and delivers
 * physical units.
 *
 * See hal/hal.h for the conventions (error codes, timing classes).
 */
#ifndef MC_HAL_ADC_H
#define MC_HAL_ADC_H

#include <errno.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Bits of mc_hal_adc_sample_t.valid_mask: the channel holds a real value. */
#define MC_HAL_ADC_VALID_IA   (1u << 0)
#define MC_HAL_ADC_VALID_IB   (1u << 1)
#define MC_HAL_ADC_VALID_IC   (1u << 2)
#define MC_HAL_ADC_VALID_VBUS (1u << 3)
#define MC_HAL_ADC_VALID_ALL \
    (MC_HAL_ADC_VALID_IA | MC_HAL_ADC_VALID_IB | MC_HAL_ADC_VALID_IC | MC_HAL_ADC_VALID_VBUS)

/** Bits of mc_hal_adc_temp_t.valid_mask. */
#define MC_HAL_ADC_TEMP_VALID_POWER_STAGE (1u << 0)
#define MC_HAL_ADC_TEMP_VALID_MOTOR       (1u << 1)
#define MC_HAL_ADC_TEMP_VALID_ALL         (MC_HAL_ADC_TEMP_VALID_POWER_STAGE | MC_HAL_ADC_TEMP_VALID_MOTOR)

/**
 * One fast-loop sample, taken at one PWM-synchronous trigger.
 *
 * Currents are positive flowing from the inverter into the motor phase.
 * A channel whose bit is clear in valid_mask is not measured on this board
 * (e.g. two shunts only: ic_a is then absent and the drive uses
 * ia + ib + ic = 0) or was unusable at this trigger (ADC at a rail, i.e.
 * amplifier saturated); its value is then unspecified (0.0f by convention)
 * and must not be used.
 */
typedef struct mc_hal_adc_sample {
    float ia_a;               /**< phase a current [A] */
    float ib_a;               /**< phase b current [A] */
    float ic_a;               /**< phase c current [A] */
    float vbus_v;             /**< DC-bus voltage [V] */
    uint32_t valid_mask;      /**< MC_HAL_ADC_VALID_* bits */
    uint32_t timestamp_ticks; /**< tick counter (hal/tick.h) at the trigger */
    uint32_t seq;             /**< +1 per completed conversion, wraps; a gap
                                   of more than 1 between two reads means
                                   samples were missed */
} mc_hal_adc_sample_t;

/** Slow temperature channels. */
typedef struct mc_hal_adc_temp {
    float power_stage_temp_c; /**< power stage (FET / heat sink) [deg C] */
    float motor_temp_c;       /**< motor winding thermistor [deg C] */
    uint32_t valid_mask;      /**< MC_HAL_ADC_TEMP_VALID_* bits; a clear bit
                                   means no reading: no sensor, none yet, or
                                   open/short circuit */
    uint32_t absent_mask;     /**< MC_HAL_ADC_TEMP_VALID_* bits of the sensors
                                   this board does not have (0: both fitted);
                                   the drive enforces its limit on the others */
} mc_hal_adc_temp_t;

typedef struct mc_hal_adc_ops {
    /** See mc_hal_adc_read(). */
    int (*read)(void *ctx, mc_hal_adc_sample_t *p_sample);
    /** See mc_hal_adc_read_temp(). NULL if the board has no temperature
     *  channels. */
    int (*read_temp)(void *ctx, mc_hal_adc_temp_t *p_temp);
} mc_hal_adc_ops_t;

typedef struct mc_hal_adc {
    const mc_hal_adc_ops_t *ops;
    void *ctx;
} mc_hal_adc_t;

/**
 * Latest completed fast-loop conversion.               Timing: FAST.
 *
 * Called once per PWM period from the fast-loop ISR, after the triggered
 * conversion has completed. Copies out the newest sample and marks it
 * consumed.
 * @return 0 and *p_sample filled;
 *         -EAGAIN no conversion completed since the previous successful read
 *                 (trigger missed or read called twice): *p_sample unchanged,
 *                 the drive treats it as a missed sample;
 *         -EIO    ADC fault (overrun, conversion error): *p_sample unchanged;
 *         -ENODEV / -EINVAL as in hal/hal.h.
 */
static inline int mc_hal_adc_read(const mc_hal_adc_t *dev, mc_hal_adc_sample_t *p_sample)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->read == NULL)) {
        return -ENODEV;
    }
    if (p_sample == NULL) {
        return -EINVAL;
    }
    return dev->ops->read(dev->ctx, p_sample);
}

/**
 * Latest temperatures (power stage and motor).          Timing: SLOW.
 *
 * Returns the latest background conversion; does not start or wait for one.
 * @return 0 and *p_temp filled (check valid_mask per channel);
 *         -EIO ADC fault: *p_temp unchanged; -ENODEV / -EINVAL.
 */
static inline int mc_hal_adc_read_temp(const mc_hal_adc_t *dev, mc_hal_adc_temp_t *p_temp)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->read_temp == NULL)) {
        return -ENODEV;
    }
    if (p_temp == NULL) {
        return -EINVAL;
    }
    return dev->ops->read_temp(dev->ctx, p_temp);
}

#ifdef __cplusplus
}
#endif

#endif /* MC_HAL_ADC_H */
