// Parameter table access and whole-configuration validation
// (firmware/app/config/mc_params.h). Exact comparisons throughout: the
// checks are on stored float32 values, no arithmetic in between.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "mc_drive.h"
#include "mc_hal_fake.h"
#include "mc_params.h"

extern "C" {
#include "mc_law_cfg.h"
}

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
    // current_bw 0: derived, 0.08 pwm_hz; kp = L bw, ki = R bw (pole-zero
    // cancelling; float32 products, so exact to the last bit of the same
    // product)
    const float bw = static_cast<float>(0.08 * 20000.0);
    EXPECT_EQ(cfg.foc.kp_d_v_per_a, mc_params_default.ld_h * bw);
    EXPECT_EQ(cfg.foc.ki_q_v_per_as, mc_params_default.r_ohm * bw);
    EXPECT_EQ(cfg.foc.dt_s, 1.0f / 20000.0f);
    mc_hal_fake_t fake;
    mc_hal_fake_config_t fc;
    mc_hal_fake_config_default(&fc);
    ASSERT_EQ(mc_hal_fake_init(&fake, &fc), 0);
    mc_drive_t d;
    EXPECT_EQ(mc_drive_init(&d, &cfg, &fake.board), MC_DRIVE_CFG_OK);
}

// Each "0: derived" parameter by its formula (mc_params.h, mc_gains.c), on
// the table's defaults (the paper-002 test motor, 48 V, 20 kHz); a value
// set is taken as given. Exact where the derivation is one float or double
// expression; the rest against the gains they come from.
TEST(Params, DerivedUnlessSet)
{
    const mc_params_t &p = mc_params_default;
    mc_params_eff_t e;
    ASSERT_EQ(mc_params_resolve(&p, &e), MC_GAINS_OK);
    const mc_params_t &r = e.p;
    // the current limit: min(i_max, i_sense / 1.25, 0.8 v_max / R) = i_max here
    const double v_max = 0.95 * 48.0 / std::sqrt(3.0);
    EXPECT_EQ(e.g.i_limit_a,
              std::min({10.0, 60.0 / 1.25, 0.8 * v_max / static_cast<double>(p.r_ohm)}));
    EXPECT_EQ(r.current_bw_rad_s, static_cast<float>(0.08 * 20000.0));
    EXPECT_EQ(r.speed_pll_bw_rad_s, 1000.0f); // min(1000, 0.1 pwm_hz)
    EXPECT_EQ(r.speed_bw_rad_s, std::min(r.current_bw_rad_s / 10.0f, 1000.0f / 4.0f));
    const double kt = 1.5 * 4.0 * static_cast<double>(p.flux_wb);
    EXPECT_EQ(r.speed_kp_a_s_rad, static_cast<float>(static_cast<double>(p.j_kgm2) *
                                                     static_cast<double>(r.speed_bw_rad_s) / kt));
    EXPECT_EQ(r.speed_ki_a_rad,
              static_cast<float>(static_cast<double>(r.speed_kp_a_s_rad) * r.speed_bw_rad_s / 4.0));
    EXPECT_EQ(r.speed_ramp_rad_s2,
              static_cast<float>(0.5 * kt * e.g.i_limit_a / static_cast<double>(p.j_kgm2)));
    EXPECT_EQ(r.stop_decel_rad_s2, r.speed_ramp_rad_s2);
    EXPECT_EQ(r.traj_a_max_rad_s2, r.speed_ramp_rad_s2);
    EXPECT_EQ(r.i_trip_a, std::min(1.6f * 10.0f, 0.98f * 60.0f));
    EXPECT_EQ(r.vbus_min_v, 24.0f);
    EXPECT_EQ(r.vbus_max_v, 72.0f);
    EXPECT_EQ(r.omega_max_rad_s, 1.5f * p.speed_max_rad_s);
    // bus power: fractions of the margin vbus_max - vbus = 24 V
    EXPECT_EQ(r.brake_on_v, 48.0f + 0.2f * 24.0f);
    EXPECT_EQ(r.brake_full_v, 48.0f + 0.45f * 24.0f);
    EXPECT_EQ(r.vbus_regen_start_v, 48.0f + 0.5f * 24.0f);
    EXPECT_EQ(r.vbus_regen_end_v, 48.0f + 0.8f * 24.0f);
    EXPECT_EQ(r.regen_id_a, std::min(10.0f, 0.5f * p.flux_wb / p.ld_h));
    // the drive's configuration takes them
    mc_drive_cfg_t c;
    ASSERT_EQ(mc_params_to_drive_cfg(&p, &c), MC_PARAMS_OK);
    EXPECT_EQ(c.i_max_a, static_cast<float>(e.g.i_limit_a));
    EXPECT_EQ(c.stop_decel_rad_s2, r.stop_decel_rad_s2);
    EXPECT_EQ(c.stop_kp_a_s_rad, r.speed_kp_a_s_rad);
    EXPECT_EQ(c.vbus_regen_end_v, r.vbus_regen_end_v);
    EXPECT_EQ(c.brake_full_v, 0.0f) << "no chopper unless brake_enable";
    EXPECT_FALSE(c.fw_enable);
    // a value set is taken as given, and what derives from it follows
    mc_params_t q = p;
    q.current_bw_rad_s = 1000.0f;
    q.speed_ramp_rad_s2 = 123.0f;
    q.brake_enable = 1u;
    q.vbus_max_v = 60.0f;
    ASSERT_EQ(mc_params_resolve(&q, &e), MC_GAINS_OK);
    EXPECT_EQ(e.p.current_bw_rad_s, 1000.0f);
    EXPECT_EQ(e.p.speed_bw_rad_s, 100.0f);
    EXPECT_EQ(e.p.stop_decel_rad_s2, 123.0f);
    EXPECT_EQ(e.p.brake_on_v, 48.0f + 0.2f * 12.0f);
    ASSERT_EQ(mc_params_to_drive_cfg(&q, &c), MC_PARAMS_OK);
    EXPECT_EQ(c.brake_on_v, e.p.brake_on_v);
    EXPECT_EQ(c.brake_full_v, e.p.brake_full_v);
}

