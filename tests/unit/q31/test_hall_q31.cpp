// The q31 Hall kernel and hand-over against their f32 twins on the same
// inputs: a rotor with a speed profile (accelerating, reversing, stopping)
// through ideal 120-degree sensors with hysteresis and an uneven edge
// table, and illegal codes.
#include <gtest/gtest.h>

#include <cmath>

#include "hall/mc_hall.h"
#include "hall/mc_hall_q31.h"
#include "hall/mc_hallobs.h"
#include "hall/mc_hallobs_q31.h"

namespace
{

constexpr double kPi = 3.14159265358979323846;
constexpr uint8_t kCodes[6] = {5u, 1u, 3u, 2u, 6u, 4u};
constexpr float kEdges[6] = {0.05f, 1.10f, 2.06f, 3.20f, 4.15f, 5.22f}; // an uneven table
constexpr float kDt = 50e-6f;
constexpr float kOmegaBase = 5000.0f; // rad/s el.

uint32_t code_at(double th, double shift)
{
    double t = std::fmod(th + shift, 2.0 * kPi);
    if (t < 0.0) {
        t += 2.0 * kPi;
    }
    int k = 5;
    for (int j = 0; j < 5; ++j) {
        if (t >= kEdges[j] && t < kEdges[j + 1]) {
            k = j;
        }
    }
    return kCodes[k];
}

double wrap_pi(double x)
{
    double w = std::fmod(x + kPi, 2.0 * kPi);
    if (w < 0.0) {
        w += 2.0 * kPi;
    }
    return w - kPi;
}

} // namespace

TEST(HallQ31, MatchesF32OnAProfile)
{
    mc_hall_q31_cfg_t c{};
    for (int k = 0; k < 6; ++k) {
        c.f.code_of_sector[k] = kCodes[k];
        c.f.edge_e_rad[k] = kEdges[k];
    }
    c.f.hysteresis_e_rad = 0.04f;
    c.f.dt_s = kDt;
    c.f.omega_min_e_rad_s = 20.0f;
    c.omega_base_rad_s = kOmegaBase;
    mc_hall_f32_t f{};
    mc_hall_q31_t q{};
    ASSERT_EQ(mc_hall_f32_init(&f, &c.f), MC_HALL_ERR_NONE);
    ASSERT_EQ(mc_hall_q31_init(&q, &c), MC_HALL_ERR_NONE);
    double th = 0.3;
    double w = 0.0;
    double dth_max = 0.0;
    double dw_max = 0.0;
    int interp = 0;
    int flag_diff = 0;
    for (int n = 0; n < 60000; ++n) {
        // 0..1 s: accelerate to 1500 rad/s; 1..2 s: reverse to -800; 2..3 s: stop
        const double t = n * kDt;
        const double a = (t < 1.0) ? 1500.0 : ((t < 2.0) ? -2300.0 : 800.0);
        w += a * kDt;
        th += w * kDt;
        const double shift = (w > 0.0) ? -0.02 : 0.02; // the band: seen late
        uint32_t code = code_at(th, shift);
        if (n % 7919 == 0) {
            code = 0u; // a glitch: illegal in both
        }
        mc_hall_f32_out_t of{};
        mc_hall_q31_out_t oq{};
        const uint32_t ef = mc_hall_f32_step(&f, code, &of);
        const uint32_t eq = mc_hall_q31_step(&q, code, &oq);
        ASSERT_EQ(ef, eq) << n;
        ASSERT_EQ(of.sector, oq.sector);
        ASSERT_EQ(of.edge, oq.edge);
        // interpolation starts and stops at omega_min in both (a speed
        // within rounding of the threshold may differ: counted, skipped)
        if (of.interpolating != oq.interpolating) {
            ++flag_diff;
            continue;
        }
        interp += of.interpolating ? 1 : 0;
        const double thq = mc_q31_angle_to_rad_f32(oq.theta_e);
        dth_max = std::fmax(dth_max, std::fabs(wrap_pi(thq - of.theta_e_rad)));
        const double wq = mc_q31_to_f32(oq.omega_e) * kOmegaBase;
        dw_max = std::fmax(dw_max, std::fabs(wq - of.omega_e_rad_s));
    }
    EXPECT_GT(interp, 30000);
    // the speed crosses omega_min a few times (the stop, the reversal):
    // only samples right at the threshold may decide differently
    EXPECT_LE(flag_diff, 4);
    // angle: f32 rounding of the edge plus travel (2.4e-7 rad near 2 pi, a
    // few operations) and the q31 step truncated to 2^-32 turn per sample
    // over a sector (1.5e-9 rad x samples): 2e-6 rad
    EXPECT_LE(dth_max, 2e-6);
    // speed: the q31 gain's and float's rounding, 1e-5 relative at 1500
    // rad/s, plus the q31 LSB of 5000 rad/s (2.3e-6): 0.02 rad/s
    EXPECT_LE(dw_max, 0.02);
}

