// The laws' gains in C (firmware/app/config/mc_gains.c, mc_law_cfg.c): the
// correctly rounded square root the derivation uses on targets without a
// libm, the gains of the parameter table's defaults, and the named refusals.
// The simulator's scenarios boot the drive application on a parameter table
// (sim/cli/app_params.hpp), which calls the same functions: there is no
// second derivation to compare with.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

extern "C" {
#include "mc_law_cfg.h"
}

namespace
{

uint64_t Bits(double x)
{
    uint64_t u = 0u;
    std::memcpy(&u, &x, sizeof u);
    return u;
}

// IEEE 754 sqrt is correctly rounded; mc_gains_sqrt must give the same bits
// as the host's sqrt (SSE2 SQRTSD) for any positive double, including
// perfect squares, values next to them, subnormals and the extremes.
TEST(GainsSqrt, BitIdenticalToIeeeSqrt)
{
    std::mt19937_64 rng(12345u);
    std::uniform_int_distribution<uint64_t> any(1u, 0x7FEFFFFFFFFFFFFFull);
    for (int i = 0; i < 200000; ++i) {
        const uint64_t u = any(rng);
        double x = 0.0;
        std::memcpy(&x, &u, sizeof x);
        ASSERT_EQ(Bits(mc_gains_sqrt(x)), Bits(std::sqrt(x))) << x;
    }
    for (double k = 1.0; k < 5000.0; k += 1.0) {
        const double sq = k * k;
        ASSERT_EQ(Bits(mc_gains_sqrt(sq)), Bits(k));
        ASSERT_EQ(Bits(mc_gains_sqrt(std::nextafter(sq, 0.0))),
                  Bits(std::sqrt(std::nextafter(sq, 0.0))));
        ASSERT_EQ(Bits(mc_gains_sqrt(std::nextafter(sq, 1e300))),
                  Bits(std::sqrt(std::nextafter(sq, 1e300))));
    }
    for (double x : {3.0, 0.2, 4.9e-324, 2.2250738585072014e-308, 1.7976931348623157e307, 1e-300}) {
        EXPECT_EQ(Bits(mc_gains_sqrt(x)), Bits(std::sqrt(x))) << x;
    }
    EXPECT_EQ(mc_gains_sqrt(0.0), 0.0);
    EXPECT_EQ(mc_gains_sqrt(std::numeric_limits<double>::infinity()),
              std::numeric_limits<double>::infinity());
    EXPECT_TRUE(std::isnan(mc_gains_sqrt(-1.0)));
}

// The table's defaults (the paper-002 test motor on a 48 V board) give every
// law valid gains, and each law's init accepts its configuration.
TEST(LawCfg, DefaultsGiveEveryLaw)
{
    mc_params_t p = mc_params_default;
    mc_gains_motor_t m{};
    mc_gains_t g{};
    ASSERT_EQ(mc_law_gains_from_params(&p, &m, &g), MC_GAINS_OK);
    // the table's 0s are derived (mc_gains.c), its other values taken as given
    EXPECT_EQ(g.cur_bw_rad_s, 0.08 * p.pwm_hz);
    EXPECT_EQ(g.i_limit_a, static_cast<double>(p.i_max_a)); // below the sensor's and the bus's
    EXPECT_EQ(g.pos_v_max_rad_s, 0.5 * g.speed_rated_eff_rad_s);
    p.current_bw_rad_s = 900.0f;
    p.traj_v_max_rad_s = 12.5f;
    ASSERT_EQ(mc_law_gains_from_params(&p, &m, &g), MC_GAINS_OK);
    EXPECT_EQ(g.cur_bw_rad_s, 900.0);
    EXPECT_EQ(g.pos_v_max_rad_s, 12.5);
    p = mc_params_default;
    ASSERT_EQ(mc_law_gains_from_params(&p, &m, &g), MC_GAINS_OK);
    // obs_* 0: derived, 0.02 of the rated speed the bus allows, and
    // min(300, 0.04 pwm_hz)
    EXPECT_EQ(g.obs_crit_rad_s, 0.02 * g.speed_rated_eff_rad_s);
    EXPECT_LE(g.speed_rated_eff_rad_s, static_cast<double>(p.speed_rated_rad_s));
    EXPECT_EQ(g.pll_bw_rad_s, std::min(300.0, 0.04 * p.pwm_hz));
    mc_ctrl_sls_cfg_t sc{};
    mc_law_sls_cfg(&m, &g, &sc);
    static mc_ctrl_sls_t sls;
    EXPECT_EQ(mc_ctrl_sls_init(&sls, &sc), 0u);
    mc_ctrl_pi2d_cfg_t dc{};
    EXPECT_EQ(mc_law_pi2d_cfg(&m, &g, &dc), 0u);
    static mc_ctrl_pi2d_t pi2d;
    EXPECT_EQ(mc_ctrl_pi2d_init(&pi2d, &dc), 0u);
    mc_ctrl_pos_cfg_t pc{};
    mc_law_pos_cfg(&m, &g, &pc);
    static mc_ctrl_pos_t pos;
    EXPECT_EQ(mc_ctrl_pos_init(&pos, &pc), 0u);
    mc_ctrl_speed_cfg_t spc{};
    mc_law_speed_cfg(&m, &g, &spc);
    static mc_ctrl_speed_t spd;
    EXPECT_EQ(mc_ctrl_speed_init(&spd, &spc), 0u);
    // the drive's reference for the speed laws the application builds
    EXPECT_TRUE(sc.ref_from_drive);
    EXPECT_TRUE(dc.ref_from_drive);
    EXPECT_TRUE(mc_ctrl_speed_ops(&spd)->uses_speed_ref);
    EXPECT_EQ(mc_ctrl_speed_ops(&spd)->outputs, MC_DRIVE_OUT_CURRENT);
    EXPECT_EQ(mc_ctrl_pos_ops(&pos)->outputs, MC_DRIVE_OUT_CURRENT);
    EXPECT_EQ(mc_ctrl_sls_ops(&sls)->outputs, MC_DRIVE_OUT_CURRENT);
    for (uint32_t law : {MC_LAW_SPEED_PI, MC_LAW_SPEED_SENSORLESS, MC_LAW_SPEED_PI2D}) {
        p.speed_law = law;
        EXPECT_EQ(mc_law_speed_check(&p), 0u) << law;
        EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_OK) << law;
    }
}

