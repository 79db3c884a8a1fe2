// Parameter table access and whole-configuration validation
// (firmware/app/config/mc_params.h). Exact comparisons throughout: the
// checks are on stored float32 values, no arithmetic in between.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "mc_drive.h"
#include "mc_hal_fake.h"
#include "mc_params.h"

namespace
{

uint32_t Bits(float f)
{
    uint32_t u;
    std::memcpy(&u, &f, sizeof u);
    return u;
}

TEST(Params, TableSortedUniqueAndDefaultsInRange)
{
    for (uint32_t i = 0; i < MC_PARAM_COUNT; ++i) {
        const mc_param_info_t &p = mc_param_table[i];
        if (i > 0) {
            EXPECT_LT(mc_param_table[i - 1].id, p.id) << "table must be sorted for the lookup";
        }
        EXPECT_EQ(mc_param_check_value(&p, p.def.u), MC_PARAM_OK) << "id " << p.id;
        uint32_t idx = 999;
        EXPECT_EQ(mc_param_find(p.id, &idx), &p);
        EXPECT_EQ(idx, i);
        if (p.offset != MC_PARAM_NO_FIELD) {
            EXPECT_EQ(mc_param_get_raw(&mc_params_default, &p), p.def.u) << "id " << p.id;
        }
    }
    EXPECT_EQ(mc_param_find(0, nullptr), nullptr);
    EXPECT_EQ(mc_param_find(65535, nullptr), nullptr);
    EXPECT_EQ(mc_param_find(MC_PARAM_ID_R_OHM + 18u, nullptr), nullptr); // 19: a gap
}

TEST(Params, SingleValueChecks)
{
    const mc_param_info_t *r = mc_param_find(MC_PARAM_ID_R_OHM, nullptr);
    ASSERT_NE(r, nullptr);
    EXPECT_EQ(mc_param_check_value(r, Bits(0.0f)), MC_PARAM_OK);   // min inclusive
    EXPECT_EQ(mc_param_check_value(r, Bits(100.0f)), MC_PARAM_OK); // max inclusive
    EXPECT_EQ(mc_param_check_value(r, Bits(-1e-9f)), MC_PARAM_ERR_RANGE);
    EXPECT_EQ(mc_param_check_value(r, Bits(std::nextafter(100.0f, 200.0f))), MC_PARAM_ERR_RANGE);
    EXPECT_EQ(mc_param_check_value(r, Bits(std::numeric_limits<float>::quiet_NaN())),
              MC_PARAM_ERR_RANGE);
    EXPECT_EQ(mc_param_check_value(r, Bits(std::numeric_limits<float>::infinity())),
              MC_PARAM_ERR_RANGE);
    const mc_param_info_t *pp = mc_param_find(MC_PARAM_ID_POLE_PAIRS, nullptr);
    ASSERT_NE(pp, nullptr);
    EXPECT_EQ(mc_param_check_value(pp, 0u), MC_PARAM_ERR_RANGE);
    EXPECT_EQ(mc_param_check_value(pp, 1u), MC_PARAM_OK);
    EXPECT_EQ(mc_param_check_value(pp, 64u), MC_PARAM_OK);
    EXPECT_EQ(mc_param_check_value(pp, 65u), MC_PARAM_ERR_RANGE);
    EXPECT_EQ(mc_param_check_value(nullptr, 0u), MC_PARAM_ERR_UNKNOWN_ID);
}

TEST(Params, DefaultsValidAndAcceptedByTheDrive)
{
    EXPECT_EQ(mc_params_validate(&mc_params_default), MC_PARAMS_OK);
    mc_drive_cfg_t cfg;
    ASSERT_EQ(mc_params_to_drive_cfg(&mc_params_default, &cfg), MC_PARAMS_OK);
    // kp = L bw, ki = R bw (pole-zero cancelling; float32 products, so exact
    // to the last bit of the same product)
    EXPECT_EQ(cfg.foc.kp_d_v_per_a, mc_params_default.ld_h * mc_params_default.current_bw_rad_s);
    EXPECT_EQ(cfg.foc.ki_q_v_per_as, mc_params_default.r_ohm * mc_params_default.current_bw_rad_s);
    EXPECT_EQ(cfg.foc.dt_s, 1.0f / 20000.0f);
    mc_hal_fake_t fake;
    mc_hal_fake_config_t fc;
    mc_hal_fake_config_default(&fc);
    ASSERT_EQ(mc_hal_fake_init(&fake, &fc), 0);
    mc_drive_t d;
    EXPECT_EQ(mc_drive_init(&d, &cfg, &fake.board), MC_DRIVE_CFG_OK);
}

TEST(Params, CurrentLimitAboveSensorFullScaleRefused)
{
    mc_params_t p = mc_params_default;
    p.i_sense_max_a = 12.0f; // i_max 10 fits, i_trip 15 does not
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_ERR_SENSE);
    p.i_trip_a = 12.0f;
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_OK);
    p.i_max_a = 12.5f; // now i_max > i_trip (drive) and > full scale
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_ERR_SENSE | MC_PARAMS_ERR_DRIVE);
}

TEST(Params, CrossChecks)
{
    mc_params_t p = mc_params_default;
    p.current_bw_rad_s = 0.5f * 20000.0f; // bw dt = 0.5: the limit itself is allowed
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_OK);
    p.pwm_hz = 19999u; // same bandwidth, slower loop: bw dt > 0.5
    EXPECT_EQ(mc_params_validate(&p) & MC_PARAMS_ERR_BANDWIDTH, MC_PARAMS_ERR_BANDWIDTH);
    p = mc_params_default;
    p.dead_time_s = 5.0e-6f; // 10 % of 50 us is 5 us: allowed
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_OK);
    p.pwm_hz = 25000u; // 12.5 %
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_ERR_DEAD_TIME);
    p = mc_params_default;
    p.can_bitrate_bps = 300000u; // in range, not a standard rate
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_ERR_BITRATE);
    p = mc_params_default;
    p.vbus_min_v = 60.0f; // above vbus_max_v: the drive's own check
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_ERR_DRIVE);
    p = mc_params_default;
    p.r_ohm = std::numeric_limits<float>::quiet_NaN();
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_ERR_RANGE);
    EXPECT_EQ(mc_params_validate(nullptr), MC_PARAMS_ERR_NULL);
}

} // namespace