TEST(HallQ31, RefusesBadScale)
{
    mc_hall_q31_cfg_t c{};
    for (int k = 0; k < 6; ++k) {
        c.f.code_of_sector[k] = kCodes[k];
        c.f.edge_e_rad[k] = kEdges[k];
    }
    c.f.dt_s = kDt;
    c.f.omega_min_e_rad_s = 20.0f;
    c.omega_base_rad_s = 0.0f;
    mc_hall_q31_t q{};
    EXPECT_EQ(mc_hall_q31_init(&q, &c), MC_HALL_ERR_SCALE);
    c.omega_base_rad_s = kOmegaBase;
    c.f.omega_min_e_rad_s = 1e-6f; // below 2^-32 turn per sample
    EXPECT_EQ(mc_hall_q31_init(&q, &c), MC_HALL_ERR_SCALE);
    c.f.omega_min_e_rad_s = 20.0f;
    c.f.code_of_sector[0] = 1u; // the f32 validation: twice
    EXPECT_EQ(mc_hall_q31_init(&q, &c), MC_HALL_ERR_CFG);
}

TEST(HallObsQ31, MatchesF32)
{
    mc_hallobs_q31_cfg_t c{};
    c.f.omega_start_e_rad_s = 200.0f;
    c.f.omega_end_e_rad_s = 400.0f;
    c.f.disagree_max_e_rad = 0.6f;
    c.omega_base_rad_s = kOmegaBase;
    mc_hallobs_f32_t f{};
    mc_hallobs_q31_t q{};
    ASSERT_EQ(mc_hallobs_f32_init(&f, &c.f), MC_HALLOBS_ERR_NONE);
    ASSERT_EQ(mc_hallobs_q31_init(&q, &c), MC_HALLOBS_ERR_NONE);
    double dmax = 0.0;
    for (int n = 0; n < 2000; ++n) {
        const float hall = static_cast<float>(std::fmod(0.37 * n, 2.0 * kPi));
        const float obs =
            static_cast<float>(std::fmod(0.37 * n + 0.5 * std::sin(0.01 * n), 2.0 * kPi));
        const float w = static_cast<float>(n % 600) - 50.0f;
        float tf = 0.0f;
        q31_t tq = 0;
        const uint32_t ef = mc_hallobs_f32_step(&f, hall, obs, w, &tf);
        const uint32_t eq =
            mc_hallobs_q31_step(&q, mc_q31_angle_from_rad_f32(hall), mc_q31_angle_from_rad_f32(obs),
                                mc_q31_from_f32(w / kOmegaBase), &tq);
        ASSERT_EQ(ef, eq) << n;
        dmax = std::fmax(dmax, std::fabs(wrap_pi(mc_q31_angle_to_rad_f32(tq) - tf)));
    }
    // the weight's rounding (q31 speed to 1/5000 rad/s: 5e-8 of the span)
    // times the offset (<= 0.6 rad), and float angles (2.4e-7 rad): 1e-6 rad
    EXPECT_LE(dmax, 1e-6);
}