// The bus limits come from the board (vbus_board_max_v): the derived trip
// is min(1.5 vbus_v, the board's), the braking thresholds follow its
// margin, the sensorless law's static voltage limit is the same value; a
// set trip above the board's, or a nominal bus not below it, is refused
// MC_PARAMS_ERR_BOARD. The VESC 6's values: 48 V nominal, 57 V limit (its
// divider reads 61.8 V; 1.5 vbus_v would be 72 V).
TEST(Params, BusLimitsFromTheBoard)
{
    mc_params_t p = mc_params_default;
    p.vbus_v = 48.0f;
    p.vbus_board_max_v = 57.0f;
    ASSERT_EQ(mc_params_validate(&p), MC_PARAMS_OK);
    mc_params_eff_t e;
    ASSERT_EQ(mc_params_resolve(&p, &e), MC_GAINS_OK);
    EXPECT_EQ(e.p.vbus_max_v, 57.0f);
    EXPECT_EQ(e.p.brake_on_v, 48.0f + 0.2f * 9.0f);
    EXPECT_EQ(e.p.vbus_regen_start_v, 48.0f + 0.5f * 9.0f);
    EXPECT_EQ(e.p.vbus_regen_end_v, 48.0f + 0.8f * 9.0f);
    mc_drive_cfg_t c;
    ASSERT_EQ(mc_params_to_drive_cfg(&p, &c), MC_PARAMS_OK);
    EXPECT_EQ(c.vbus_max_v, 57.0f);
    EXPECT_EQ(c.foc.v_abs_max_v, 57.0f);
    // the sensorless law's limit is the drive's trip (no second 1.5 rule)
    mc_ctrl_sls_cfg_t sc{};
    mc_law_sls_cfg(&e.m, &e.g, &sc);
    EXPECT_EQ(sc.vbus_max_v, 57.0f);
    // a board limit above 1.5 vbus_v leaves the nominal derivation
    p.vbus_board_max_v = 100.0f;
    ASSERT_EQ(mc_params_resolve(&p, &e), MC_GAINS_OK);
    EXPECT_EQ(e.p.vbus_max_v, 72.0f);
    // set values: at the board's limit taken, above it refused
    p.vbus_board_max_v = 57.0f;
    p.vbus_max_v = 57.0f;
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_OK);
    p.vbus_max_v = 57.5f;
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_ERR_BOARD);
    p.vbus_max_v = 0.0f;
    p.vbus_v = 57.0f;
    EXPECT_NE(mc_params_validate(&p) & MC_PARAMS_ERR_BOARD, 0u) << "nominal bus at the limit";
    // no board limit (0): the nominal rule alone
    p = mc_params_default;
    p.vbus_board_max_v = 0.0f;
    ASSERT_EQ(mc_params_resolve(&p, &e), MC_GAINS_OK);
    EXPECT_EQ(e.p.vbus_max_v, 1.5f * p.vbus_v);
}