// The position law's input mode from its configuration (the application
// sets it from pos_input_mode): FILTER is taken at the first fast step and
// stays through an enable (reset); FILTER without a filter bandwidth, and
// a mode that does not exist, are refused at init.
TEST(LawCfg, PositionInputModeFromTheConfiguration)
{
    const mc_params_t p = mc_params_default;
    mc_gains_motor_t m{};
    mc_gains_t g{};
    ASSERT_EQ(mc_law_gains_from_params(&p, &m, &g), MC_GAINS_OK);
    mc_ctrl_pos_cfg_t pc{};
    mc_law_pos_cfg(&m, &g, &pc);
    EXPECT_EQ(pc.input_mode, MC_TRAJ_MODE_TRAP); // the builder's default
    static mc_ctrl_pos_t pos;
    pc.input_mode = MC_TRAJ_MODE_FILTER;
    ASSERT_GT(pc.traj.filter_bw_rad_s, 0.0f);
    ASSERT_EQ(mc_ctrl_pos_init(&pos, &pc), 0u);
    const mc_drive_ctrl_t *ops = mc_ctrl_pos_ops(&pos);
    ASSERT_EQ(ops->reset(ops->ctx), 0u);
    mc_drive_meas_t meas{};
    meas.have_encoder = true;
    meas.enc_cpr = 8192u;
    meas.vbus_v = 24.0f;
    meas.dt_s = pc.dt_s;
    meas.i_max_a = pc.iq_max_a;
    meas.regen_scale = 1.0f;
    mc_drive_out_t out{};
    ASSERT_EQ(ops->fast(ops->ctx, &meas, &out), 0u);
    EXPECT_EQ(pos.traj.mode, MC_TRAJ_MODE_FILTER);
    ASSERT_EQ(ops->reset(ops->ctx), 0u); // an enable
    ASSERT_EQ(ops->fast(ops->ctx, &meas, &out), 0u);
    EXPECT_EQ(pos.traj.mode, MC_TRAJ_MODE_FILTER);
    pc.traj.filter_bw_rad_s = 0.0f;
    EXPECT_EQ(mc_ctrl_pos_init(&pos, &pc), MC_CTRL_POS_ERR_TRAJ);
    mc_law_pos_cfg(&m, &g, &pc);
    pc.input_mode = static_cast<mc_traj_mode_t>(7);
    EXPECT_EQ(mc_ctrl_pos_init(&pos, &pc), MC_CTRL_POS_ERR_TRAJ);
}

