/**
 * @file mc_drv8301.c
 * @brief TI DRV8301 register set-up and fault read-back. Register facts:
 *        TI SLOS719F; see mc_drv8301.h.
 */
#include "mc_drv8301.h"

#include <errno.h>
#include <float.h>
#include <stddef.h>

/* Control 1 fields */
#define CTRL1_GATE_CURRENT_SHIFT 0u
#define CTRL1_PWM_MODE_SHIFT     3u
#define CTRL1_OCP_MODE_SHIFT     4u
#define CTRL1_OC_ADJ_SHIFT       6u
/* Control 2 fields */
#define CTRL2_OCTW_SHIFT    0u
#define CTRL2_GAIN_SHIFT    2u
#define CTRL2_OC_TOFF_SHIFT 6u
/* Status 2 */
#define STATUS2_GVDD_OV        (1u << 7)
#define STATUS2_DEVICE_ID_MASK 0xFu
#define STATUS1_MASK           0x7FFu

/* SLOS719F, OC_ADJ_SET table: V_DS threshold per code [mV]. */
static const uint16_t k_oc_adj_vds_mv[MC_DRV8301_OC_ADJ_CODES] = {
    60u,  68u,  76u,   86u,   97u,   109u,  123u,  138u,  155u,  175u,  197u,
    222u, 250u, 282u,  317u,  358u,  403u,  454u,  511u,  576u,  648u,  730u,
    822u, 926u, 1043u, 1175u, 1324u, 1491u, 1679u, 1892u, 2131u, 2400u,
};

static const char *const k_fault_names[12] = {
    "FETLC_OC", "FETHC_OC", "FETLB_OC", "FETHB_OC", "FETLA_OC", "FETHA_OC",
    "OTW",      "OTSD",     "PVDD_UV",  "GVDD_UV",  "FAULT",    "GVDD_OV",
};

static bool finite_pos(float x)
{
    return (x > 0.0f) && (x <= FLT_MAX);
}

uint16_t mc_drv8301_frame_write(uint32_t addr, uint32_t data)
{
    return (uint16_t)(((addr << MC_DRV8301_FRAME_ADDR_SHIFT) & MC_DRV8301_FRAME_ADDR_MASK) |
                      (data & MC_DRV8301_FRAME_DATA_MASK));
}

uint16_t mc_drv8301_frame_read(uint32_t addr)
{
    return (uint16_t)(MC_DRV8301_FRAME_READ |
                      ((addr << MC_DRV8301_FRAME_ADDR_SHIFT) & MC_DRV8301_FRAME_ADDR_MASK));
}

int mc_drv8301_ctrl_encode(const mc_drv8301_config_t *p_cfg, uint16_t *p_ctrl1, uint16_t *p_ctrl2)
{
    uint32_t c1;
    uint32_t c2;

    if ((p_cfg == NULL) || (p_ctrl1 == NULL) || (p_ctrl2 == NULL)) {
        return -EINVAL;
    }
    if ((p_cfg->oc_adj_set >= MC_DRV8301_OC_ADJ_CODES) ||
        ((uint32_t)p_cfg->gain > (uint32_t)MC_DRV8301_GAIN_80) ||
        ((uint32_t)p_cfg->ocp_mode > (uint32_t)MC_DRV8301_OCP_DISABLED) ||
        ((uint32_t)p_cfg->pwm_mode > (uint32_t)MC_DRV8301_PWM_3) ||
        ((uint32_t)p_cfg->gate_current > (uint32_t)MC_DRV8301_GATE_0A25) ||
        ((uint32_t)p_cfg->octw_mode > (uint32_t)MC_DRV8301_OCTW_OC_ONLY) ||
        ((uint32_t)p_cfg->oc_toff > (uint32_t)MC_DRV8301_OC_TOFF_OFF_TIME)) {
        return -EINVAL;
    }
    c1 = ((uint32_t)p_cfg->gate_current << CTRL1_GATE_CURRENT_SHIFT) |
         ((uint32_t)p_cfg->pwm_mode << CTRL1_PWM_MODE_SHIFT) |
         ((uint32_t)p_cfg->ocp_mode << CTRL1_OCP_MODE_SHIFT) |
         ((uint32_t)p_cfg->oc_adj_set << CTRL1_OC_ADJ_SHIFT);
    c2 = ((uint32_t)p_cfg->octw_mode << CTRL2_OCTW_SHIFT) |
         ((uint32_t)p_cfg->gain << CTRL2_GAIN_SHIFT) |
         ((uint32_t)p_cfg->oc_toff << CTRL2_OC_TOFF_SHIFT);
    *p_ctrl1 = (uint16_t)c1;
    *p_ctrl2 = (uint16_t)c2;
    return 0;
}

