// The open-phase check (MC_DRIVE_FAULT_OPEN_PHASE) on the fake board: its
// configuration rules, the per-phase count (up without conduction, down with
// it, nothing below the reference threshold or at the voltage limit), and
// its reset on entering CURRENT and clearing the faults.
#include <cmath>

#include <gtest/gtest.h>

#include "app_test_fixture.h"

namespace apptest
{
namespace
{

constexpr uint32_t kTripSteps = 10u;

class AppOpenPhase : public AppDrive
{
  protected:
    void SetUp() override
    {
        AppDrive::SetUp();
        cfg.open_phase_i_min_a = 1.0f;
        cfg.open_phase_time_s = static_cast<float>(kTripSteps) * kDt;
    }

    // Phase references for (id, iq) at the drive's angle: encoder at count 0,
    // theta_e = kOffset (amplitude-invariant inverse Park + Clarke).
    static void PhaseRefs(float id, float iq, float r[3])
    {
        const double c = std::cos(static_cast<double>(kOffset));
        const double s = std::sin(static_cast<double>(kOffset));
        const double a = id * c - iq * s;
        const double b = id * s + iq * c;
        r[0] = static_cast<float>(a);
        r[1] = static_cast<float>(-0.5 * a + 0.5 * std::sqrt(3.0) * b);
        r[2] = static_cast<float>(-0.5 * a - 0.5 * std::sqrt(3.0) * b);
    }

    // Run CURRENT at (id, iq) and feed phase currents i (ic derived).
    void Start(float id, float iq)
    {
        InitDrive();
        ASSERT_EQ(0, mc_drive_set_current_ref(&d, id, iq));
        ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
    }
    void StepWith(float ia, float ib)
    {
        ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, ia, ib, 0.0f, kVbus, kMask3));
        (void)mc_drive_fast_step(&d);
    }
};

TEST_F(AppOpenPhase, ConfigRulesEachRejected)
{
    auto ExpectRejected = [&](const mc_drive_cfg_t &c, const char *why) {
        mc_drive_t probe{};
        probe.fast_count = 77u;
        EXPECT_EQ(MC_DRIVE_CFG_ERR_OPEN_PHASE, mc_drive_init(&probe, &c, hal)) << why;
        EXPECT_EQ(77u, probe.fast_count) << "drive written on error: " << why;
    };
    for (float v : {-1.0f, kNaN, kInf}) {
        mc_drive_cfg_t c = cfg;
        c.open_phase_i_min_a = v;
        ExpectRejected(c, "i_min negative or not finite");
        c = cfg;
        c.open_phase_time_s = v;
        ExpectRejected(c, "time negative or not finite");
    }
    mc_drive_cfg_t c = cfg;
    c.open_phase_time_s = 0.0f;
    ExpectRejected(c, "i_min set, time 0");
    c = cfg;
    c.open_phase_i_min_a = 0.0f;
    ExpectRejected(c, "time set, i_min 0");
    c = cfg;
    c.open_phase_i_min_a = std::nextafter(kIMax, 1e9f);
    ExpectRejected(c, "i_min above i_max");
    c = cfg;
    c.open_phase_time_s = 0.9f * kDt;
    ExpectRejected(c, "shorter than one period");
    c = cfg;
    c.open_phase_time_s = 16777217.0f * 2.0f * kDt;
    ExpectRejected(c, "longer than 2^24 periods");

    // Accepted: both 0 (off), and the edges i_min = i_max, time = one period.
    c = cfg;
    c.open_phase_i_min_a = 0.0f;
    c.open_phase_time_s = 0.0f;
    ASSERT_EQ(MC_DRIVE_CFG_OK, mc_drive_init(&d, &c, hal));
    EXPECT_EQ(0u, d.open_phase_trip);
    c = cfg;
    c.open_phase_i_min_a = kIMax;
    c.open_phase_time_s = kDt;
    ASSERT_EQ(MC_DRIVE_CFG_OK, mc_drive_init(&d, &c, hal));
    EXPECT_EQ(1u, d.open_phase_trip);
    ASSERT_EQ(MC_DRIVE_CFG_OK, mc_drive_init(&d, &cfg, hal));
    EXPECT_EQ(kTripSteps, d.open_phase_trip);
}

