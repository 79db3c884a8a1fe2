/**
 * @file mc_drv8301.h
 * @brief TI DRV8301 three-phase gate driver: register set-up and fault
 *        read-back over SPI (hal/spi.h).
 *
 * Used by the ODrive v3.6 (one per axis, SPI3) and the VESC 6 (HW_60).
 * Register facts from the datasheet, TI SLOS719F (DRV8301, August 2011,
 * revised January 2016), section 7.5 (SPI) and 7.6 (register maps):
 *
 *   SPI       slave, 16-bit frames, MSB first, SCLK idle low, data
 *             captured on the falling edge (mode 1: CPOL 0, CPHA 1), up
 *             to 10 MHz; nSCS low for the frame.
 *   command   bit 15 R/W (1 read, 0 write), bits 14:11 address,
 *             bits 10:0 data (ignored for a read).
 *   response  shifted out during the NEXT frame (frame N carries the
 *             answer to command N - 1): bit 15 frame fault of that frame,
 *             bits 14:11 address, bits 10:0 the register.
 *   0x00  Status 1   D10 FAULT, D9 GVDD_UV, D8 PVDD_UV, D7 OTSD, D6 OTW,
 *                    D5 FETHA_OC, D4 FETLA_OC, D3 FETHB_OC, D2 FETLB_OC,
 *                    D1 FETHC_OC, D0 FETLC_OC; latched, cleared by a read.
 *   0x01  Status 2   D7 GVDD_OV (latched, cleared by a read), D3:D0 device ID.
 *   0x02  Control 1  D10:D6 OC_ADJ_SET (0..31), D5:D4 OCP_MODE (00 current
 *                    limit, 01 OC latch shut down, 10 report only, 11 OC
 *                    disabled), D3 PWM_MODE (0 six inputs, 1 three inputs),
 *                    D2 GATE_RESET (1 resets latched faults), D1:D0
 *                    GATE_CURRENT (00 1.7 A, 01 0.7 A, 10 0.25 A, 11 reserved).
 *   0x03  Control 2  D6 OC_TOFF (0 cycle by cycle, 1 off-time control),
 *                    D5 DC_CAL_CH2, D4 DC_CAL_CH1, D3:D2 GAIN (00 10 V/V,
 *                    01 20, 10 40, 11 80), D1:D0 OCTW_MODE (00 report OT and
 *                    OC, 01 OT only, 10 OC only, 11 reserved).
 *   OC_ADJ_SET  code -> V_DS trip threshold, 60 mV (code 0) .. 2.400 V
 *               (code 31); the over-current trips when V_DS = I R_DS(on)
 *               exceeds it (codes 28..31 not for PVDD 6..8 V; up to 20 %
 *               spread between channels).
 * The same encodings are used by the two public firmwares that drive this
 * chip (ODrive Firmware/Drivers/DRV8301/drv8301.{hpp,cpp}, VESC
 * hwconf/drv8301.{c,h} and datatypes.h drv8301_oc_mode), which the boards'
 * settings come from (firmware/targets/stm32f405/boards).
 *
 * No globals: the caller owns the mc_drv8301_t. Not reentrant; SLOW timing
 * (each register access is two SPI frames).
 */
#ifndef MC_DRV8301_H
#define MC_DRV8301_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/spi.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Control 1 D2: reset latched faults (reads back 0). */
#define MC_DRV8301_CTRL1_GATE_RESET (1u << 2)

/* Register addresses (bits 14:11 of a frame). */
#define MC_DRV8301_REG_STATUS1 0x0u
#define MC_DRV8301_REG_STATUS2 0x1u
#define MC_DRV8301_REG_CTRL1   0x2u
#define MC_DRV8301_REG_CTRL2   0x3u

/* Frame fields. */
#define MC_DRV8301_FRAME_READ       (1u << 15) /**< command: read; response: frame fault */
#define MC_DRV8301_FRAME_ADDR_SHIFT 11u
#define MC_DRV8301_FRAME_ADDR_MASK  (0xFu << 11)
#define MC_DRV8301_FRAME_DATA_MASK  0x7FFu

/* Faults as reported by mc_drv8301_read_faults(): bits 0..10 are Status 1
 * D0..D10, bit 11 is Status 2 D7 (GVDD_OV). */