uint32_t mc_drv8301_faults_from_status(uint16_t status1, uint16_t status2)
{
    uint32_t f = (uint32_t)status1 & STATUS1_MASK;

    if (((uint32_t)status2 & STATUS2_GVDD_OV) != 0u) {
        f |= MC_DRV8301_FAULT_GVDD_OV;
    }
    return f;
}

const char *mc_drv8301_fault_name(uint32_t fault)
{
    uint32_t k;

    for (k = 0u; k < 12u; k++) {
        if (fault == (1u << k)) {
            return k_fault_names[k];
        }
    }
    return NULL;
}

uint32_t mc_drv8301_oc_adj_vds_mv(uint32_t code)
{
    return (code < MC_DRV8301_OC_ADJ_CODES) ? (uint32_t)k_oc_adj_vds_mv[code] : 0u;
}

int mc_drv8301_oc_adj_for_trip(float i_trip_a, float rds_on_ohm, uint8_t *p_code)
{
    float vds_mv;
    uint32_t k;

    if ((p_code == NULL) || !finite_pos(i_trip_a) || !finite_pos(rds_on_ohm)) {
        return -EINVAL;
    }
    vds_mv = i_trip_a * rds_on_ohm * 1000.0f;
    if (!(vds_mv >= (float)k_oc_adj_vds_mv[0])) {
        return -EINVAL;
    }
    for (k = MC_DRV8301_OC_ADJ_CODES - 1u; k > 0u; k--) {
        if ((float)k_oc_adj_vds_mv[k] <= vds_mv) {
            break;
        }
    }
    *p_code = (uint8_t)k;
    return 0;
}

float mc_drv8301_gain_v_per_v(mc_drv8301_gain_t gain)
{
    switch (gain) {
    case MC_DRV8301_GAIN_10:
        return 10.0f;
    case MC_DRV8301_GAIN_20:
        return 20.0f;
    case MC_DRV8301_GAIN_40:
        return 40.0f;
    case MC_DRV8301_GAIN_80:
        return 80.0f;
    default:
        return 0.0f;
    }
}

const char *mc_drv8301_status_name(mc_drv8301_status_t status)
{
    switch (status) {
    case MC_DRV8301_STATUS_OK:
        return "ok";
    case MC_DRV8301_STATUS_NOT_INIT:
        return "not set up";
    case MC_DRV8301_STATUS_CONFIG:
        return "configuration refused";
    case MC_DRV8301_STATUS_SPI:
        return "SPI transfer failed";
    case MC_DRV8301_STATUS_NO_RESPONSE:
        return "no response (frame fault or wrong address)";
    case MC_DRV8301_STATUS_READBACK:
        return "control registers do not read back";
    case MC_DRV8301_STATUS_FAULT:
        return "chip reports a fault";
    default:
        return "unknown";
    }
}

/* One register access result: 0, -EIO (SPI) or -EPROTO (bad response). */
static int read_raw(const mc_hal_spi_t *p_spi, uint32_t addr, uint16_t *p_data)
{
    uint16_t rx = 0u;
    int rc;

    rc = mc_hal_spi_transfer16(p_spi, mc_drv8301_frame_read(addr), NULL);
    if (rc != 0) {
        return -EIO;
    }
    /* The answer to the read comes with the next frame. */
    rc = mc_hal_spi_transfer16(p_spi, mc_drv8301_frame_read(MC_DRV8301_REG_CTRL1), &rx);
    if (rc != 0) {
        return -EIO;
    }
    if (((rx & MC_DRV8301_FRAME_READ) != 0u) ||
        (((uint32_t)rx & MC_DRV8301_FRAME_ADDR_MASK) >> MC_DRV8301_FRAME_ADDR_SHIFT) != addr) {
        return -EPROTO;
    }
    *p_data = (uint16_t)(rx & MC_DRV8301_FRAME_DATA_MASK);
    return 0;
}

int mc_drv8301_read_reg(const mc_drv8301_t *p_drv, uint32_t addr, uint16_t *p_data)
{
    uint16_t v = 0u;

    if ((p_drv == NULL) || (p_data == NULL) || (addr > MC_DRV8301_REG_CTRL2)) {
        return -EINVAL;
    }
    if (read_raw(p_drv->p_spi, addr, &v) != 0) {
        return -EIO;
    }
    *p_data = v;
    return 0;
}

int mc_drv8301_write_reg(const mc_drv8301_t *p_drv, uint32_t addr, uint32_t data)
{
    if ((p_drv == NULL) || (addr > MC_DRV8301_REG_CTRL2) || (data > MC_DRV8301_FRAME_DATA_MASK)) {
        return -EINVAL;
    }
    return (mc_hal_spi_transfer16(p_drv->p_spi, mc_drv8301_frame_write(addr, data), NULL) == 0)
               ? 0
               : -EIO;
}

