// 3-phase and 2-phase PWM through the fake: duties, enable/disable, and the
// rule that a rejected call changes nothing.
#include <cerrno>
#include <limits>

#include "hal_test_fixture.h"

namespace
{

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

void ExpectPwm3(const mc_hal_fake_t &f, float a, float b, float c, bool en)
{
    EXPECT_NEAR(a, f.pwm3.duty_a, kExact);
    EXPECT_NEAR(b, f.pwm3.duty_b, kExact);
    EXPECT_NEAR(c, f.pwm3.duty_c, kExact);
    EXPECT_EQ(en, f.pwm3.enabled);
}

TEST_F(HalFake, Pwm3PowerUpStateIsDisabledAtZeroVector)
{
    mc_hal_pwm3_state_t st{};
    ASSERT_EQ(0, mc_hal_pwm3_get_state(hal->pwm3, &st));
    EXPECT_NEAR(MC_HAL_PWM3_DUTY_INIT, st.duty_a, kExact);
    EXPECT_NEAR(MC_HAL_PWM3_DUTY_INIT, st.duty_b, kExact);
    EXPECT_NEAR(MC_HAL_PWM3_DUTY_INIT, st.duty_c, kExact);
    EXPECT_NEAR(50e-6f, st.period_s, kExact);
    EXPECT_FALSE(st.enabled);
}

TEST_F(HalFake, Pwm3SetEnableReadBack)
{
    ASSERT_EQ(0, mc_hal_pwm3_set_duty(hal->pwm3, 0.25f, 0.5f, 0.75f));
    ASSERT_EQ(0, mc_hal_pwm3_enable(hal->pwm3));
    mc_hal_pwm3_state_t st{};
    ASSERT_EQ(0, mc_hal_pwm3_get_state(hal->pwm3, &st));
    EXPECT_NEAR(0.25f, st.duty_a, kExact);
    EXPECT_NEAR(0.5f, st.duty_b, kExact);
    EXPECT_NEAR(0.75f, st.duty_c, kExact);
    EXPECT_TRUE(st.enabled);

    float period_s = 0.0f;
    ASSERT_EQ(0, mc_hal_pwm3_get_period_s(hal->pwm3, &period_s));
    EXPECT_NEAR(50e-6f, period_s, kExact);

    // Enable is idempotent; disable keeps the duties.
    EXPECT_EQ(0, mc_hal_pwm3_enable(hal->pwm3));
    ASSERT_EQ(0, mc_hal_pwm3_disable(hal->pwm3));
    ExpectPwm3(fake, 0.25f, 0.5f, 0.75f, false);
    EXPECT_EQ(0, mc_hal_pwm3_disable(hal->pwm3));
    ExpectPwm3(fake, 0.25f, 0.5f, 0.75f, false);
}

TEST_F(HalFake, Pwm3AcceptsTheClosedIntervalEnds)
{
    EXPECT_EQ(0, mc_hal_pwm3_set_duty(hal->pwm3, 0.0f, 1.0f, -0.0f));
    ExpectPwm3(fake, 0.0f, 1.0f, 0.0f, false);
}

TEST_F(HalFake, Pwm3DutiesSetWhileDisabledAreUsedOnEnable)
{
    ASSERT_EQ(0, mc_hal_pwm3_set_duty(hal->pwm3, 0.1f, 0.2f, 0.3f));
    EXPECT_FALSE(fake.pwm3.enabled);
    ASSERT_EQ(0, mc_hal_pwm3_enable(hal->pwm3));
    ExpectPwm3(fake, 0.1f, 0.2f, 0.3f, true);
}

TEST_F(HalFake, Pwm3RejectsBadDutiesAndChangesNothing)
{
    ASSERT_EQ(0, mc_hal_pwm3_set_duty(hal->pwm3, 0.25f, 0.5f, 0.75f));
    ASSERT_EQ(0, mc_hal_pwm3_enable(hal->pwm3));

    struct Case {
        float a, b, c;
    };
    // Each bad value in each position, with valid values in the others so
    // that a driver writing duties one by one would be caught.
    const Case bad[] = {
        {kNan, 0.5f, 0.5f},       {0.5f, kNan, 0.5f},   {0.5f, 0.5f, kNan},  {-0.01f, 0.5f, 0.5f},
        {0.5f, -0.01f, 0.5f},     {0.5f, 0.5f, -0.01f}, {1.01f, 0.5f, 0.5f}, {0.5f, 1.01f, 0.5f},
        {0.5f, 0.5f, 1.01f},      {kInf, 0.5f, 0.5f},   {0.5f, -kInf, 0.5f}, {0.5f, 0.5f, kInf},
        {1.0000001f, 0.5f, 0.5f},
    };
    for (const Case &c : bad) {
        SCOPED_TRACE(testing::Message() << c.a << ", " << c.b << ", " << c.c);
        EXPECT_EQ(-EINVAL, mc_hal_pwm3_set_duty(hal->pwm3, c.a, c.b, c.c));
        ExpectPwm3(fake, 0.25f, 0.5f, 0.75f, true);
    }
}

TEST_F(HalFake, Pwm3InjectedEIOChangesNothing)
{
    ASSERT_EQ(0, mc_hal_pwm3_set_duty(hal->pwm3, 0.25f, 0.5f, 0.75f));
    ASSERT_EQ(0, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_PWM3_SET_DUTY, -EIO, 1u));
    EXPECT_EQ(-EIO, mc_hal_pwm3_set_duty(hal->pwm3, 0.6f, 0.6f, 0.6f));
    ExpectPwm3(fake, 0.25f, 0.5f, 0.75f, false);

