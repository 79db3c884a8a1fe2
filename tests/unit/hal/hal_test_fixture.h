// Shared fixture: a freshly initialised fake board with default config.
#ifndef HAL_TEST_FIXTURE_H
#define HAL_TEST_FIXTURE_H

#include <gtest/gtest.h>

#include "hal/hal.h"
#include "mc_hal_fake.h"

// Tolerance for float fields: 0. The fake and the wrappers copy floats
// without any arithmetic, so a stored value must come back bit-identical;
// any difference at all is a bug.
constexpr float kExact = 0.0f;

class HalFake : public ::testing::Test
{
  protected:
    void SetUp() override
    {
        ASSERT_EQ(0, mc_hal_fake_config_default(&cfg));
        ASSERT_EQ(0, mc_hal_fake_init(&fake, &cfg));
        hal = &fake.board;
    }

    mc_hal_fake_config_t cfg{};
    mc_hal_fake_t fake{};
    const mc_hal_t *hal = nullptr;
};

#endif // HAL_TEST_FIXTURE_H