// Each refusal by its name, and only for the law that needs it: the
// sensored PI takes any motor the drive takes.
TEST(LawCfg, RefusalsAreNamed)
{
    mc_params_t p = mc_params_default;
    p.ld_h = 1.2f * p.lq_h; // salient: the observer takes it (active flux), PI2D not
    p.speed_law = MC_LAW_SPEED_PI;
    EXPECT_EQ(mc_law_speed_check(&p), 0u);
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_OK);
    p.speed_law = MC_LAW_SPEED_SENSORLESS;
    EXPECT_EQ(mc_law_speed_check(&p), 0u);
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_OK);
    p.speed_law = MC_LAW_SPEED_PI2D;
    EXPECT_NE(mc_law_speed_check(&p) & MC_GAINS_ERR_SALIENT, 0u);

    // PI2D's empirical coupling bound: a light rotor with a strong magnet
    p = mc_params_default;
    p.speed_law = MC_LAW_SPEED_PI2D;
    p.j_kgm2 = 1e-6f;
    EXPECT_NE(mc_law_speed_check(&p) & MC_GAINS_ERR_PI2D_COUPLING, 0u);

    // the sensor's range too small for the motor: the usable current
    // i_sense / 1.25 is below 10 % of i_max (every law, the drive too)
    p = mc_params_default;
    p.speed_law = MC_LAW_SPEED_SENSORLESS;
    p.i_sense_max_a = 1.0f;
    EXPECT_EQ(mc_law_speed_check(&p), MC_GAINS_ERR_I_LIMIT);

    // no motor values: nothing derived
    mc_gains_motor_t m{};
    mc_gains_t g{};
    EXPECT_EQ(mc_gains_derive(&m, nullptr, &g), MC_GAINS_ERR_VALUE);
    EXPECT_EQ(mc_gains_derive(nullptr, nullptr, &g), MC_GAINS_ERR_VALUE);
}

// The 21-pole-pair U8-class outrunner (sim/motors/u8-class-kv100.toml) on
// a 48 V board at 8 kHz.
mc_gains_motor_t U8At8kHz()
{
    mc_gains_motor_t m{};
    m.r_ohm = 0.13;
    m.ld_h = 80.0e-6;
    m.lq_h = 80.0e-6;
    m.flux_wb = 2.63e-3;
    m.pole_pairs = 21.0;
    m.j_kgm2 = 2.0e-4;
    m.b_nm_s_rad = 1.0e-5;
    m.i_max_a = 30.0;
    m.i_rated_a = 15.0;
    m.speed_max_rad_s = 560.0;
    m.speed_rated_rad_s = 450.0;
    m.vbus_v = 48.0;
    m.pwm_hz = 8000.0;
    m.dead_time_s = 1.0e-7;
    m.i_sense_max_a = 60.0;
    m.delay_periods = 1.0;
    return m;
}

