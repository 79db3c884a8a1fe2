// Hall + observer in the drive (firmware/app/drive/mc_drive_hallobs.h): the
// flux observer and its PLL beside the Hall angle, the hand-over's blend,
// the fallback on a disagreement, and the parameters that configure it
// (hall_obs_* 175-177, mc_law_hallobs_cfg). The blend's rule itself is
// tested in tests/unit/hall (test_hallobs.cpp); here what the drive's
// module adds, on a rotor written in the test: a PMSM turning at a constant
// speed with no current, whose back-EMF the voltage is (v = d flux / dt).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

extern "C" {
#include "config/mc_law_cfg.h"
#include "config/mc_params.h"
#include "mc_drive_hallobs.h"
}

namespace
{

constexpr double kPi = 3.14159265358979323846;
constexpr float kDt = 50e-6f;
constexpr float kFlux = 0.02f;

mc_drive_hallobs_cfg_t cfg()
{
    mc_drive_hallobs_cfg_t c{};
    c.blend.omega_start_e_rad_s = 200.0f;
    c.blend.omega_end_e_rad_s = 400.0f;
    c.blend.disagree_max_e_rad = 0.5f;
    c.r_ohm = 0.5f;
    c.l_h = 0.5e-3f;
    c.flux_wb = kFlux;
    // critical speed 20 rad/s el.: gamma = 4 omega / flux^2
    c.gamma = 4.0f * 20.0f / (kFlux * kFlux);
    c.resid_tol = 0.3f;
    c.resid_time_s = 0.05f;
    c.pll_bw_rad_s = 300.0f;
    c.omega_max_e_rad_s = 5000.0f;
    c.dt_s = kDt;
    c.pwm_delay_periods = 0u;
    return c;
}

double wrap_pi(double x)
{
    return std::remainder(x, 2.0 * kPi);
}

// The module's inputs for a rotor with no current that turned from th0 to
// th1 [rad el.] over the period that just ended at omega [rad/s el.]: the
// voltage is the back-EMF, the flux's chord over the period (exact for a
// constant speed); the Hall angle hall_err off the rotor's.
mc_drive_hallobs_in_t inputs(double th0, double th1, double omega, double hall_err)
{
    mc_drive_hallobs_in_t i{};
    i.v_alpha_prev_v = static_cast<float>(kFlux * (std::cos(th1) - std::cos(th0)) / kDt);
    i.v_beta_prev_v = static_cast<float>(kFlux * (std::sin(th1) - std::sin(th0)) / kDt);
    i.theta_hall_e_rad = static_cast<float>(std::fmod(th1 + hall_err + 100.0 * kPi, 2.0 * kPi));
    i.omega_hall_e_rad_s = static_cast<float>(omega);
    return i;
}

// A rotor at omega [rad/s el.] from angle 0, no current.
struct Rotor {
    double omega;
    double theta(long n) const
    {
        return omega * kDt * static_cast<double>(n);
    }
    mc_drive_hallobs_in_t in(long n, double hall_err) const
    {
        return inputs(theta(n - 1), theta(n), omega, hall_err);
    }
};

TEST(DriveHallObs, InitRefusesByNameAndLeavesTheStateAlone)
{
    mc_drive_hallobs_t h{};
    std::memset(&h, 0x5a, sizeof h);
    mc_drive_hallobs_t before;
    std::memcpy(&before, &h, sizeof h);
    mc_drive_hallobs_cfg_t c = cfg();
    EXPECT_EQ(mc_drive_hallobs_init(nullptr, &c), MC_DRIVE_HALLOBS_ERR_NULL);
    EXPECT_EQ(mc_drive_hallobs_init(&h, nullptr), MC_DRIVE_HALLOBS_ERR_NULL);
    struct Case {
        void (*bad)(mc_drive_hallobs_cfg_t *);
        uint32_t err;
    };
    const Case cases[] = {
        {[](mc_drive_hallobs_cfg_t *x) { x->blend.omega_end_e_rad_s = 200.0f; },
         MC_DRIVE_HALLOBS_ERR_BLEND}, // end not above start
        {[](mc_drive_hallobs_cfg_t *x) { x->blend.omega_start_e_rad_s = 0.0f; },
         MC_DRIVE_HALLOBS_ERR_BLEND},
        {[](mc_drive_hallobs_cfg_t *x) { x->blend.disagree_max_e_rad = 0.0f; },
         MC_DRIVE_HALLOBS_ERR_BLEND},
        {[](mc_drive_hallobs_cfg_t *x) { x->blend.disagree_max_e_rad = 1.6f; },
         MC_DRIVE_HALLOBS_ERR_BLEND}, // above pi/2: no torque left at the bound
        {[](mc_drive_hallobs_cfg_t *x) { x->flux_wb = 0.0f; }, MC_DRIVE_HALLOBS_ERR_OBSERVER},
        {[](mc_drive_hallobs_cfg_t *x) { x->l_h = -1e-3f; }, MC_DRIVE_HALLOBS_ERR_OBSERVER},
        {[](mc_drive_hallobs_cfg_t *x) { x->pll_bw_rad_s = 0.0f; }, MC_DRIVE_HALLOBS_ERR_PLL},
        {[](mc_drive_hallobs_cfg_t *x) { x->pwm_delay_periods = 4u; }, MC_DRIVE_HALLOBS_ERR_TIMING},
    };
    for (const Case &k : cases) {
        mc_drive_hallobs_cfg_t b = cfg();
        k.bad(&b);
        EXPECT_EQ(mc_drive_hallobs_init(&h, &b), k.err);
        EXPECT_EQ(std::memcmp(&h, &before, sizeof h), 0);
    }
    EXPECT_EQ(mc_drive_hallobs_init(&h, &c), MC_DRIVE_HALLOBS_ERR_NONE);
    EXPECT_FALSE(h.running);
    EXPECT_EQ(h.flags, 0u);
}

// Below the start the Hall angle is returned as it is; well above the end
// the observer's, which follows the rotor: a Hall angle 0.3 rad off (within
// disagree_max 0.5) is corrected to the observer's error.
TEST(DriveHallObs, HallBelowTheStartObserverAboveTheEnd)
{
    mc_drive_hallobs_t h{};
    const mc_drive_hallobs_cfg_t c = cfg();
    ASSERT_EQ(mc_drive_hallobs_init(&h, &c), MC_DRIVE_HALLOBS_ERR_NONE);
    const Rotor slow{100.0};
    for (long n = 1; n <= 4000; ++n) {
        const mc_drive_hallobs_in_t in = slow.in(n, 0.3);
        const float th = mc_drive_hallobs_step(&h, &in);
        // the observer's weight is 0: the Hall angle to float rounding
        ASSERT_NEAR(wrap_pi(th - in.theta_hall_e_rad), 0.0, 1e-5) << n;
        ASSERT_EQ(h.w_obs, 0.0f);
    }
    mc_drive_hallobs_stop(&h);
    const Rotor fast{1000.0};
    double err_max = 0.0;
    for (long n = 1; n <= 8000; ++n) {
        const mc_drive_hallobs_in_t in = fast.in(n, 0.3);
        const float th = mc_drive_hallobs_step(&h, &in);
        if (n > 4000) { // started at the Hall angle: 4 time scales (2 / (gamma flux^2)
                        // = 25 ms) without weight, then 4 more to converge
            err_max = std::fmax(err_max, std::fabs(wrap_pi(th - fast.theta(n))));
            ASSERT_EQ(h.w_obs, 1.0f) << n;
        }
    }
    // the observer's own error (float rounding of the flux integration; no
    // current here): 10 mrad, 30 times below the Hall's 0.3 rad
    EXPECT_LT(err_max, 0.01);
    EXPECT_EQ(h.flags, 0u);
}

// Up through the hand-over and back down (100 -> 1000 -> 100 rad/s el.,
// 0.25 rad/s per step) with the Hall angle 0.3 rad off: the angle used moves
// from one step to the next by the rotor's travel plus the change of the
// weight times the disagreement, (0.25 / 200) x 0.3 = 0.4 mrad, plus the
// observer's noise: bound 2 mrad on |change of (used - true)|. Without the
// settle or with a switch instead of the ramp it would be 0.3 rad.
TEST(DriveHallObs, ContinuousThroughTheHandOverBothWays)
{
    mc_drive_hallobs_t h{};
    const mc_drive_hallobs_cfg_t c = cfg();
    ASSERT_EQ(mc_drive_hallobs_init(&h, &c), MC_DRIVE_HALLOBS_ERR_NONE);
    double th = 0.0;
    double prev = std::nan("");
    double jump = 0.0;
    bool handed = false;
    const long n_ramp = 3600; // 900 rad/s at 0.25 rad/s per step
    for (long n = 1; n <= 4 * n_ramp; ++n) {
        // hold 100, ramp up, ramp down, hold 100
        const long m = n - n_ramp;
        const double w = (m <= 0)            ? 100.0
                         : (m <= n_ramp)     ? 100.0 + 0.25 * static_cast<double>(m)
                         : (m <= 2 * n_ramp) ? 1000.0 - 0.25 * static_cast<double>(m - n_ramp)
                                             : 100.0;
        const double th0 = th;
        th += w * kDt;
        const mc_drive_hallobs_in_t in = inputs(th0, th, w, 0.3);
        const double e = wrap_pi(mc_drive_hallobs_step(&h, &in) - th);
        if (!std::isnan(prev)) {
            jump = std::fmax(jump, std::fabs(wrap_pi(e - prev)));
        }
        prev = e;
        handed = handed || (h.w_obs == 1.0f);
    }
    EXPECT_TRUE(handed);
    EXPECT_EQ(h.w_obs, 0.0f); // back on the Hall angle
    EXPECT_LT(jump, 0.002);
    EXPECT_EQ(h.flags, 0u);
}

// A disagreement while the observer carries weight (the Hall angle 0.8 rad
// off, disagree_max 0.5): the Hall angle from that step on, latched until
// the next start; the cause stays in flags after it.
TEST(DriveHallObs, DisagreeFallsBackToTheHallAngleUntilTheNextStart)
{
    mc_drive_hallobs_t h{};
    const mc_drive_hallobs_cfg_t c = cfg();
    ASSERT_EQ(mc_drive_hallobs_init(&h, &c), MC_DRIVE_HALLOBS_ERR_NONE);
    const Rotor fast{1000.0};
    long n_fall = -1;
    for (long n = 1; n <= 8000; ++n) {
        const mc_drive_hallobs_in_t in = fast.in(n, 0.8);
        const float th = mc_drive_hallobs_step(&h, &in);
        if (h.fallback && n_fall < 0)
            n_fall = n;
        if (n_fall > 0) {
            ASSERT_NEAR(wrap_pi(th - in.theta_hall_e_rad), 0.0, 1e-5) << n;
            ASSERT_EQ(h.w_obs, 0.0f);
        }
    }
    ASSERT_GT(n_fall, 0);
    EXPECT_EQ(h.flags & MC_HALLOBS_ERR_DISAGREE, MC_HALLOBS_ERR_DISAGREE);
    mc_drive_hallobs_stop(&h);
    EXPECT_FALSE(h.fallback);
    EXPECT_EQ(h.flags & MC_HALLOBS_ERR_DISAGREE, MC_HALLOBS_ERR_DISAGREE); // sticky
}

// The parameters: off by default (no refusal, nothing to configure); on,
// the refusals are named by mc_law_hallobs_cfg and the set by
// MC_PARAMS_ERR_HALL_OBS.
TEST(DriveHallObs, ParametersConfigureAndRefuseByName)
{
    mc_params_t p = mc_params_default;
    EXPECT_EQ(p.hall_obs_end_e_rad_s, 0.0f);
    p.encoder_type = MC_PARAMS_ENCODER_HALL;
    p.encoder_cpr = 6u * p.pole_pairs;
    ASSERT_EQ(mc_params_validate(&p), MC_PARAMS_OK);
    p.hall_obs_start_e_rad_s = 300.0f;
    p.hall_obs_end_e_rad_s = 600.0f;
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_OK);
    mc_drive_hallobs_cfg_t hc;
    ASSERT_EQ(mc_law_hallobs_cfg(&p, &hc), MC_DRIVE_HALLOBS_ERR_NONE);
    // the sensorless law's observer: its R, L (lq), flux and PLL
    EXPECT_EQ(hc.flux_wb, p.flux_wb);
    EXPECT_EQ(hc.l_h, p.lq_h);
    EXPECT_EQ(hc.blend.disagree_max_e_rad, p.hall_obs_disagree_e_rad);
    EXPECT_GT(hc.gamma, 0.0f);
    struct Case {
        void (*bad)(mc_params_t *);
        uint32_t err;
    };
    const Case cases[] = {
        {[](mc_params_t *x) { x->hall_obs_start_e_rad_s = 600.0f; }, MC_DRIVE_HALLOBS_ERR_BLEND},
        {[](mc_params_t *x) { x->hall_obs_start_e_rad_s = 0.0f; }, MC_DRIVE_HALLOBS_ERR_BLEND},
        {[](mc_params_t *x) { x->hall_obs_disagree_e_rad = 0.0f; }, MC_DRIVE_HALLOBS_ERR_BLEND},
        {[](mc_params_t *x) {
             x->encoder_type = 0u;
             x->encoder_cpr = 8192u;
         },
         MC_DRIVE_HALLOBS_ERR_NOT_HALL},
        {[](mc_params_t *x) { x->ld_h = 2.0f * x->lq_h; }, MC_DRIVE_HALLOBS_ERR_MOTOR},
    };
    for (const Case &k : cases) {
        mc_params_t q = p;
        k.bad(&q);
        EXPECT_EQ(mc_law_hallobs_cfg(&q, &hc), k.err);
        EXPECT_EQ(mc_params_validate(&q) & MC_PARAMS_ERR_HALL_OBS, MC_PARAMS_ERR_HALL_OBS);
    }
    mc_params_t q = p;
    q.flux_wb = 0.0f; // the observer needs the flux
    EXPECT_EQ(mc_law_hallobs_cfg(&q, &hc) & MC_DRIVE_HALLOBS_ERR_MOTOR, MC_DRIVE_HALLOBS_ERR_MOTOR);
}

} // namespace