#define MC_DRV8301_FAULT_FETLC_OC (1u << 0) /**< phase C low-side FET over-current */
#define MC_DRV8301_FAULT_FETHC_OC (1u << 1) /**< phase C high-side FET over-current */
#define MC_DRV8301_FAULT_FETLB_OC (1u << 2)
#define MC_DRV8301_FAULT_FETHB_OC (1u << 3)
#define MC_DRV8301_FAULT_FETLA_OC (1u << 4)
#define MC_DRV8301_FAULT_FETHA_OC (1u << 5)
#define MC_DRV8301_FAULT_OTW      (1u << 6)  /**< over-temperature warning */
#define MC_DRV8301_FAULT_OTSD     (1u << 7)  /**< over-temperature shut down */
#define MC_DRV8301_FAULT_PVDD_UV  (1u << 8)  /**< supply under-voltage */
#define MC_DRV8301_FAULT_GVDD_UV  (1u << 9)  /**< gate supply under-voltage */
#define MC_DRV8301_FAULT_FAULT    (1u << 10) /**< any fault (the nFAULT pin) */
#define MC_DRV8301_FAULT_GVDD_OV  (1u << 11) /**< gate supply over-voltage */
#define MC_DRV8301_FAULT_ALL      0xFFFu
/** Faults that are only warnings: the chip keeps switching. */
#define MC_DRV8301_FAULT_WARNINGS MC_DRV8301_FAULT_OTW

/** Number of OC_ADJ_SET codes. */
#define MC_DRV8301_OC_ADJ_CODES 32u
/** Write-and-verify attempts of mc_drv8301_init() (the ODrive firmware
 *  notes that a single write is sometimes ignored and writes Control 1
 *  five times; here every write is verified by reading it back). */
#define MC_DRV8301_INIT_ATTEMPTS 3u

typedef enum mc_drv8301_gain {
    MC_DRV8301_GAIN_10 = 0,
    MC_DRV8301_GAIN_20 = 1,
    MC_DRV8301_GAIN_40 = 2,
    MC_DRV8301_GAIN_80 = 3
} mc_drv8301_gain_t;

typedef enum mc_drv8301_ocp_mode {
    MC_DRV8301_OCP_CURRENT_LIMIT = 0, /**< cycle-by-cycle limit (OC_TOFF) */
    MC_DRV8301_OCP_LATCH = 1,         /**< the bridge is shut down until reset */
    MC_DRV8301_OCP_REPORT_ONLY = 2,
    MC_DRV8301_OCP_DISABLED = 3
} mc_drv8301_ocp_mode_t;

typedef enum mc_drv8301_pwm_mode {
    MC_DRV8301_PWM_6 = 0, /**< INH_x and INL_x per phase (TIM1 CHx + CHxN) */
    MC_DRV8301_PWM_3 = 1  /**< INH_x only; the chip makes the low side */
} mc_drv8301_pwm_mode_t;

typedef enum mc_drv8301_gate_current {
    MC_DRV8301_GATE_1A7 = 0,
    MC_DRV8301_GATE_0A7 = 1,
    MC_DRV8301_GATE_0A25 = 2
} mc_drv8301_gate_current_t;

typedef enum mc_drv8301_octw_mode {
    MC_DRV8301_OCTW_OT_AND_OC = 0,
    MC_DRV8301_OCTW_OT_ONLY = 1,
    MC_DRV8301_OCTW_OC_ONLY = 2
} mc_drv8301_octw_mode_t;

typedef enum mc_drv8301_oc_toff {
    MC_DRV8301_OC_TOFF_CYCLE = 0,   /**< current limit cycle by cycle */
    MC_DRV8301_OC_TOFF_OFF_TIME = 1 /**< off-time control */
} mc_drv8301_oc_toff_t;

typedef struct mc_drv8301_config {
    mc_drv8301_gain_t gain; /**< shunt amplifier gain */
    uint8_t oc_adj_set;     /**< OC_ADJ_SET code 0..31 */
    mc_drv8301_ocp_mode_t ocp_mode;
    mc_drv8301_pwm_mode_t pwm_mode;
    mc_drv8301_gate_current_t gate_current;
    mc_drv8301_octw_mode_t octw_mode;
    mc_drv8301_oc_toff_t oc_toff;
} mc_drv8301_config_t;

/** Outcome of the last mc_drv8301_init() (why a set-up failed). */
typedef enum mc_drv8301_status {
    MC_DRV8301_STATUS_OK = 0,
    MC_DRV8301_STATUS_NOT_INIT,    /**< never set up */
    MC_DRV8301_STATUS_CONFIG,      /**< configuration refused */
    MC_DRV8301_STATUS_SPI,         /**< the SPI transfer failed */
    MC_DRV8301_STATUS_NO_RESPONSE, /**< response with the frame-fault bit or
                                          the wrong address (no chip, EN_GATE
                                          low, MISO stuck) */
    MC_DRV8301_STATUS_READBACK,    /**< the control registers do not hold
                                          what was written */
    MC_DRV8301_STATUS_FAULT        /**< the chip reports a fault (faults) */
} mc_drv8301_status_t;