    ASSERT_EQ(0, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_PWM3_ENABLE, -EIO, 1u));
    EXPECT_EQ(-EIO, mc_hal_pwm3_enable(hal->pwm3));
    EXPECT_FALSE(fake.pwm3.enabled);

    ASSERT_EQ(0, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_PWM3_GET_STATE, -EIO, 1u));
    mc_hal_pwm3_state_t st{};
    st.duty_a = -7.0f;
    EXPECT_EQ(-EIO, mc_hal_pwm3_get_state(hal->pwm3, &st));
    EXPECT_NEAR(-7.0f, st.duty_a, kExact);
    float period_s = -7.0f;
    ASSERT_EQ(0, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_PWM3_GET_STATE, -EIO, 1u));
    EXPECT_EQ(-EIO, mc_hal_pwm3_get_period_s(hal->pwm3, &period_s));
    EXPECT_NEAR(-7.0f, period_s, kExact);
}

TEST(HalPwm3, DutyValidHelper)
{
    EXPECT_TRUE(mc_hal_pwm3_duty_valid(0.0f));
    EXPECT_TRUE(mc_hal_pwm3_duty_valid(1.0f));
    EXPECT_TRUE(mc_hal_pwm3_duty_valid(0.5f));
    EXPECT_FALSE(mc_hal_pwm3_duty_valid(kNan));
    EXPECT_FALSE(mc_hal_pwm3_duty_valid(-kNan));
    EXPECT_FALSE(mc_hal_pwm3_duty_valid(kInf));
    EXPECT_FALSE(mc_hal_pwm3_duty_valid(-1e-30f));
    EXPECT_FALSE(mc_hal_pwm3_duty_valid(1.0000001f));
}

// ---- pwm2 --------------------------------------------------------------

void ExpectPwm2(const mc_hal_fake_t &f, float a, float b, bool en)
{
    EXPECT_NEAR(a, f.pwm2.duty_a, kExact);
    EXPECT_NEAR(b, f.pwm2.duty_b, kExact);
    EXPECT_EQ(en, f.pwm2.enabled);
}

TEST_F(HalFake, Pwm2SetEnableReadBack)
{
    mc_hal_pwm2_state_t st{};
    ASSERT_EQ(0, mc_hal_pwm2_get_state(hal->pwm2, &st));
    EXPECT_NEAR(MC_HAL_PWM2_DUTY_INIT, st.duty_a, kExact);
    EXPECT_NEAR(MC_HAL_PWM2_DUTY_INIT, st.duty_b, kExact);
    EXPECT_NEAR(50e-6f, st.period_s, kExact);
    EXPECT_FALSE(st.enabled);

    ASSERT_EQ(0, mc_hal_pwm2_set_duty(hal->pwm2, -1.0f, 1.0f)); // the ends
    ASSERT_EQ(0, mc_hal_pwm2_enable(hal->pwm2));
    ASSERT_EQ(0, mc_hal_pwm2_get_state(hal->pwm2, &st));
    EXPECT_NEAR(-1.0f, st.duty_a, kExact);
    EXPECT_NEAR(1.0f, st.duty_b, kExact);
    EXPECT_TRUE(st.enabled);
    EXPECT_FALSE(fake.pwm3.enabled); // the bridges are independent

    ASSERT_EQ(0, mc_hal_pwm2_disable(hal->pwm2));
    ExpectPwm2(fake, -1.0f, 1.0f, false);
}

TEST_F(HalFake, Pwm2RejectsBadDutiesAndChangesNothing)
{
    ASSERT_EQ(0, mc_hal_pwm2_set_duty(hal->pwm2, -0.3f, 0.4f));
    ASSERT_EQ(0, mc_hal_pwm2_enable(hal->pwm2));
    const float bad[] = {kNan, kInf, -kInf, 1.01f, -1.01f, 1.0000001f};
    for (float v : bad) {
        SCOPED_TRACE(v);
        EXPECT_EQ(-EINVAL, mc_hal_pwm2_set_duty(hal->pwm2, v, 0.0f));
        EXPECT_EQ(-EINVAL, mc_hal_pwm2_set_duty(hal->pwm2, 0.0f, v));
        ExpectPwm2(fake, -0.3f, 0.4f, true);
    }
    ASSERT_EQ(0, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_PWM2_SET_DUTY, -EIO, 1u));
    EXPECT_EQ(-EIO, mc_hal_pwm2_set_duty(hal->pwm2, 0.0f, 0.0f));
    ExpectPwm2(fake, -0.3f, 0.4f, true);
    ASSERT_EQ(0, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_PWM2_DISABLE, -EIO, 1u));
    EXPECT_EQ(-EIO, mc_hal_pwm2_disable(hal->pwm2));
    ExpectPwm2(fake, -0.3f, 0.4f, true);
}

TEST(HalPwm2, DutyValidHelper)
{
    EXPECT_TRUE(mc_hal_pwm2_duty_valid(-1.0f));
    EXPECT_TRUE(mc_hal_pwm2_duty_valid(1.0f));
    EXPECT_TRUE(mc_hal_pwm2_duty_valid(0.0f));
    EXPECT_FALSE(mc_hal_pwm2_duty_valid(kNan));
    EXPECT_FALSE(mc_hal_pwm2_duty_valid(-kInf));
    EXPECT_FALSE(mc_hal_pwm2_duty_valid(-1.0000001f));
}

} // namespace
