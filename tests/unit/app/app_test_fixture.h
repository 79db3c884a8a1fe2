// Shared set-up of the drive application tests: a fake HAL board with its
// default config (20 kHz PWM, 16384 counts/rev, fault inputs kill the gate)
// and a drive configuration that mc_drive_init accepts.
#ifndef APP_TEST_FIXTURE_H
#define APP_TEST_FIXTURE_H

#include <gtest/gtest.h>

#include <cerrno>
#include <cstdint>
#include <limits>

#include "foc/mc_foc.h"
#include "hal/hal.h"
#include "mc_drive.h"
#include "mc_hal_fake.h"

namespace apptest
{

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

constexpr float kDt = 50e-6f; // PWM period of the fake board [s]
constexpr uint32_t kPolePairs = 4u;
constexpr float kOffset = 0.3f;  // encoder offset [rad]
constexpr float kPllBw = 500.0f; // speed tracking loop bandwidth [rad/s]
constexpr uint32_t kSlowDiv = 10u;
constexpr float kIMax = 20.0f;
constexpr float kITrip = 30.0f;
constexpr float kVbusMin = 10.0f;
constexpr float kVbusMax = 60.0f;
constexpr float kVbus = 24.0f; // nominal bus voltage of the tests

// ADC channels the drive needs (ic is derived when IC is not valid).
constexpr uint32_t kMask3 = MC_HAL_ADC_VALID_IA | MC_HAL_ADC_VALID_IB | MC_HAL_ADC_VALID_VBUS;

inline mc_drive_cfg_t GoodCfg()
{
    mc_drive_cfg_t c{};
    // Current loop as in tests/unit/foc: 0.1 ohm, 100 uH, bw 1000 rad/s.
    c.foc.r_ohm = 0.1f;
    c.foc.ld_h = 100e-6f;
    c.foc.lq_h = 100e-6f;
    c.foc.flux_wb = 0.01f;
    c.foc.kp_d_v_per_a = 0.1f;    // L bw
    c.foc.ki_d_v_per_as = 100.0f; // R bw
    c.foc.kp_q_v_per_a = 0.1f;
    c.foc.ki_q_v_per_as = 100.0f;
    c.foc.dt_s = kDt;
    c.foc.aw = MC_PI_AW_CLAMP;
    c.foc.kaw_per_s = 1000.0f;
    c.foc.limit_mode = MC_SVPWM_LIMIT_CIRCLE;
    c.foc.v_limit_ratio = 1.0f;
    c.foc.v_abs_max_v = 40.0f;
    c.foc.decouple = true;
    c.pole_pairs = kPolePairs;
    c.encoder_offset_rad = kOffset;
    c.speed_pll_bw_rad_s = kPllBw;
    c.slow_loop_div = kSlowDiv;
    c.i_max_a = kIMax;
    c.i_trip_a = kITrip;
    c.vbus_min_v = kVbusMin;
    c.vbus_max_v = kVbusMax;
    return c;
}

class AppDrive : public ::testing::Test
{
  protected:
    void SetUp() override
    {
        ASSERT_EQ(0, mc_hal_fake_config_default(&fcfg));
        ASSERT_EQ(0, mc_hal_fake_init(&fake, &fcfg));
        hal = &fake.board;
        cfg = GoodCfg();
    }

    // Init the drive with cfg; encoder valid at count 0.
    void InitDrive()
    {
        ASSERT_EQ(MC_DRIVE_CFG_OK, mc_drive_init(&d, &cfg, hal));
        ASSERT_EQ(0, mc_hal_fake_encoder_set(&fake, 0u, MC_HAL_ENCODER_FLAG_VALID));
    }

    // One conversion with zero currents at the nominal bus voltage.
    void GoodSample()
    {
        ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, 0.0f, 0.0f, 0.0f, kVbus, kMask3));
    }

    // Init, enter CURRENT, run one clean fast step.
    void InitRunning()
    {
        InitDrive();
        ASSERT_EQ(0, mc_drive_set_current_ref(&d, 1.0f, 5.0f));
        ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
        GoodSample();
        (void)mc_drive_fast_step(&d);
        ASSERT_EQ(MC_DRIVE_MODE_CURRENT, d.mode);
        ASSERT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
        ASSERT_TRUE(fake.pwm3.enabled);
    }

    uint32_t Calls(mc_hal_fake_call_t c) const
    {
        return fake.call_count[c];
    }

    mc_hal_fake_config_t fcfg{};
    mc_hal_fake_t fake{};
    const mc_hal_t *hal = nullptr;
    mc_drive_cfg_t cfg{};
    mc_drive_t d{};
};

} // namespace apptest

#endif // APP_TEST_FIXTURE_H