// The derived speed limit stops below omega_e T = 0.6 rad (the current loop's
// design bound with its delay compensation) where that comes before the bus
// voltage: a 21-pole-pair U8-class outrunner (sim/motors/u8-class-kv100.toml)
// at 8 kHz and 48 V. Where the voltage binds (24 kHz) the limit is 0.9 of the
// voltage-limited speed bit for bit, as before the delay bound existed.
TEST(GainsDerive, SpeedLimitStopsBelowTheCurrentLoopsAnglePerPeriod)
{
    mc_gains_motor_t m = U8At8kHz();
    mc_gains_t g{};
    ASSERT_EQ(mc_gains_derive(&m, nullptr, &g), 0u);
    // 0.9 x 0.6 rad / (21 x 125 us) = 205.714 rad/s; 1e-12 relative: the
    // double rounding of four operations
    const double w_d = 0.9 * 0.6 * 8000.0 / 21.0;
    EXPECT_NEAR(g.speed_limit_rad_s, w_d, 1e-12 * w_d);
    EXPECT_NEAR(g.speed_delay_rad_s, w_d / 0.9, 1e-12 * w_d);
    EXPECT_GT(0.9 * g.speed_voltage_rad_s, g.speed_limit_rad_s) << "the voltage must not bind";
    EXPECT_LE(g.speed_rated_eff_rad_s, g.speed_limit_rad_s);
    // omega_e T at the limit
    EXPECT_LE(g.speed_limit_rad_s * m.pole_pairs / m.pwm_hz, MC_GAINS_WE_T_MAX);

    m.pwm_hz = 24000.0;
    ASSERT_EQ(mc_gains_derive(&m, nullptr, &g), 0u);
    EXPECT_LT(g.speed_voltage_rad_s, g.speed_delay_rad_s);
    EXPECT_EQ(g.speed_limit_rad_s, 0.9 * g.speed_voltage_rad_s); // bit for bit
}

// The encoder tracking loop's bandwidth is bounded by the sensor: its
// resolution (bw_q with the chip's counts: 16384 for an AS5047P) and its
// latency (encoder_latency_s: 0.1 / latency once it is longer than a PWM
// period; an AS5047P's one period leaves the 0.1 / T bound as it was).
// The U8-class outrunner at 8 kHz: 0.1 / T = 800 rad/s binds without a latency.
TEST(GainsDerive, EncoderLoopFollowsTheSensorsResolutionAndLatency)
{
    mc_gains_motor_t m = U8At8kHz();
    m.encoder_cpr = 16384.0;
    mc_gains_t g{};
    ASSERT_EQ(mc_gains_derive(&m, nullptr, &g), 0u);
    EXPECT_EQ(g.enc_pll_bw_rad_s, 0.1 * 8000.0);
    m.encoder_latency_s = 1.0 / m.pwm_hz; // one period: the same bound
    ASSERT_EQ(mc_gains_derive(&m, nullptr, &g), 0u);
    EXPECT_EQ(g.enc_pll_bw_rad_s, 0.1 * 8000.0);
    m.encoder_latency_s = 400e-6; // an AS5047P without DAEC at a slow rate, say
    ASSERT_EQ(mc_gains_derive(&m, nullptr, &g), 0u);
    EXPECT_EQ(g.enc_pll_bw_rad_s, 0.1 / 400e-6); // 250 rad/s
    EXPECT_EQ(g.speed_wc_rad_s, 250.0 / 4.0);    // the speed PI follows it
    // a coarse sensor's resolution binds below both (a 90-count Hall class)
    m.encoder_latency_s = 0.0;
    m.encoder_cpr = 90.0;
    ASSERT_EQ(mc_gains_derive(&m, nullptr, &g), 0u);
    EXPECT_EQ(g.enc_pll_bw_rad_s, mc_gains_enc_bw_quant_rad_s(&m, &g));
    EXPECT_LT(g.enc_pll_bw_rad_s, 250.0);
}

} // namespace
