// The wrappers' common contract (absent capability, NULL arguments) and the
// fake's own set-up validation.
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>

#include "hal_test_fixture.h"

namespace
{

TEST(HalContract, AbsentCapabilitiesReturnENODEV)
{
    // A board with nothing: every wrapper must say "not present", not crash.
    const mc_hal_t board{};
    mc_hal_adc_sample_t s{};
    mc_hal_adc_temp_t t{};
    mc_hal_pwm3_state_t p3{};
    mc_hal_pwm2_state_t p2{};
    mc_hal_encoder_sample_t e{};
    mc_hal_can_frame_t f{};
    mc_hal_can_status_t cs{};
    mc_hal_fault_status_t fs{};
    uint32_t u = 0;
    float period_s = 0.0f;

    EXPECT_EQ(-ENODEV, mc_hal_adc_read(board.adc, &s));
    EXPECT_EQ(-ENODEV, mc_hal_adc_read_temp(board.adc, &t));
    EXPECT_EQ(-ENODEV, mc_hal_pwm3_set_duty(board.pwm3, 0.5f, 0.5f, 0.5f));
    EXPECT_EQ(-ENODEV, mc_hal_pwm3_enable(board.pwm3));
    EXPECT_EQ(-ENODEV, mc_hal_pwm3_disable(board.pwm3));
    EXPECT_EQ(-ENODEV, mc_hal_pwm3_get_state(board.pwm3, &p3));
    EXPECT_EQ(-ENODEV, mc_hal_pwm3_get_period_s(board.pwm3, &period_s));
    EXPECT_EQ(-ENODEV, mc_hal_pwm2_set_duty(board.pwm2, 0.0f, 0.0f));
    EXPECT_EQ(-ENODEV, mc_hal_pwm2_enable(board.pwm2));
    EXPECT_EQ(-ENODEV, mc_hal_pwm2_disable(board.pwm2));
    EXPECT_EQ(-ENODEV, mc_hal_pwm2_get_state(board.pwm2, &p2));
    EXPECT_EQ(-ENODEV, mc_hal_encoder_read(board.encoder, &e));
    EXPECT_EQ(-ENODEV, mc_hal_can_send(board.can, &f));
    EXPECT_EQ(-ENODEV, mc_hal_can_receive(board.can, &f));
    EXPECT_EQ(-ENODEV, mc_hal_can_get_status(board.can, &cs));
    EXPECT_EQ(-ENODEV, mc_hal_tick_read(board.tick, &u));
    EXPECT_EQ(-ENODEV, mc_hal_tick_get_freq_hz(board.tick, &u));
    EXPECT_EQ(-ENODEV, mc_hal_fault_read(board.fault, &fs));
    EXPECT_EQ(-ENODEV, mc_hal_fault_gate_kill(board.fault));
    EXPECT_EQ(-ENODEV, mc_hal_fault_gate_release(board.fault));
}

TEST(HalContract, HandleWithoutOpsOrWithNullOpReturnsENODEV)
{
    int ctx = 0;
    const mc_hal_adc_t no_ops{nullptr, &ctx};
    const mc_hal_adc_ops_t read_only{nullptr, nullptr};
    const mc_hal_adc_t null_op{&read_only, &ctx};
    const mc_hal_fault_ops_t no_kill{nullptr, nullptr, nullptr};
    const mc_hal_fault_t fault{&no_kill, &ctx};
    mc_hal_adc_sample_t s{};

    EXPECT_EQ(-ENODEV, mc_hal_adc_read(&no_ops, &s));
    EXPECT_EQ(-ENODEV, mc_hal_adc_read(&null_op, &s));
    EXPECT_EQ(-ENODEV, mc_hal_fault_gate_kill(&fault));
}

TEST_F(HalFake, WrappersRejectNullOutputBeforeCallingTheOp)
{
    EXPECT_EQ(-EINVAL, mc_hal_adc_read(hal->adc, nullptr));
    EXPECT_EQ(-EINVAL, mc_hal_adc_read_temp(hal->adc, nullptr));
    EXPECT_EQ(-EINVAL, mc_hal_pwm3_get_state(hal->pwm3, nullptr));
    EXPECT_EQ(-EINVAL, mc_hal_pwm3_get_period_s(hal->pwm3, nullptr));
    EXPECT_EQ(-EINVAL, mc_hal_pwm2_get_state(hal->pwm2, nullptr));
    EXPECT_EQ(-EINVAL, mc_hal_encoder_read(hal->encoder, nullptr));
    EXPECT_EQ(-EINVAL, mc_hal_can_send(hal->can, nullptr));
    EXPECT_EQ(-EINVAL, mc_hal_can_receive(hal->can, nullptr));
    EXPECT_EQ(-EINVAL, mc_hal_can_get_status(hal->can, nullptr));
    EXPECT_EQ(-EINVAL, mc_hal_tick_read(hal->tick, nullptr));
    EXPECT_EQ(-EINVAL, mc_hal_tick_get_freq_hz(hal->tick, nullptr));
    EXPECT_EQ(-EINVAL, mc_hal_fault_read(hal->fault, nullptr));
    for (uint32_t n : fake.call_count) {
        EXPECT_EQ(0u, n); // the ops were never reached
    }
}

TEST_F(HalFake, OpsCalledDirectlyAlsoRejectNullArguments)
{
    // Drivers may be called without the wrapper (e.g. by the host binding).
    EXPECT_EQ(-EINVAL, fake.adc_dev.ops->read(fake.adc_dev.ctx, nullptr));
    EXPECT_EQ(-EINVAL, fake.adc_dev.ops->read(nullptr, nullptr));
    EXPECT_EQ(-EINVAL, fake.pwm3_dev.ops->set_duty(nullptr, 0.5f, 0.5f, 0.5f));
    EXPECT_EQ(-EINVAL, fake.can_dev.ops->send(fake.can_dev.ctx, nullptr));
    fake.fault_dev.ops->gate_kill(nullptr); // must not crash
}

TEST_F(HalFake, InitGivesEveryCapabilityAndPowerUpState)
{
    EXPECT_NE(nullptr, hal->adc);
    EXPECT_NE(nullptr, hal->pwm3);
    EXPECT_NE(nullptr, hal->pwm2);
    EXPECT_NE(nullptr, hal->encoder);
    EXPECT_NE(nullptr, hal->can);
    EXPECT_NE(nullptr, hal->tick);
    EXPECT_NE(nullptr, hal->fault);
    EXPECT_FALSE(fake.pwm3.enabled);
    EXPECT_FALSE(fake.pwm2.enabled);
    EXPECT_FALSE(fake.fault.gate_killed);
    EXPECT_EQ(0u, fake.can_tx.count);
    EXPECT_EQ(0u, fake.can_rx.count);
    EXPECT_EQ(0u, fake.tick_now);
}

TEST(HalFakeInit, RejectsBadConfigAndLeavesFakeUnchanged)
{
    mc_hal_fake_config_t good{};
    ASSERT_EQ(0, mc_hal_fake_config_default(&good));
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();

    struct Case {
        const char *what;
        mc_hal_fake_config_t cfg;
    };
    Case cases[] = {
        {"pwm3 period NaN", good},   {"pwm3 period 0", good},   {"pwm3 period < 0", good},
        {"pwm3 period > 1 s", good}, {"pwm3 period inf", good}, {"pwm2 period NaN", good},
        {"pwm2 period 0", good},     {"tick 0 Hz", good},       {"encoder 0 counts", good},
    };
    cases[0].cfg.pwm3_period_s = nan;
    cases[1].cfg.pwm3_period_s = 0.0f;
    cases[2].cfg.pwm3_period_s = -50e-6f;
    cases[3].cfg.pwm3_period_s = 1.5f;
    cases[4].cfg.pwm3_period_s = inf;
    cases[5].cfg.pwm2_period_s = nan;
    cases[6].cfg.pwm2_period_s = 0.0f;
    cases[7].cfg.tick_freq_hz = 0u;
    cases[8].cfg.encoder_counts_per_rev = 0u;

    for (const Case &c : cases) {
        SCOPED_TRACE(c.what);
        static mc_hal_fake_t fake;
        static mc_hal_fake_t before;
        std::memset(&fake, 0xA5, sizeof(fake));
        std::memcpy(&before, &fake, sizeof(fake));
        EXPECT_EQ(-EINVAL, mc_hal_fake_init(&fake, &c.cfg));
        EXPECT_EQ(0, std::memcmp(&before, &fake, sizeof(fake)));
    }
    static mc_hal_fake_t fake;
    EXPECT_EQ(-EINVAL, mc_hal_fake_init(&fake, nullptr));
    EXPECT_EQ(-EINVAL, mc_hal_fake_init(nullptr, &good));
    EXPECT_EQ(-EINVAL, mc_hal_fake_config_default(nullptr));
    // The boundary 1 s is accepted.
    good.pwm3_period_s = 1.0f;
    EXPECT_EQ(0, mc_hal_fake_init(&fake, &good));
}

TEST_F(HalFake, InjectErrorRejectsBadArguments)
{
    EXPECT_EQ(-EINVAL, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_CALL_COUNT, -EIO, 1u));
    EXPECT_EQ(-EINVAL, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_ADC_READ, 0, 1u));
    EXPECT_EQ(-EINVAL, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_ADC_READ, EIO, 1u));
    EXPECT_EQ(-EINVAL, mc_hal_fake_inject_error(nullptr, MC_HAL_FAKE_ADC_READ, -EIO, 1u));
}

TEST_F(HalFake, InjectedErrorFiresTheRequestedNumberOfTimesThenCanBeCancelled)
{
    uint32_t t = 0;
    ASSERT_EQ(0, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_TICK_READ, -EIO, 2u));
    EXPECT_EQ(-EIO, mc_hal_tick_read(hal->tick, &t));
    EXPECT_EQ(-EIO, mc_hal_tick_read(hal->tick, &t));
    EXPECT_EQ(0, mc_hal_tick_read(hal->tick, &t));
    ASSERT_EQ(0, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_TICK_READ, -EIO, 5u));
    ASSERT_EQ(0, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_TICK_READ, -EIO, 0u));
    EXPECT_EQ(0, mc_hal_tick_read(hal->tick, &t));
    EXPECT_EQ(4u, fake.call_count[MC_HAL_FAKE_TICK_READ]); // failed ones count
}

} // namespace