// No safe gains: refused by name (MC_PARAMS_ERR_GAINS, the reason from
// mc_params_resolve); encoder_cpr 1 to 3 refused, 0 (none) accepted.
TEST(Params, NoGainsAndEncoderRefused)
{
    mc_params_t p = mc_params_default;
    p.pwm_hz = 5000u;
    p.ld_h = 1e-4f;
    p.lq_h = 1e-4f;
    p.r_ohm = 2.0f; // L/R = 50 us, shorter than two 200 us periods
    EXPECT_EQ(mc_params_validate(&p) & MC_PARAMS_ERR_GAINS, MC_PARAMS_ERR_GAINS);
    mc_params_eff_t e;
    EXPECT_NE(mc_params_resolve(&p, &e) & MC_GAINS_ERR_LR_SHORT, 0u);
    mc_drive_cfg_t c;
    EXPECT_EQ(mc_params_to_drive_cfg(&p, &c), MC_PARAMS_ERR_GAINS);
    p = mc_params_default;
    for (uint32_t cpr : {1u, 2u, 3u}) {
        p.encoder_cpr = cpr;
        EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_ERR_ENCODER) << cpr;
    }
    p.encoder_cpr = 0u;
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_OK);
    p.encoder_cpr = 4u;
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_OK);
}

TEST(Params, TripAboveSensorFullScaleRefused)
{
    mc_params_t p = mc_params_default;
    p.i_trip_a = 15.0f;
    p.i_sense_max_a = 14.0f; // i_max 10 fits (10 < 14 / 1.25), the trip does not
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_ERR_SENSE);
    p.i_trip_a = 14.0f;
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_OK);
    // the motor's i_max above what the sensor sees is clamped, not refused:
    // the drive's limit is i_sense / 1.25
    p.i_max_a = 30.0f;
    p.i_trip_a = 0.0f;
    mc_params_eff_t e;
    ASSERT_EQ(mc_params_resolve(&p, &e), MC_GAINS_OK);
    EXPECT_EQ(e.g.i_limit_a, static_cast<double>(14.0f) / 1.25);
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_OK);
}

TEST(Params, CrossChecks)
{
    mc_params_t p = mc_params_default;
    p.current_bw_rad_s = 0.3f * 20000.0f; // bw dt = 0.3: the limit itself is allowed
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_OK);
    p.pwm_hz = 19999u; // same bandwidth, slower loop: bw dt > 0.3
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
    p.vbus_min_v = 80.0f; // above vbus_max_v (derived, 72 V): the drive's own check
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_ERR_DRIVE);
    p = mc_params_default;
    p.r_ohm = std::numeric_limits<float>::quiet_NaN();
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_ERR_RANGE);
    // thermal derating (mc_drive_thermal.h): each value in range, the pair
    // refused when its end is not above its start or only one is 0
    p = mc_params_default;
    p.derate_motor_start_c = 120.0f;
    p.derate_motor_end_c = 100.0f;
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_ERR_DRIVE);
    p.derate_motor_end_c = 0.0f;
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_ERR_DRIVE);
    p.derate_motor_end_c = 140.0f;
    p.winding_model = 1u;
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_OK);
    p.derate_fet_start_c = 250.0f; // above the parameter's range (200)
    p.derate_fet_end_c = 260.0f;
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_ERR_RANGE);
    EXPECT_EQ(mc_params_validate(nullptr), MC_PARAMS_ERR_NULL);
}

} // namespace