/* Status registers into faults/device_id; 0, -EIO or -EPROTO. */
static int read_status(mc_drv8301_t *p_drv)
{
    uint16_t s1 = 0u;
    uint16_t s2 = 0u;
    int rc;

    rc = read_raw(p_drv->p_spi, MC_DRV8301_REG_STATUS1, &s1);
    if (rc == 0) {
        rc = read_raw(p_drv->p_spi, MC_DRV8301_REG_STATUS2, &s2);
    }
    if (rc != 0) {
        return rc;
    }
    p_drv->faults = mc_drv8301_faults_from_status(s1, s2);
    p_drv->device_id = (uint8_t)((uint32_t)s2 & STATUS2_DEVICE_ID_MASK);
    return 0;
}

int mc_drv8301_read_faults(mc_drv8301_t *p_drv, uint32_t *p_faults)
{
    mc_drv8301_t copy;

    if (p_drv == NULL) {
        return -EINVAL;
    }
    copy = *p_drv;
    if (read_status(&copy) != 0) {
        return -EIO;
    }
    p_drv->faults = copy.faults;
    p_drv->device_id = copy.device_id;
    if (p_faults != NULL) {
        *p_faults = copy.faults;
    }
    return 0;
}

int mc_drv8301_reset_faults(const mc_drv8301_t *p_drv)
{
    uint16_t r1 = 0u;

    if ((p_drv == NULL) || (p_drv->p_spi == NULL)) {
        return -EINVAL;
    }
    if (mc_hal_spi_transfer16(
            p_drv->p_spi,
            mc_drv8301_frame_write(MC_DRV8301_REG_CTRL1,
                                   (uint32_t)p_drv->ctrl1 | MC_DRV8301_CTRL1_GATE_RESET),
            NULL) != 0) {
        return -EIO;
    }
    if ((read_raw(p_drv->p_spi, MC_DRV8301_REG_CTRL1, &r1) != 0) || (r1 != p_drv->ctrl1)) {
        return -EIO;
    }
    return 0;
}

static mc_drv8301_status_t status_of(int rc)
{
    return (rc == -EPROTO) ? MC_DRV8301_STATUS_NO_RESPONSE : MC_DRV8301_STATUS_SPI;
}

int mc_drv8301_init(mc_drv8301_t *p_drv, const mc_hal_spi_t *p_spi,
                    const mc_drv8301_config_t *p_cfg)
{
    uint16_t c1 = 0u;
    uint16_t c2 = 0u;
    uint16_t r1 = 0u;
    uint16_t r2 = 0u;
    uint32_t attempt;
    int rc = 0;
    bool match = false;

    if (p_drv == NULL) {
        return -EINVAL;
    }
    if ((p_spi == NULL) || (mc_drv8301_ctrl_encode(p_cfg, &c1, &c2) != 0)) {
        p_drv->status = MC_DRV8301_STATUS_CONFIG;
        return -EINVAL;
    }
    p_drv->p_spi = p_spi;
    p_drv->ctrl1 = c1;
    p_drv->ctrl2 = c2;
    p_drv->faults = 0u;
    p_drv->device_id = 0u;

    for (attempt = 0u; (attempt < MC_DRV8301_INIT_ATTEMPTS) && !match; attempt++) {
        if ((mc_hal_spi_transfer16(p_spi, mc_drv8301_frame_write(MC_DRV8301_REG_CTRL1, c1), NULL) !=
             0) ||
            (mc_hal_spi_transfer16(p_spi, mc_drv8301_frame_write(MC_DRV8301_REG_CTRL2, c2), NULL) !=
             0)) {
            p_drv->status = MC_DRV8301_STATUS_SPI;
            return -EIO;
        }
        rc = read_raw(p_spi, MC_DRV8301_REG_CTRL1, &r1);
        if (rc == 0) {
            rc = read_raw(p_spi, MC_DRV8301_REG_CTRL2, &r2);
        }
        if (rc != 0) {
            p_drv->status = status_of(rc);
            return -EIO;
        }
        match = (r1 == c1) && (r2 == c2);
    }
    if (!match) {
        p_drv->status = MC_DRV8301_STATUS_READBACK;
        return -EIO;
    }
    rc = read_status(p_drv);
    if (rc != 0) {
        p_drv->status = status_of(rc);
        return -EIO;
    }
    if ((p_drv->faults & ~MC_DRV8301_FAULT_WARNINGS) != 0u) {
        p_drv->status = MC_DRV8301_STATUS_FAULT;
        return -EBUSY;
    }
    p_drv->status = MC_DRV8301_STATUS_OK;
    return 0;
}
