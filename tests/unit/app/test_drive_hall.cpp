// The Hall sensors as the drive's position source (firmware/app/drive/
// mc_drive_hall.h): the adapter between the Hall inputs (a test's own
// hal/hall.h device) and the encoder capability the drive reads, and the
// parameters that select it (encoder_type 1, the hall_* table). The
// kernel's own decoding is tested in tests/unit/hall; here what the adapter
// adds: the count and its electrical turns, the middle of the sector below
// the interpolation's speed, the samples it marks not valid and why.
#include <gtest/gtest.h>

#include <cerrno>
#include <cmath>
#include <vector>

extern "C" {
#include "config/mc_params.h"
#include "mc_drive.h"
#include "mc_drive_hall.h"
}

namespace
{

constexpr double kPi = 3.14159265358979323846;
constexpr uint32_t kK = MC_DRIVE_HALL_COUNTS_E;
// The usual 120-degree placement from sector 0 (the parameters' default).
constexpr uint8_t kCodes[6] = {5u, 1u, 3u, 2u, 6u, 4u};

struct FakeHall {
    uint32_t code = 5u;
    int rc = 0;
    mc_hal_hall_ops_t ops{};
    mc_hal_hall_t dev{};
    FakeHall()
    {
        ops.read = [](void *ctx, uint32_t *p) {
            auto *f = static_cast<FakeHall *>(ctx);
            *p = f->code;
            return f->rc;
        };
        dev.ops = &ops;
        dev.ctx = this;
    }
};

mc_drive_hall_cfg_t ideal(uint32_t pole_pairs, float dt_s = 1.0f / 20000.0f)
{
    mc_drive_hall_cfg_t c{};
    for (int k = 0; k < 6; ++k) {
        c.table.code_of_sector[k] = kCodes[k];
        c.table.edge_e_rad[k] = static_cast<float>(k * kPi / 3.0);
    }
    c.table.hysteresis_e_rad = 0.0f;
    c.table.dt_s = dt_s;
    c.table.omega_min_e_rad_s = 50.0f;
    c.pole_pairs = pole_pairs;
    return c;
}

// The adapter on a fake's inputs with the ideal table.
struct Rig {
    FakeHall f;
    mc_drive_hall_t h{};
    explicit Rig(uint32_t pole_pairs, float dt_s = 1.0f / 20000.0f)
    {
        const mc_drive_hall_cfg_t c = ideal(pole_pairs, dt_s);
        EXPECT_EQ(mc_drive_hall_init(&h, &c, &f.dev, nullptr), MC_DRIVE_HALL_ERR_NONE);
    }
    Rig(const Rig &) = delete;
    Rig &operator=(const Rig &) = delete;
};

mc_hal_encoder_sample_t read(mc_drive_hall_t *h, int *p_rc = nullptr)
{
    mc_hal_encoder_sample_t s{};
    const int rc = mc_hal_encoder_read(mc_drive_hall_encoder(h), &s);
    if (p_rc != nullptr) {
        *p_rc = rc;
    }
    return s;
}

// The sector of an ideal set at electrical angle th (the table above).
uint32_t code_at(double th_e)
{
    const double w = std::fmod(std::fmod(th_e, 2 * kPi) + 2 * kPi, 2 * kPi);
    return kCodes[static_cast<int>(w / (kPi / 3.0)) % 6];
}

TEST(DriveHall, InitRefusesAndLeavesTheStateAlone)
{
    FakeHall f;
    mc_drive_hall_t h{};
    h.pole_pairs = 77u; // a marker: a refused init writes nothing
    mc_drive_hall_cfg_t c = ideal(7u);
    EXPECT_EQ(mc_drive_hall_init(nullptr, &c, &f.dev, nullptr), MC_DRIVE_HALL_ERR_NULL);
    EXPECT_EQ(mc_drive_hall_init(&h, nullptr, &f.dev, nullptr), MC_DRIVE_HALL_ERR_NULL);
    EXPECT_EQ(mc_drive_hall_init(&h, &c, nullptr, nullptr), MC_DRIVE_HALL_ERR_NULL);
    c.pole_pairs = 0u;
    EXPECT_EQ(mc_drive_hall_init(&h, &c, &f.dev, nullptr), MC_DRIVE_HALL_ERR_POLES);
    c = ideal(7u);
    c.table.code_of_sector[1] = 5u; // a code twice
    EXPECT_EQ(mc_drive_hall_init(&h, &c, &f.dev, nullptr), MC_DRIVE_HALL_ERR_CFG);
    c = ideal(7u);
    c.table.edge_e_rad[2] = c.table.edge_e_rad[1]; // a sector of width 0
    EXPECT_EQ(mc_drive_hall_init(&h, &c, &f.dev, nullptr), MC_DRIVE_HALL_ERR_CFG);
    EXPECT_EQ(h.pole_pairs, 77u);
}

// Power-up: the first sample gives the middle of the sector read (a
// rotor at rest, below omega_min), referenced at once: VALID and INDEX,
// counts_per_rev = pole pairs x 4096, the count in the first electrical
// turn (the mechanical angle is relative to the power-up's turn).
TEST(DriveHall, PowerUpIsTheMiddleOfTheSectorRead)
{
    for (uint32_t k = 0u; k < 6u; ++k) {
        FakeHall f;
        f.code = kCodes[k];
        mc_drive_hall_t h{};
        mc_drive_hall_cfg_t c = ideal(15u);
        ASSERT_EQ(mc_drive_hall_init(&h, &c, &f.dev, nullptr), MC_DRIVE_HALL_ERR_NONE);
        int rc = -1;
        const mc_hal_encoder_sample_t s = read(&h, &rc);
        EXPECT_EQ(rc, 0);
        EXPECT_EQ(s.flags, MC_HAL_ENCODER_FLAG_ALL);
        EXPECT_EQ(s.counts_per_rev, 15u * kK);
        // (k + 1/2) x 60 degrees in 4096ths of a turn, within one count
        // (the float angle truncated to a count)
        const double want = (k + 0.5) * kK / 6.0;
        EXPECT_NEAR(static_cast<double>(s.count), want, 1.0) << k;
    }
}

// Turning slowly (below omega_min: the middle of each sector) forward two
// electrical turns and back: the count moves by a sixth of 4096 a sector,
// a whole electrical turn adds 4096 (mod pole pairs x 4096), and back to
// the start gives the start's count; never not valid.
TEST(DriveHall, CountsElectricalTurnsBothWays)
{
    Rig r(3u);
    r.f.code = kCodes[4];
    const uint32_t c0 = read(&r.h).count;
    const uint32_t cpr = 3u * kK;
    std::vector<int> steps; // two turns forward, a sector at a time, and back
    for (int k = 1; k <= 12; ++k) {
        steps.push_back(k);
    }
    for (int k = 11; k >= 0; --k) {
        steps.push_back(k);
    }
    for (const int step : steps) {
        r.f.code = kCodes[(4 + step) % 6];
        for (int n = 0; n < 2000; ++n) { // 0.1 s a sector: 10.5 rad/s el., below 50
            const mc_hal_encoder_sample_t s = read(&r.h);
            ASSERT_EQ(s.flags, MC_HAL_ENCODER_FLAG_ALL);
        }
        const uint32_t want = (c0 + static_cast<uint32_t>(step) * kK / 6u) % cpr;
        EXPECT_NEAR(static_cast<double>(read(&r.h).count), static_cast<double>(want), 1.0) << step;
    }
}

// At a constant speed above omega_min the count is the kernel's
// interpolated angle: within the kernel's bound of the true angle, one
// sample's motion (mc_hall.h: the sampling error of the speed) plus a count
// and the half sample of edge timing, after the first two edges.
TEST(DriveHall, InterpolatesAtSpeed)
{
    const float dt = 1.0f / 20000.0f;
    Rig r(7u, dt);
    FakeHall &f = r.f;
    mc_drive_hall_t &h = r.h;
    const double w = 600.0; // rad/s el.: 35 samples a sector
    double worst = 0.0;
    for (int n = 0; n < 4000; ++n) {
        const double th = 0.3 + w * n * dt;
        f.code = code_at(th);
        const mc_hal_encoder_sample_t s = read(&h);
        ASSERT_EQ(s.flags, MC_HAL_ENCODER_FLAG_ALL);
        if (n < 200) {
            continue; // the first edges: no speed yet
        }
        const double th_count = 2 * kPi * static_cast<double>(s.count % kK) / kK;
        const double err = std::remainder(th_count - th, 2 * kPi);
        worst = std::fmax(worst, std::fabs(err));
    }
    const double bound = 1.5 * w * dt + 2 * kPi / kK;
    EXPECT_LT(worst, bound);
}

// 000 and 111 (a supply lost, a connector off) and a jump by two sectors:
// that sample is not valid (the drive's ENCODER fault), error names it
// (sticky), the count holds; a legal code afterwards is valid again (the
// drive's fault is its own to clear). A read the inputs refuse is -EIO.
TEST(DriveHall, IllegalCodesAndJumpsAreNotValidWithTheirReason)
{
    Rig r(7u);
    FakeHall &f = r.f;
    mc_drive_hall_t &h = r.h;
    f.code = kCodes[2];
    const uint32_t c0 = read(&h).count;
    for (uint32_t bad : {0u, 7u}) {
        f.code = bad;
        const mc_hal_encoder_sample_t s = read(&h);
        EXPECT_EQ(s.flags & MC_HAL_ENCODER_FLAG_VALID, 0u) << bad;
        EXPECT_EQ(s.count, c0) << bad;
        EXPECT_EQ(h.error, MC_HALL_ERR_ILLEGAL) << bad;
    }
    f.code = kCodes[2];
    EXPECT_EQ(read(&h).flags, MC_HAL_ENCODER_FLAG_ALL);
    f.code = kCodes[4]; // two sectors in one sample
    EXPECT_EQ(read(&h).flags & MC_HAL_ENCODER_FLAG_VALID, 0u);
    EXPECT_EQ(h.error, MC_HALL_ERR_ILLEGAL | MC_HALL_ERR_SEQUENCE);
    f.rc = -EIO;
    int rc = 0;
    (void)read(&h, &rc);
    EXPECT_EQ(rc, -EIO);
}

// The parameters: encoder_type 1 needs encoder_cpr = 6 pole pairs (the
// Hall's edges per mechanical turn), angle_ref 0 (referenced at power-up)
// and a table the kernel takes; the default table is the 120-degree
// placement; the drive then skips its jump check (enc_steps_checked),
// other encoder types keep it.
TEST(DriveHall, ParametersSelectAndCheckTheHall)
{
    mc_params_t p = mc_params_default;
    mc_drive_cfg_t dc;
    ASSERT_EQ(mc_params_to_drive_cfg(&p, &dc), MC_PARAMS_OK);
    EXPECT_FALSE(dc.enc_steps_checked);
    mc_hall_f32_cfg_t t;
    ASSERT_EQ(mc_params_hall_table(&p, &t), MC_PARAMS_OK);
    for (int k = 0; k < 6; ++k) {
        EXPECT_EQ(t.code_of_sector[k], kCodes[k]) << k;
        EXPECT_NEAR(t.edge_e_rad[k], k * kPi / 3.0, 1e-6) << k;
    }
    EXPECT_FLOAT_EQ(t.dt_s, 1.0f / static_cast<float>(p.pwm_hz));
    p.encoder_type = MC_PARAMS_ENCODER_HALL;
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_ERR_ENCODER); // 8192 counts
    p.encoder_cpr = 6u * p.pole_pairs;
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_OK);
    ASSERT_EQ(mc_params_to_drive_cfg(&p, &dc), MC_PARAMS_OK);
    EXPECT_TRUE(dc.enc_steps_checked);
    mc_params_t q = p;
    q.angle_ref = MC_DRIVE_ANGLE_REF_ALIGN;
    EXPECT_EQ(mc_params_validate(&q) & MC_PARAMS_ERR_ENCODER, MC_PARAMS_ERR_ENCODER);
    q = p;
    q.hall_codes = 5u | (5u << 3) | (3u << 6) | (2u << 9) | (6u << 12) | (4u << 15);
    EXPECT_EQ(mc_params_validate(&q), MC_PARAMS_ERR_ENCODER);
    q = p;
    q.hall_edge3_e_rad = q.hall_edge1_e_rad; // out of order
    EXPECT_EQ(mc_params_validate(&q), MC_PARAMS_ERR_ENCODER);
    q = p;
    q.hall_edge1_e_rad = 0.2f;       // sector 0 0.2 rad wide (above the 10 degrees)
    q.hall_hysteresis_e_rad = 0.15f; // not below half of it
    EXPECT_EQ(mc_params_validate(&q), MC_PARAMS_ERR_ENCODER);
    q.hall_hysteresis_e_rad = 0.09f;
    EXPECT_EQ(mc_params_validate(&q), MC_PARAMS_OK);
}

} // namespace
