// Fault inputs and the gate kill: the kill disables every bridge, latches,
// and works even when every other call fails.
#include <cerrno>

#include "hal_test_fixture.h"

namespace
{

class HalFakeRunning : public HalFake
{
  protected:
    void SetUp() override
    {
        HalFake::SetUp();
        ASSERT_EQ(0, mc_hal_pwm3_set_duty(hal->pwm3, 0.3f, 0.5f, 0.7f));
        ASSERT_EQ(0, mc_hal_pwm3_enable(hal->pwm3));
        ASSERT_EQ(0, mc_hal_pwm2_enable(hal->pwm2));
        ASSERT_TRUE(fake.pwm3.enabled);
        ASSERT_TRUE(fake.pwm2.enabled);
    }
};

TEST_F(HalFakeRunning, GateKillDisablesAllPwmAndLatches)
{
    ASSERT_EQ(0, mc_hal_fault_gate_kill(hal->fault));
    EXPECT_FALSE(fake.pwm3.enabled);
    EXPECT_FALSE(fake.pwm2.enabled);

    mc_hal_fault_status_t st{};
    ASSERT_EQ(0, mc_hal_fault_read(hal->fault, &st));
    EXPECT_TRUE(st.gate_killed);
    EXPECT_EQ(0u, st.active_mask); // software kill: no input asserted

    // Latched: enables are refused and outputs stay off.
    EXPECT_EQ(-EBUSY, mc_hal_pwm3_enable(hal->pwm3));
    EXPECT_EQ(-EBUSY, mc_hal_pwm2_enable(hal->pwm2));
    EXPECT_FALSE(fake.pwm3.enabled);
    EXPECT_FALSE(fake.pwm2.enabled);
    // Duties may still be prepared.
    EXPECT_EQ(0, mc_hal_pwm3_set_duty(hal->pwm3, 0.5f, 0.5f, 0.5f));
    EXPECT_FALSE(fake.pwm3.enabled);

    // Idempotent.
    ASSERT_EQ(0, mc_hal_fault_gate_kill(hal->fault));
    EXPECT_EQ(2u, fake.gate_kill_count);
    EXPECT_TRUE(fake.fault.gate_killed);
}

TEST_F(HalFakeRunning, GateKillWorksWhenEveryOtherCallFails)
{
    for (int c = 0; c < MC_HAL_FAKE_CALL_COUNT; ++c) {
        ASSERT_EQ(0,
                  mc_hal_fake_inject_error(&fake, static_cast<mc_hal_fake_call_t>(c), -EIO, 100u));
    }
    EXPECT_EQ(-EIO, mc_hal_pwm3_disable(hal->pwm3));
    EXPECT_EQ(-EIO, mc_hal_pwm2_disable(hal->pwm2));
    EXPECT_TRUE(fake.pwm3.enabled); // the normal stop failed...

    ASSERT_EQ(0, mc_hal_fault_gate_kill(hal->fault));
    EXPECT_FALSE(fake.pwm3.enabled); // ...the kill did not
    EXPECT_FALSE(fake.pwm2.enabled);
    EXPECT_TRUE(fake.fault.gate_killed);
}

TEST_F(HalFakeRunning, ReleaseClearsTheLatchButDoesNotReEnable)
{
    ASSERT_EQ(0, mc_hal_fault_gate_kill(hal->fault));
    ASSERT_EQ(0, mc_hal_fault_gate_release(hal->fault));
    EXPECT_FALSE(fake.fault.gate_killed);
    EXPECT_FALSE(fake.pwm3.enabled);
    EXPECT_FALSE(fake.pwm2.enabled);
    EXPECT_EQ(0, mc_hal_pwm3_enable(hal->pwm3));
    EXPECT_TRUE(fake.pwm3.enabled);
}

TEST_F(HalFakeRunning, FaultInputTripsTheKillAndBlocksReleaseWhileAsserted)
{
    ASSERT_EQ(0, mc_hal_fake_fault_set_inputs(&fake, MC_HAL_FAULT_OVERCURRENT));
    EXPECT_FALSE(fake.pwm3.enabled);
    EXPECT_FALSE(fake.pwm2.enabled);

    mc_hal_fault_status_t st{};
    ASSERT_EQ(0, mc_hal_fault_read(hal->fault, &st));
    EXPECT_EQ(MC_HAL_FAULT_OVERCURRENT, st.active_mask);
    EXPECT_EQ(MC_HAL_FAULT_OVERCURRENT, st.latched_mask);
    EXPECT_TRUE(st.gate_killed);

    EXPECT_EQ(-EBUSY, mc_hal_fault_gate_release(hal->fault));
    EXPECT_TRUE(fake.fault.gate_killed); // nothing changed
    EXPECT_EQ(MC_HAL_FAULT_OVERCURRENT, fake.fault.latched_mask);

    // Input goes away: still latched until released.
    ASSERT_EQ(0, mc_hal_fake_fault_set_inputs(&fake, 0u));
    ASSERT_EQ(0, mc_hal_fault_read(hal->fault, &st));
    EXPECT_EQ(0u, st.active_mask);
    EXPECT_EQ(MC_HAL_FAULT_OVERCURRENT, st.latched_mask);
    EXPECT_TRUE(st.gate_killed);

    ASSERT_EQ(0, mc_hal_fault_gate_release(hal->fault));
    ASSERT_EQ(0, mc_hal_fault_read(hal->fault, &st));
    EXPECT_EQ(0u, st.latched_mask);
    EXPECT_FALSE(st.gate_killed);
}

TEST_F(HalFake, FaultInputNotWiredToBreakOnlyReports)
{
    cfg.fault_input_kills = false;
    ASSERT_EQ(0, mc_hal_fake_init(&fake, &cfg));
    ASSERT_EQ(0, mc_hal_pwm3_enable(hal->pwm3));
    ASSERT_EQ(0, mc_hal_fake_fault_set_inputs(&fake, MC_HAL_FAULT_GATE_DRIVER));
    EXPECT_TRUE(fake.pwm3.enabled); // the drive must react itself
    mc_hal_fault_status_t st{};
    ASSERT_EQ(0, mc_hal_fault_read(hal->fault, &st));
    EXPECT_EQ(MC_HAL_FAULT_GATE_DRIVER, st.active_mask);
    EXPECT_FALSE(st.gate_killed);
}

TEST_F(HalFake, FaultSetInputsRejectsUnknownBits)
{
    EXPECT_EQ(-EINVAL, mc_hal_fake_fault_set_inputs(&fake, 1u << 5));
    EXPECT_EQ(0u, fake.fault.active_mask);
    EXPECT_EQ(0u, fake.fault.latched_mask);
    EXPECT_FALSE(fake.fault.gate_killed);
}

TEST_F(HalFake, FaultReadInjectedEIOLeavesOutput)
{
    ASSERT_EQ(0, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_FAULT_READ, -EIO, 1u));
    mc_hal_fault_status_t st{};
    st.active_mask = 0xABCu;
    EXPECT_EQ(-EIO, mc_hal_fault_read(hal->fault, &st));
    EXPECT_EQ(0xABCu, st.active_mask);
}

} // namespace
