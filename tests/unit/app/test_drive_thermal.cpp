// Thermal derating and the winding model (firmware/app/drive/mc_drive_thermal.h):
// the steady rise and the winding's time constant against their closed
// forms, the derating factor and its warning's hysteresis, the refusal of
// bad parameters, and the drive's current limit following the factor.
#include <cmath>

#include <gtest/gtest.h>

#include "app_test_fixture.h"
#include "mc_drive_thermal.h"

namespace apptest
{
namespace
{

constexpr float kAlpha = MC_DRIVE_THERMAL_ALPHA_CU_1_K;

mc_drive_thermal_cfg_t ModelCfg()
{
    mc_drive_thermal_cfg_t c{};
    c.model_enable = true;
    c.r_ohm = 0.2f;
    c.i_rated_a = 10.0f;
    c.rise_k = 80.0f;
    c.share = 0.3f;
    c.tau_w_s = 0.2f; // short time constants: the test's runs stay short
    c.tau_h_s = 2.0f;
    c.ambient_c = 25.0f;
    c.motor_start_c = 0.0f;
    c.motor_end_c = 0.0f;
    return c;
}

const mc_drive_thermal_in_t kNoSensor = {0.0f, 0.0f, false, false};

// Runs the model at a constant current for t_s in 1 ms slow steps.
float RunModel(mc_drive_thermal_t *th, float i_a, float t_s)
{
    const int n = static_cast<int>(std::lround(t_s / 1e-3f));
    for (int k = 0; k < n; ++k) {
        (void)mc_drive_thermal_step(th, 1e-3f, i_a * i_a, &kNoSensor);
    }
    return th->t_w_c;
}

// The steady winding rise, closed form of T - Ta = K (1 + a (T - 20)) with
// K = rise (i / i_rated)^2 / (1 + a (Ta + rise - 20)).
double SteadyRise(const mc_drive_thermal_cfg_t &c, double i_a)
{
    const double ta = c.ambient_c;
    const double k = c.rise_k * (i_a / c.i_rated_a) * (i_a / c.i_rated_a) /
                     (1.0 + kAlpha * (ta + c.rise_k - 20.0));
    const double r0 = 1.0 + kAlpha * (ta - 20.0);
    return k * r0 / (1.0 - k * kAlpha);
}

TEST(DriveThermal, SteadyRiseAtRatedCurrentIsTheRatedRise)
{
    mc_drive_thermal_t th{};
    const mc_drive_thermal_cfg_t c = ModelCfg();
    ASSERT_EQ(MC_DRIVE_THERMAL_ERR_NONE, mc_drive_thermal_init(&th, &c));
    // 40 s = 20 housing time constants (80 s at 12 A, whose rising R slows
    // the slow mode by about half): the transient left is below 1e-4 of
    // the rise.
    // Tolerance 0.05 K: float rounding of 40000 backward-Euler steps (the
    // method's steady state is exact).
    EXPECT_NEAR(25.0 + 80.0, RunModel(&th, 10.0f, 40.0f), 0.05);
    EXPECT_NEAR(25.0 + SteadyRise(c, 12.0), RunModel(&th, 12.0f, 80.0f), 0.05);
    EXPECT_NEAR(25.0 + SteadyRise(c, 5.0), RunModel(&th, 5.0f, 40.0f), 0.05);
}

TEST(DriveThermal, CatalogueTimeConstantsReachTheSteadyStateInFloat)
{
    // tau_h 900 s in 1 ms steps: an increment is below half a float ulp of
    // 100 C long before the steady state (uncompensated sums stop about
    // 7 K short). 12000 s is 12 times the slow mode (about tau_h +
    // tau_w / share = 1000 s): the transient left is below 1e-5 of the rise;
    // tolerance 0.05 K for the rounding the compensation leaves.
    mc_drive_thermal_cfg_t c = ModelCfg();
    c.tau_w_s = 30.0f;
    c.tau_h_s = 900.0f;
    mc_drive_thermal_t th{};
    ASSERT_EQ(MC_DRIVE_THERMAL_ERR_NONE, mc_drive_thermal_init(&th, &c));
    EXPECT_NEAR(25.0 + 80.0, RunModel(&th, 10.0f, 12000.0f), 0.05);
}

TEST(DriveThermal, AResistanceErrorCancelsInTheSteadyRise)
{
    // The network is derived from the same r_ohm the losses use: 10 % off
    // changes neither the steady rise nor the time constants.
    mc_drive_thermal_cfg_t c = ModelCfg();
    c.r_ohm *= 1.1f;
    mc_drive_thermal_t th{};
    ASSERT_EQ(MC_DRIVE_THERMAL_ERR_NONE, mc_drive_thermal_init(&th, &c));
    EXPECT_NEAR(25.0 + SteadyRise(c, 12.0), RunModel(&th, 12.0f, 80.0f), 0.05);
}

TEST(DriveThermal, WindingTimeConstant)
{
    // With the housing's capacity huge (tau_h 1e5 s) the housing stays at
    // ambient over a second (its rise < 1e-3 K), and the winding alone is
    //   C_w dx/dt = P0 (1 + a' x) - x / R_wh,  a' = a / (1 + a (Ta - 20)),
    // x(t) = x_inf (1 - exp(-t / tau')), tau' = C_w / (1/R_wh - P0 a').
    mc_drive_thermal_cfg_t c = ModelCfg();
    c.tau_h_s = 1.0e5f;
    mc_drive_thermal_t th{};
    ASSERT_EQ(MC_DRIVE_THERMAL_ERR_NONE, mc_drive_thermal_init(&th, &c));
    const double i = 20.0;
    const double p0 = 1.5 * c.r_ohm * i * i;
    const double ap = kAlpha / (1.0 + kAlpha * (c.ambient_c - 20.0));
    const double g = 1.0 / th.r_wh_k_w - p0 * ap;
    ASSERT_GT(g, 0.0);
    const double tau = th.c_w_j_k / g;
    const double x_inf = p0 / g;
    EXPECT_NEAR(c.tau_w_s / th.r_wh_k_w, th.c_w_j_k, 1e-3 * th.c_w_j_k);
    const double t1 = RunModel(&th, static_cast<float>(i), static_cast<float>(tau)) - 25.0;
    // Backward Euler with h = 1 ms against tau' of about 0.2 s: the state
    // lags by about h / 2 = 0.5 ms, 0.25 % of x_inf at t = tau (tolerance
    // 0.5 %; one slow step of rounding of the run's length adds 0.2 %).
    EXPECT_NEAR(x_inf * (1.0 - std::exp(-1.0)), t1, 5e-3 * x_inf);
    const double t3 = RunModel(&th, static_cast<float>(i), static_cast<float>(2.0 * tau)) - 25.0;
    EXPECT_NEAR(x_inf * (1.0 - std::exp(-3.0)), t3, 5e-3 * x_inf);
}

TEST(DriveThermal, DeratingFactorIsLinearBetweenStartAndEnd)
{
    EXPECT_FLOAT_EQ(1.0f, mc_drive_thermal_factor(80.0f, 80.0f, 100.0f));
    EXPECT_FLOAT_EQ(0.75f, mc_drive_thermal_factor(85.0f, 80.0f, 100.0f));
    EXPECT_FLOAT_EQ(0.5f, mc_drive_thermal_factor(90.0f, 80.0f, 100.0f));
    EXPECT_FLOAT_EQ(0.0f, mc_drive_thermal_factor(100.0f, 80.0f, 100.0f));
    EXPECT_FLOAT_EQ(0.0f, mc_drive_thermal_factor(150.0f, 80.0f, 100.0f));
    EXPECT_FLOAT_EQ(1.0f, mc_drive_thermal_factor(150.0f, 0.0f, 0.0f)); // off
}

TEST(DriveThermal, EachThermistorDeratesAndTheWarningHasHysteresis)
{
    mc_drive_thermal_cfg_t c{};
    c.fet_start_c = 80.0f;
    c.fet_end_c = 100.0f;
    c.motor_start_c = 100.0f;
    c.motor_end_c = 120.0f;
    mc_drive_thermal_t th{};
    ASSERT_EQ(MC_DRIVE_THERMAL_ERR_NONE, mc_drive_thermal_init(&th, &c));
    mc_drive_thermal_in_t in = {90.0f, 40.0f, true, true};
    EXPECT_FLOAT_EQ(0.5f, mc_drive_thermal_step(&th, 1e-3f, 0.0f, &in));
    EXPECT_TRUE(th.derating);
    in = {40.0f, 115.0f, true, true};
    EXPECT_FLOAT_EQ(0.25f, mc_drive_thermal_step(&th, 1e-3f, 0.0f, &in));
    in = {90.0f, 115.0f, true, true}; // the lower factor wins
    EXPECT_FLOAT_EQ(0.25f, mc_drive_thermal_step(&th, 1e-3f, 0.0f, &in));
    // back below the start: full current, the warning still on within the
    // hysteresis (5 K), off below it
    in = {78.0f, 40.0f, true, true};
    EXPECT_FLOAT_EQ(1.0f, mc_drive_thermal_step(&th, 1e-3f, 0.0f, &in));
    EXPECT_TRUE(th.derating);
    in = {74.0f, 40.0f, true, true};
    (void)mc_drive_thermal_step(&th, 1e-3f, 0.0f, &in);
    EXPECT_FALSE(th.derating);
    // a sensor without a reading derates nothing (the drive's trip handles it)
    in = {500.0f, 500.0f, false, false};
    EXPECT_FLOAT_EQ(1.0f, mc_drive_thermal_step(&th, 1e-3f, 0.0f, &in));
}

TEST(DriveThermal, TheEstimateDeratesAndStartsFromTheMotorThermistor)
{
    mc_drive_thermal_cfg_t c = ModelCfg();
    c.motor_start_c = 90.0f;
    c.motor_end_c = 110.0f;
    mc_drive_thermal_t th{};
    ASSERT_EQ(MC_DRIVE_THERMAL_ERR_NONE, mc_drive_thermal_init(&th, &c));
    // power-up: the estimate starts at the motor thermistor's reading
    const mc_drive_thermal_in_t hot = {30.0f, 95.0f, true, false};
    const mc_drive_thermal_in_t hot_m = {30.0f, 95.0f, false, true};
    (void)mc_drive_thermal_step(&th, 1e-3f, 0.0f, &hot_m);
    EXPECT_NEAR(95.0f, th.t_w_c, 0.01f);
    mc_drive_thermal_t th2{};
    ASSERT_EQ(MC_DRIVE_THERMAL_ERR_NONE, mc_drive_thermal_init(&th2, &c));
    (void)mc_drive_thermal_step(&th2, 1e-3f, 0.0f, &hot); // only the FET: max(ambient, FET)
    EXPECT_NEAR(30.0f, th2.t_w_c, 0.01f);
    // at 2x rated the steady rise (far above the end) would pass the end:
    // the factor falls as the estimate crosses the start
    mc_drive_thermal_t th3{};
    ASSERT_EQ(MC_DRIVE_THERMAL_ERR_NONE, mc_drive_thermal_init(&th3, &c));
    (void)RunModel(&th3, 20.0f, 10.0f);
    EXPECT_GT(th3.t_w_c, 90.0f);
    EXPECT_LT(th3.k, 1.0f);
    EXPECT_NEAR(mc_drive_thermal_factor(th3.t_w_c, 90.0f, 110.0f), th3.k, 1e-6f);
}

// The scale of R the drive hands its current loop and its law: copper's
// R(T_w) / R(ambient) at the estimate, with r_follow and the model started;
// 1 otherwise. Exact to float rounding (tolerance 1e-6 relative: a
// handful of float operations).
TEST(DriveThermal, RScaleIsCoppersFactorAtTheEstimate)
{
    mc_drive_thermal_cfg_t c = ModelCfg();
    c.r_follow = true;
    mc_drive_thermal_t th{};
    ASSERT_EQ(MC_DRIVE_THERMAL_ERR_NONE, mc_drive_thermal_init(&th, &c));
    EXPECT_EQ(1.0f, mc_drive_thermal_r_scale(&th)); // not started yet
    const mc_drive_thermal_in_t hot_m = {30.0f, 120.0f, false, true};
    (void)mc_drive_thermal_step(&th, 1e-3f, 0.0f, &hot_m);
    const double want = (1.0 + kAlpha * (th.t_w_c - 20.0)) / (1.0 + kAlpha * (25.0 - 20.0));
    EXPECT_NEAR(want, mc_drive_thermal_r_scale(&th), 1e-6 * want);
    EXPECT_GT(mc_drive_thermal_r_scale(&th), 1.36f); // 120 C against 25 C: +37 %
    th.cfg.r_follow = false;
    EXPECT_EQ(1.0f, mc_drive_thermal_r_scale(&th));
    th.cfg.r_follow = true;
    th.cfg.model_enable = false;
    EXPECT_EQ(1.0f, mc_drive_thermal_r_scale(&th));
}

TEST(DriveThermal, BadParametersAreRefusedAndChangeNothing)
{
    auto Refused = [](const mc_drive_thermal_cfg_t &c, uint32_t want) {
        mc_drive_thermal_t th{};
        th.k = 0.123f;
        EXPECT_EQ(want, mc_drive_thermal_init(&th, &c));
        EXPECT_EQ(0.123f, th.k) << "state written on error";
    };
    mc_drive_thermal_cfg_t c = ModelCfg();
    c.fet_start_c = 100.0f;
    c.fet_end_c = 80.0f; // end below start
    Refused(c, MC_DRIVE_THERMAL_ERR_DERATE);
    c = ModelCfg();
    c.motor_start_c = 0.0f;
    c.motor_end_c = 120.0f; // only one of the pair 0
    Refused(c, MC_DRIVE_THERMAL_ERR_DERATE);
    c = ModelCfg();
    c.motor_start_c = kNaN;
    c.motor_end_c = 120.0f;
    Refused(c, MC_DRIVE_THERMAL_ERR_DERATE);
    const float bad[] = {0.0f, -1.0f, kNaN, kInf};
    for (float v : bad) {
        for (int f = 0; f < 5; ++f) {
            c = ModelCfg();
            float *p[5] = {&c.r_ohm, &c.i_rated_a, &c.rise_k, &c.tau_w_s, &c.tau_h_s};
            *p[f] = v;
            Refused(c, MC_DRIVE_THERMAL_ERR_MODEL);
        }
    }
    c = ModelCfg();
    c.share = 1.0f;
    Refused(c, MC_DRIVE_THERMAL_ERR_MODEL);
    c = ModelCfg();
    c.ambient_c = kNaN;
    Refused(c, MC_DRIVE_THERMAL_ERR_MODEL);
    c = ModelCfg();
    c.model_enable = false;
    c.r_ohm = 0.0f; // the model's parameters matter only with the model on
    mc_drive_thermal_t th{};
    EXPECT_EQ(MC_DRIVE_THERMAL_ERR_NONE, mc_drive_thermal_init(&th, &c));
    EXPECT_EQ(MC_DRIVE_THERMAL_ERR_NULL, mc_drive_thermal_init(nullptr, &c));
}

class AppDriveThermal : public AppDrive
{
};

TEST_F(AppDriveThermal, TheDrivesCurrentLimitFollowsTheFetDerating)
{
    cfg.thermal.fet_start_c = 80.0f;
    cfg.thermal.fet_end_c = 100.0f;
    InitDrive();
    ASSERT_EQ(0, mc_hal_fake_adc_set_temp(&fake, 95.0f, 0.0f, MC_HAL_ADC_TEMP_VALID_POWER_STAGE));
    ASSERT_EQ(0, mc_drive_set_current_ref(&d, 0.0f, kIMax));
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
    GoodSample();
    (void)mc_drive_fast_step(&d);
    EXPECT_FLOAT_EQ(kIMax, d.tm.iq_ref_a); // no slow step yet: full limit
    mc_drive_slow_step(&d);
    GoodSample();
    (void)mc_drive_fast_step(&d);
    EXPECT_FLOAT_EQ(0.25f * kIMax, d.tm.iq_ref_a);
    EXPECT_TRUE(d.thermal.derating);
    EXPECT_EQ(MC_DRIVE_MODE_CURRENT, d.mode); // derating does not stop the drive
}

TEST_F(AppDriveThermal, BadThermalConfigIsADriveConfigError)
{
    cfg.thermal.motor_start_c = 120.0f;
    cfg.thermal.motor_end_c = 100.0f;
    mc_drive_t probe{};
    EXPECT_EQ(MC_DRIVE_CFG_ERR_THERMAL, mc_drive_init(&probe, &cfg, hal));
    EXPECT_EQ(MC_DRIVE_CFG_ERR_THERMAL, mc_drive_check_cfg(&cfg));
}

} // namespace
} // namespace apptest