TEST_F(AppOpenPhase, BrokenPhaseTripsAfterItsCount)
{
    // 4 A on d at theta_e = 0.3 rad: references (3.82, -0.89, -2.94) A.
    // Phase a reads 0 (broken), b and c carry their references: a counts
    // up each step and trips at the 10th; b is below the 1 A threshold (no
    // evidence) and c conducts.
    float r[3];
    PhaseRefs(4.0f, 0.0f, r);
    ASSERT_GT(std::abs(r[0]), 1.0f);
    ASSERT_LT(std::abs(r[1]), 1.0f);
    Start(4.0f, 0.0f);
    for (uint32_t k = 1u; k < kTripSteps; ++k) {
        StepWith(0.0f, r[1]);
        ASSERT_EQ(MC_DRIVE_FAULT_NONE, d.faults) << "step " << k;
        EXPECT_EQ(k, d.open_phase_count[0]);
    }
    EXPECT_EQ(0u, d.open_phase_count[1]);
    EXPECT_EQ(0u, d.open_phase_count[2]);
    StepWith(0.0f, r[1]);
    EXPECT_EQ(MC_DRIVE_FAULT_OPEN_PHASE, d.faults);
    EXPECT_EQ(1u, d.open_phase_mask);
    EXPECT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
    EXPECT_FALSE(fake.pwm3.enabled);

    // Clearing forgets the phase; entering CURRENT again restarts the counts.
    ASSERT_EQ(0, mc_drive_clear_faults(&d));
    EXPECT_EQ(0u, d.open_phase_mask);
    ASSERT_EQ(0, mc_drive_set_current_ref(&d, 4.0f, 0.0f));
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
    EXPECT_EQ(0u, d.open_phase_count[0]);
}

TEST_F(AppOpenPhase, ConductionCountsDownAndAQuarterIsConduction)
{
    // Phase c broken for 6 steps, then conducting a bit more than a quarter
    // of its reference for 6 steps: the count goes 6 -> 0. Alternating
    // single steps never accumulate. Exactly a quarter counts as
    // conduction; just below it does not.
    float r[3];
    PhaseRefs(4.0f, 0.0f, r);
    const float quarter = MC_DRIVE_OPEN_PHASE_CONDUCTION_RATIO * std::abs(r[2]);
    Start(4.0f, 0.0f);
    // ic = -(ia + ib): choose ib so that ic is the wanted value.
    auto StepIc = [&](float ic) { StepWith(r[0], -r[0] - ic); };
    for (int k = 0; k < 6; ++k)
        StepIc(0.0f);
    EXPECT_EQ(6u, d.open_phase_count[2]);
    for (int k = 0; k < 6; ++k)
        StepIc(-1.01f * quarter);
    EXPECT_EQ(0u, d.open_phase_count[2]);
    for (int k = 0; k < 100; ++k)
        StepIc((k % 2 == 0) ? 0.0f : r[2]);
    EXPECT_LE(d.open_phase_count[2], 1u);
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
    // The 0.99 / 1.01 margins keep the float sums of the derived ic on the
    // intended side of the threshold.
    Start(4.0f, 0.0f);
    StepIc(-0.99f * quarter);
    EXPECT_EQ(1u, d.open_phase_count[2]) << "below a quarter is no conduction";
    EXPECT_EQ(0u, d.open_phase_count[0]) << "phase a conducts its reference";
}

TEST_F(AppOpenPhase, NoCountAtTheVoltageLimit)
{
    // All phases read 0 with 4 A commanded on d: the d PI winds up (0.4 V +
    // 400 V/s on the 4 A error) until the voltage reaches the limit
    // (24 / sqrt(3) = 13.9 V) after about 33 ms = 670 steps. With a trip
    // count far above that, the counts must stop growing there.
    cfg.open_phase_time_s = 4000.0f * kDt;
    Start(4.0f, 0.0f);
    for (int k = 0; k < 1000; ++k)
        StepWith(0.0f, 0.0f);
    const uint32_t at_1000 = d.open_phase_count[0];
    const float v = std::hypot(d.tm.foc.vd_v, d.tm.foc.vq_v);
    EXPECT_GE(v, MC_DRIVE_OPEN_PHASE_VSAT_FRAC * kVbus / std::sqrt(3.0f)) << "at the limit";
    // Counted up to the limit and no further: 0.99 of it is reached after
    // (13.72 V - 0.4 V) / (400 V/s) = 33.3 ms = 666 steps; +-5 steps for the
    // discrete integrator (its update order and the one-step kp term).
    EXPECT_NEAR(static_cast<double>(at_1000), 666.0, 5.0);
    for (int k = 0; k < 1000; ++k)
        StepWith(0.0f, 0.0f);
    EXPECT_EQ(at_1000, d.open_phase_count[0]);
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
}

TEST_F(AppOpenPhase, OffWhenNotConfiguredAndOutsideCurrentMode)
{
    // Check off: 100 steps with nothing flowing raise nothing.
    cfg.open_phase_i_min_a = 0.0f;
    cfg.open_phase_time_s = 0.0f;
    Start(4.0f, 0.0f);
    for (int k = 0; k < 100; ++k)
        StepWith(0.0f, 0.0f);
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
    // Check on but IDLE (references kept from IDLE): nothing counts.
    cfg = GoodCfg();
    cfg.open_phase_i_min_a = 1.0f;
    cfg.open_phase_time_s = static_cast<float>(kTripSteps) * kDt;
    InitDrive();
    ASSERT_EQ(0, mc_drive_set_current_ref(&d, 4.0f, 0.0f));
    for (int k = 0; k < 100; ++k)
        StepWith(0.0f, 0.0f);
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
    EXPECT_EQ(0u, d.open_phase_count[0]);
}

} // namespace
} // namespace apptest
