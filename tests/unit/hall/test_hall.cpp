// The Hall kernel (f32) against closed forms: ideal 120-degree sensors
// written here (sector k of 60 degrees from angle 0 reads the k-th code of
// the usual sequence 101, 100, 110, 010, 011, 001 with A bit 0), a rotor
// at a constant speed sampled at dt.
#include <gtest/gtest.h>

#include <cmath>

#include "hall/mc_hall.h"

namespace
{

constexpr double kPi = 3.14159265358979323846;
constexpr uint8_t kCodes[6] = {5u, 1u, 3u, 2u, 6u, 4u};
constexpr float kDt = 50e-6f; // 20 kHz

mc_hall_f32_cfg_t ideal_cfg()
{
    mc_hall_f32_cfg_t c{};
    for (int k = 0; k < 6; ++k) {
        c.code_of_sector[k] = kCodes[k];
        c.edge_e_rad[k] = static_cast<float>(k * kPi / 3.0);
    }
    c.hysteresis_e_rad = 0.0f;
    c.dt_s = kDt;
    c.omega_min_e_rad_s = 20.0f;
    return c;
}

// The ideal sensors' code at electrical angle th (any real).
uint32_t code_at(double th)
{
    double t = std::fmod(th, 2.0 * kPi);
    if (t < 0.0) {
        t += 2.0 * kPi;
    }
    int k = static_cast<int>(t / (kPi / 3.0));
    if (k > 5) {
        k = 5;
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

TEST(HallF32, RefusesBadTables)
{
    mc_hall_f32_t st{};
    mc_hall_f32_cfg_t c = ideal_cfg();
    c.code_of_sector[3] = 1u; // twice
    EXPECT_EQ(mc_hall_f32_init(&st, &c), MC_HALL_ERR_CFG);
    c = ideal_cfg();
    c.code_of_sector[2] = 6u; // 1 -> 6 -> 2: two sensors at once
    c.code_of_sector[4] = 3u;
    EXPECT_EQ(mc_hall_f32_init(&st, &c), MC_HALL_ERR_CFG);
    c = ideal_cfg();
    c.code_of_sector[0] = 8u; // not a 3-bit code
    EXPECT_EQ(mc_hall_f32_init(&st, &c), MC_HALL_ERR_CFG);
    c = ideal_cfg();
    std::swap(c.edge_e_rad[1], c.edge_e_rad[2]); // out of order
    EXPECT_EQ(mc_hall_f32_init(&st, &c), MC_HALL_ERR_CFG);
    c = ideal_cfg();
    c.edge_e_rad[1] = 0.1f; // a 5.7-degree sector
    EXPECT_EQ(mc_hall_f32_init(&st, &c), MC_HALL_ERR_CFG);
    c = ideal_cfg();
    c.hysteresis_e_rad = 0.6f; // above half the 60-degree sector (0.52)
    EXPECT_EQ(mc_hall_f32_init(&st, &c), MC_HALL_ERR_CFG);
    c = ideal_cfg();
    c.dt_s = 0.0f;
    EXPECT_EQ(mc_hall_f32_init(&st, &c), MC_HALL_ERR_CFG);
    c = ideal_cfg();
    c.omega_min_e_rad_s = NAN;
    EXPECT_EQ(mc_hall_f32_init(&st, &c), MC_HALL_ERR_CFG);
    c = ideal_cfg();
    c.edge_e_rad[4] = INFINITY;
    EXPECT_EQ(mc_hall_f32_init(&st, &c), MC_HALL_ERR_CFG);
    EXPECT_EQ(mc_hall_f32_init(nullptr, &c), MC_HALL_ERR_NULL);
    EXPECT_EQ(mc_hall_f32_init(&st, nullptr), MC_HALL_ERR_NULL);
    // The 60-degree placement's table (1, 3, 7, 6, 4, 0) is legal; its
    // illegal codes are 010 and 101.
    c = ideal_cfg();
    const uint8_t c60[6] = {1u, 3u, 7u, 6u, 4u, 0u};
    for (int k = 0; k < 6; ++k) {
        c.code_of_sector[k] = c60[k];
    }
    ASSERT_EQ(mc_hall_f32_init(&st, &c), MC_HALL_ERR_NONE);
    EXPECT_EQ(st.sector_of_code[2], MC_HALL_NO_SECTOR);
    EXPECT_EQ(st.sector_of_code[5], MC_HALL_NO_SECTOR);
    EXPECT_EQ(st.sector_of_code[7], 2u);
}

// Power-up at rest: the middle of the sector, speed 0 (the rotor is
// somewhere in it: at most 30 degrees off).
TEST(HallF32, PowerUpAtRestIsTheSectorMiddle)
{
    mc_hall_f32_t st{};
    const mc_hall_f32_cfg_t c = ideal_cfg();
    ASSERT_EQ(mc_hall_f32_init(&st, &c), MC_HALL_ERR_NONE);
    for (int k = 0; k < 6; ++k) {
        ASSERT_EQ(mc_hall_f32_reset(&st), MC_HALL_ERR_NONE);
        mc_hall_f32_out_t o{};
        ASSERT_EQ(mc_hall_f32_step(&st, kCodes[k], &o), MC_HALL_ERR_NONE);
        EXPECT_EQ(o.sector, static_cast<uint8_t>(k));
        // (k + 1/2) 60 degrees, float rounding of the sum (2 ulp of 2 pi)
        EXPECT_NEAR(o.theta_e_rad, (k + 0.5) * kPi / 3.0, 1e-6);
        EXPECT_EQ(o.omega_e_rad_s, 0.0f);
        EXPECT_FALSE(o.interpolating);
    }
}

// A constant speed, both directions: from the second edge on, the speed
// is the sector width over the samples between edges (the edge is seen up
// to one sample late at each end: relative error <= 1 / samples per
// sector), and the interpolated angle stays within the speed error times
// the time since the edge plus the half-sample of the edge's timing
// (bound below).
TEST(HallF32, ConstantSpeedSpeedAndAngleBothDirections)
{
    for (const double omega : {314.159, -314.159, 2513.27, -2513.27}) { // 50 and 400 Hz el.
        mc_hall_f32_t st{};
        const mc_hall_f32_cfg_t c = ideal_cfg();
        ASSERT_EQ(mc_hall_f32_init(&st, &c), MC_HALL_ERR_NONE);
        const double th0 = 0.3;
        const double per_sector = (kPi / 3.0) / (std::fabs(omega) * kDt); // samples
        int edges = 0;
        double err_max = 0.0;
        double werr_max = 0.0;
        for (int n = 0; n < 20000; ++n) {
            const double th = th0 + omega * n * kDt;
            mc_hall_f32_out_t o{};
            ASSERT_EQ(mc_hall_f32_step(&st, code_at(th), &o), MC_HALL_ERR_NONE);
            edges += o.edge ? 1 : 0;
            if (edges >= 2 && o.interpolating) {
                err_max = std::fmax(err_max, std::fabs(wrap_pi(o.theta_e_rad - th)));
                werr_max =
                    std::fmax(werr_max, std::fabs(o.omega_e_rad_s - omega) / std::fabs(omega));
            }
        }
        ASSERT_GT(edges, 10);
        // speed: one sample of timing error on an interval of per_sector samples
        EXPECT_LE(werr_max, 1.0 / (per_sector - 1.0)) << omega;
        // angle: the edge seen up to one sample late (|omega| dt), plus the
        // speed error over a sector (60 deg x werr), plus float rounding
        const double bound = std::fabs(omega) * kDt + (kPi / 3.0) * werr_max + 1e-5;
        EXPECT_LE(err_max, bound) << omega;
        EXPECT_GT(err_max, 0.0);
    }
}

// Hysteresis h: moving positive each edge is seen h/2 late, negative h/2
// early; with the band in the table the angle at the edge is exact.
TEST(HallF32, HysteresisShiftsTheEdgesByDirection)
{
    const double h = 0.1;
    for (const double omega : {200.0, -200.0}) {
        mc_hall_f32_cfg_t c = ideal_cfg();
        c.hysteresis_e_rad = static_cast<float>(h);
        mc_hall_f32_t st{};
        ASSERT_EQ(mc_hall_f32_init(&st, &c), MC_HALL_ERR_NONE);
        // sensors with the band: the code of the angle shifted against the motion
        const double shift = (omega > 0.0) ? -h / 2.0 : h / 2.0;
        double err_max = 0.0;
        int edges = 0;
        for (int n = 0; n < 4000; ++n) {
            const double th = 1.0 + omega * n * kDt;
            mc_hall_f32_out_t o{};
            ASSERT_EQ(mc_hall_f32_step(&st, code_at(th + shift), &o), MC_HALL_ERR_NONE);
            if (o.edge) {
                ++edges;
                if (edges > 1) {
                    err_max = std::fmax(err_max, std::fabs(wrap_pi(o.theta_e_rad - th)));
                }
            }
        }
        ASSERT_GT(edges, 3);
        // the edge is seen up to one sample (|omega| dt = 0.01 rad) after it
        // passed; without the band in the table the error would be h/2 = 0.05
        EXPECT_LE(err_max, std::fabs(omega) * kDt + 1e-5) << omega;
    }
}

// The speed bound between edges: a rotor that stops in a sector. The
// speed falls as width / time since the edge, the angle freezes before the
// next edge, never past it.
TEST(HallF32, StoppingRotorFreezesInsideTheSector)
{
    mc_hall_f32_t st{};
    const mc_hall_f32_cfg_t c = ideal_cfg();
    ASSERT_EQ(mc_hall_f32_init(&st, &c), MC_HALL_ERR_NONE);
    double th = 0.1;
    mc_hall_f32_out_t o{};
    for (int n = 0; n < 1000; ++n) { // 500 rad/s: several edges
        th += 500.0 * kDt;
        ASSERT_EQ(mc_hall_f32_step(&st, code_at(th), &o), MC_HALL_ERR_NONE);
    }
    const uint8_t sector = o.sector;
    const double start = sector * kPi / 3.0;
    // the angle relative to the sector's start (the wrap at 2 pi aside)
    auto rel = [&](double a) {
        double r = std::fmod(a - start + 4.0 * kPi, 2.0 * kPi);
        return (r > 1.9 * kPi) ? r - 2.0 * kPi : r;
    };
    double last = rel(o.theta_e_rad);
    for (int n = 0; n < 20000; ++n) { // the rotor stops here (1 s)
        ASSERT_EQ(mc_hall_f32_step(&st, code_at(th), &o), MC_HALL_ERR_NONE);
        EXPECT_EQ(o.sector, sector);
        const double r = rel(o.theta_e_rad);
        EXPECT_LE(r, kPi / 3.0 + 1e-6); // never past the next edge
        EXPECT_GE(r, last - 1e-6);      // never backwards
        last = r;
    }
    EXPECT_FALSE(o.interpolating);
    EXPECT_EQ(o.omega_e_rad_s, 0.0f);
}

// 000 and 111 (a supply lost, a connector off): MC_HALL_ERR_ILLEGAL, the
// angle held; sticky. A jump over a sector: MC_HALL_ERR_SEQUENCE.
TEST(HallF32, IllegalStatesAndImpossibleSequences)
{
    mc_hall_f32_t st{};
    const mc_hall_f32_cfg_t c = ideal_cfg();
    ASSERT_EQ(mc_hall_f32_init(&st, &c), MC_HALL_ERR_NONE);
    mc_hall_f32_out_t o{};
    ASSERT_EQ(mc_hall_f32_step(&st, 5u, &o), MC_HALL_ERR_NONE);
    const float held = o.theta_e_rad;
    EXPECT_EQ(mc_hall_f32_step(&st, 0u, &o), MC_HALL_ERR_ILLEGAL);
    EXPECT_EQ(o.theta_e_rad, held);
    EXPECT_EQ(mc_hall_f32_step(&st, 7u, &o), MC_HALL_ERR_ILLEGAL);
    EXPECT_EQ(mc_hall_f32_step(&st, 9u, &o), MC_HALL_ERR_ILLEGAL); // not a 3-bit code
    EXPECT_EQ(mc_hall_f32_step(&st, 5u, &o), MC_HALL_ERR_NONE);
    EXPECT_EQ(st.flags, MC_HALL_ERR_ILLEGAL);
    // 5 (sector 0) -> 3 (sector 2): skipped sector 1
    EXPECT_EQ(mc_hall_f32_step(&st, 3u, &o), MC_HALL_ERR_SEQUENCE);
    EXPECT_EQ(o.sector, 2u);
    EXPECT_FALSE(o.edge);
    // 3 (sector 2) -> 4 (sector 5): three sectors
    EXPECT_EQ(mc_hall_f32_step(&st, 4u, &o), MC_HALL_ERR_SEQUENCE);
    EXPECT_EQ(st.flags, MC_HALL_ERR_ILLEGAL | MC_HALL_ERR_SEQUENCE);
    // backwards by one is an edge (a reversal), not an error
    EXPECT_EQ(mc_hall_f32_step(&st, 6u, &o), MC_HALL_ERR_NONE);
    EXPECT_TRUE(o.edge);
    EXPECT_NEAR(o.theta_e_rad, 5.0 * kPi / 3.0, 1e-6); // negative edge into 4: edge[5]
    EXPECT_EQ(mc_hall_f32_reset(&st), MC_HALL_ERR_NONE);
    EXPECT_EQ(st.flags, 0u);
    EXPECT_EQ(mc_hall_f32_step(nullptr, 5u, &o), MC_HALL_ERR_NULL);
}

// A reversal forgets the speed: no interpolation until two edges in the
// new direction.
TEST(HallF32, ReversalForgetsTheSpeed)
{
    mc_hall_f32_t st{};
    const mc_hall_f32_cfg_t c = ideal_cfg();
    ASSERT_EQ(mc_hall_f32_init(&st, &c), MC_HALL_ERR_NONE);
    double th = 0.5;
    mc_hall_f32_out_t o{};
    for (int n = 0; n < 400; ++n) {
        th += 300.0 * kDt;
        (void)mc_hall_f32_step(&st, code_at(th), &o);
    }
    ASSERT_TRUE(o.interpolating);
    ASSERT_GT(o.omega_e_rad_s, 0.0f);
    int edges_back = 0;
    bool interp_after_one = false;
    for (int n = 0; n < 400 && edges_back < 2; ++n) {
        th -= 300.0 * kDt;
        (void)mc_hall_f32_step(&st, code_at(th), &o);
        if (o.edge) {
            ++edges_back;
        } else if (edges_back == 1 && o.interpolating) {
            interp_after_one = true;
        }
    }
    EXPECT_FALSE(interp_after_one);
    ASSERT_EQ(edges_back, 2);
    EXPECT_TRUE(o.interpolating);
    EXPECT_LT(o.omega_e_rad_s, 0.0f);
}