typedef struct mc_drv8301 {
    const mc_hal_spi_t *p_spi;
    uint16_t ctrl1;    /**< Control 1 as configured */
    uint16_t ctrl2;    /**< Control 2 as configured */
    uint32_t faults;   /**< MC_DRV8301_FAULT_* of the last read */
    uint8_t device_id; /**< Status 2 D3:D0 of the last read */
    mc_drv8301_status_t status;
} mc_drv8301_t;

/** Write command frame: bit 15 = 0, address in 14:11, data in 10:0. */
uint16_t mc_drv8301_frame_write(uint32_t addr, uint32_t data);

/** Read command frame: bit 15 = 1, address in 14:11, data 0. */
uint16_t mc_drv8301_frame_read(uint32_t addr);

/**
 * Control 1 and Control 2 words for a configuration (DC_CAL off,
 * GATE_RESET 0).
 * @return 0; -EINVAL NULL, code > 31 or an enum out of range (reserved
 *         encodings included): outputs untouched.
 */
int mc_drv8301_ctrl_encode(const mc_drv8301_config_t *p_cfg, uint16_t *p_ctrl1, uint16_t *p_ctrl2);

/** MC_DRV8301_FAULT_* bits from the two status registers. */
uint32_t mc_drv8301_faults_from_status(uint16_t status1, uint16_t status2);

/** Name of one fault bit ("FETHA_OC", "GVDD_UV", ...), or NULL when
 *  `fault` is not exactly one known bit. */
const char *mc_drv8301_fault_name(uint32_t fault);

/** V_DS trip threshold of an OC_ADJ_SET code [mV]; 0 for code > 31. */
uint32_t mc_drv8301_oc_adj_vds_mv(uint32_t code);

/**
 * The largest OC_ADJ_SET code whose threshold does not exceed
 * i_trip_a * rds_on_ohm (so the chip trips at or below the requested
 * current for that R_DS(on)).
 * @return 0 and *p_code; -EINVAL non-finite or non-positive input, or a
 *         product below the smallest threshold (60 mV).
 */
int mc_drv8301_oc_adj_for_trip(float i_trip_a, float rds_on_ohm, uint8_t *p_code);

/** Amplifier gain of a setting [V/V]; 0 for an invalid setting. */
float mc_drv8301_gain_v_per_v(mc_drv8301_gain_t gain);

/** Status name ("ok", "no response", ...). */
const char *mc_drv8301_status_name(mc_drv8301_status_t status);

/**
 * Set the chip up: write Control 1 and 2, read both back (up to
 * MC_DRV8301_INIT_ATTEMPTS times until they match), then read the status
 * registers (which clears latched faults) into p_drv->faults. EN_GATE must
 * be high for at least the chip's SPI start-up time before this call.
 * @return 0 (status OK); -EINVAL bad argument (status CONFIG, or p_drv
 *         NULL); -EIO SPI failure, no valid response or read-back mismatch;
 *         -EBUSY the chip reports a fault other than a warning
 *         (p_drv->faults names it).
 */
int mc_drv8301_init(mc_drv8301_t *p_drv, const mc_hal_spi_t *p_spi,
                    const mc_drv8301_config_t *p_cfg);

/**
 * Read one register (two frames: the read command, then a read of
 * Control 1, which has no side effect, to clock the answer out).
 * @return 0 and *p_data (10:0); -EINVAL; -EIO (SPI failure, frame-fault
 *         bit or wrong address in the response: *p_data untouched).
 */
int mc_drv8301_read_reg(const mc_drv8301_t *p_drv, uint32_t addr, uint16_t *p_data);

/** Write one register (one frame). @return 0; -EINVAL; -EIO. */
int mc_drv8301_write_reg(const mc_drv8301_t *p_drv, uint32_t addr, uint32_t data);

/**
 * Reset the chip's latched faults (a latched over-current shut-down in
 * particular): write Control 1 with GATE_RESET (D2) set, which the chip
 * clears again, then read Control 1 back to check it holds the
 * configuration (GATE_RESET 0).
 * @return 0; -EINVAL (NULL or never set up); -EIO (SPI failure, no valid
 *         response, or Control 1 not as configured).
 */
int mc_drv8301_reset_faults(const mc_drv8301_t *p_drv);

/**
 * Read Status 1 and 2 (clearing the latched bits in the chip) and store the
 * faults and the device ID in p_drv.
 * @return 0 and *p_faults (may be NULL); -EINVAL; -EIO (p_drv unchanged).
 */
int mc_drv8301_read_faults(mc_drv8301_t *p_drv, uint32_t *p_faults);

#ifdef __cplusplus
}
#endif

#endif /* MC_DRV8301_H */
