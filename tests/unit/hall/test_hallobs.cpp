// The Hall-to-observer hand-over (f32): VESC's rule against its closed
// form, continuity, and the disagreement check.
#include <gtest/gtest.h>

#include <cmath>

#include "hall/mc_hallobs.h"

namespace
{

mc_hallobs_f32_cfg_t cfg()
{
    mc_hallobs_f32_cfg_t c{};
    c.omega_start_e_rad_s = 200.0f;
    c.omega_end_e_rad_s = 400.0f;
    c.disagree_max_e_rad = 0.6f;
    return c;
}

} // namespace

TEST(HallObsF32, RefusesBadConfigs)
{
    mc_hallobs_f32_t st{};
    mc_hallobs_f32_cfg_t c = cfg();
    c.omega_end_e_rad_s = 200.0f; // start == end
    EXPECT_EQ(mc_hallobs_f32_init(&st, &c), MC_HALLOBS_ERR_CFG);
    c = cfg();
    c.omega_start_e_rad_s = 0.0f;
    EXPECT_EQ(mc_hallobs_f32_init(&st, &c), MC_HALLOBS_ERR_CFG);
    c = cfg();
    c.disagree_max_e_rad = 1.7f; // beyond 90 degrees: no torque there
    EXPECT_EQ(mc_hallobs_f32_init(&st, &c), MC_HALLOBS_ERR_CFG);
    c = cfg();
    c.disagree_max_e_rad = NAN;
    EXPECT_EQ(mc_hallobs_f32_init(&st, &c), MC_HALLOBS_ERR_CFG);
    EXPECT_EQ(mc_hallobs_f32_init(nullptr, &c), MC_HALLOBS_ERR_NULL);
}

// theta = hall + w wrap(obs - hall), w = clamp((|omega| - 200) / 200, 0, 1):
// the Hall angle below 200 rad/s, the observer's above 400, linear between,
// either sign of the speed; across the 0/2 pi seam the short way.
TEST(HallObsF32, RuleAndItsClosedForm)
{
    mc_hallobs_f32_t st{};
    const mc_hallobs_f32_cfg_t c = cfg();
    ASSERT_EQ(mc_hallobs_f32_init(&st, &c), MC_HALLOBS_ERR_NONE);
    float th = 0.0f;
    const float hall = 1.0f;
    const float obs = 1.4f;
    for (const float w : {0.0f, 100.0f, 200.0f, 250.0f, 300.0f, 399.0f, 400.0f, 1000.0f}) {
        for (const float sign : {1.0f, -1.0f}) {
            ASSERT_EQ(mc_hallobs_f32_step(&st, hall, obs, sign * w, &th), MC_HALLOBS_ERR_NONE);
            const double wt = std::fmin(std::fmax((w - 200.0) / 200.0, 0.0), 1.0);
            // float rounding of one product and sum near 1.4 rad: a few ulp
            EXPECT_NEAR(th, 1.0 + wt * 0.4, 1e-6) << w;
            EXPECT_NEAR(st.w_obs, wt, 1e-6);
        }
    }
    // across the seam: Hall 6.2, observer 0.1 (0.183 rad apart the short way)
    ASSERT_EQ(mc_hallobs_f32_step(&st, 6.2f, 0.1f, 300.0f, &th), MC_HALLOBS_ERR_NONE);
    const double want = std::fmod(6.2 + 0.5 * (0.1 + 2.0 * M_PI - 6.2), 2.0 * M_PI);
    EXPECT_NEAR(th, want, 1e-5);
}

// While the observer carries weight, a disagreement beyond the bound
// returns the Hall angle and raises MC_HALLOBS_ERR_DISAGREE (sticky);
// below the start speed the observer is not looked at.
TEST(HallObsF32, DisagreementFallsBackToHall)
{
    mc_hallobs_f32_t st{};
    const mc_hallobs_f32_cfg_t c = cfg();
    ASSERT_EQ(mc_hallobs_f32_init(&st, &c), MC_HALLOBS_ERR_NONE);
    float th = 0.0f;
    EXPECT_EQ(mc_hallobs_f32_step(&st, 1.0f, 3.0f, 100.0f, &th), MC_HALLOBS_ERR_NONE);
    EXPECT_FLOAT_EQ(th, 1.0f);
    EXPECT_EQ(mc_hallobs_f32_step(&st, 1.0f, 3.0f, 500.0f, &th), MC_HALLOBS_ERR_DISAGREE);
    EXPECT_FLOAT_EQ(th, 1.0f);
    EXPECT_EQ(st.w_obs, 0.0f);
    EXPECT_EQ(mc_hallobs_f32_step(&st, 1.0f, 1.1f, 500.0f, &th), MC_HALLOBS_ERR_NONE);
    EXPECT_FLOAT_EQ(th, 1.1f);
    EXPECT_EQ(st.flags, MC_HALLOBS_ERR_DISAGREE);
    EXPECT_EQ(mc_hallobs_f32_step(&st, 1.0f, NAN, 500.0f, &th), MC_HALLOBS_ERR_NAN);
    EXPECT_FLOAT_EQ(th, 1.0f);
    EXPECT_EQ(mc_hallobs_f32_step(&st, 1.0f, 1.0f, 500.0f, nullptr), MC_HALLOBS_ERR_NULL);
}

// Continuity: a speed ramp through the blend with a fixed offset between
// the two angles moves the output monotonically from one to the other, no
// step larger than the ramp's share of the offset.
TEST(HallObsF32, ContinuousThroughTheHandOver)
{
    mc_hallobs_f32_t st{};
    const mc_hallobs_f32_cfg_t c = cfg();
    ASSERT_EQ(mc_hallobs_f32_init(&st, &c), MC_HALLOBS_ERR_NONE);
    float prev = 2.0f;
    for (int n = 0; n <= 600; ++n) {
        float th = 0.0f;
        ASSERT_EQ(mc_hallobs_f32_step(&st, 2.0f, 2.3f, static_cast<float>(n), &th),
                  MC_HALLOBS_ERR_NONE);
        EXPECT_GE(th, prev - 1e-6f);
        EXPECT_LE(th - prev, 0.3f / 200.0f + 1e-6f); // 1 rad/s of 200 per sample
        prev = th;
    }
    EXPECT_FLOAT_EQ(prev, 2.3f);
}
