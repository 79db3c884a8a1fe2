// Commissioning on each STM32F405 board (firmware/targets/stm32f405/
// mc_board_comm.c): the limits a board gives from its description are
// accepted by the commissioning module, keep every test inside the board's
// current-sense range and bus, and name the third shunt only where the board
// measures three phases. The drive runs the parameter table's defaults with
// the board's dead time, on the fake HAL.
#include <gtest/gtest.h>

#include <cmath>
#include <ostream>
#include <string>

extern "C" {
#include "commission/mc_comm_can.h"
#include "mc_board_comm.h"
#include "mc_board_example_gen.h"
#include "mc_board_odrive36_gen.h"
#include "mc_board_vesc6_gen.h"
#include "mc_hal_fake.h"
#include "mc_params.h"
}

namespace
{

struct BoardCase {
    const char *name;
    const mc_board_desc_t *desc;
    bool three_shunts; // from the board's pins.csv: adc_ia, adc_ib and adc_ic
};

void PrintTo(const BoardCase &b, std::ostream *os)
{
    *os << b.name;
}

class BoardComm : public ::testing::TestWithParam<BoardCase>
{
};

TEST_P(BoardComm, LimitsAreAcceptedAndInsideTheBoard)
{
    const BoardCase &b = GetParam();
    mc_params_t p = mc_params_default;
    p.dead_time_s = static_cast<float>(b.desc->deadtime_ns) * 1e-9f;
    p.i_sense_max_a = b.desc->i_sense_max_a;
    ASSERT_EQ(MC_PARAMS_OK, mc_params_validate(&p)) << b.name;

    mc_comm_can_cfg_t k;
    mc_board_comm_cfg_from(b.desc, &p, &k);

    // Every step of commissioning stays below 1.5 x i_test_a
    // (mc_commission.h): that must fit the sense range with room, or the
    // measurements clip.
    EXPECT_LT(1.5f * k.base.i_test_a, b.desc->i_sense_max_a) << b.name;
    // The largest test voltage vector fits the hexagon's inscribed circle at
    // the board's lowest bus (vbus / sqrt(3)).
    EXPECT_LT(k.base.v_test_max_v * std::sqrt(3.0f), b.desc->vbus_min_v) << b.name;
    EXPECT_EQ(b.three_shunts, k.base.three_shunts) << b.name;
    EXPECT_EQ(p.dead_time_s, k.base.dead_time_s) << b.name;

    mc_hal_fake_config_t fc;
    ASSERT_EQ(0, mc_hal_fake_config_default(&fc));
    static mc_hal_fake_t fake;
    ASSERT_EQ(0, mc_hal_fake_init(&fake, &fc));
    mc_drive_cfg_t dc;
    ASSERT_EQ(MC_PARAMS_OK, mc_params_to_drive_cfg(&p, &dc));
    static mc_drive_t d;
    ASSERT_EQ(MC_DRIVE_CFG_OK, mc_drive_init(&d, &dc, &fake.board));
    static mc_comm_t comm;
    mc_comm_can_t m{};
    EXPECT_EQ(MC_COMM_CAN_CFG_OK, mc_comm_can_init(&m, &k, &comm, &d, nullptr)) << b.name;
}

INSTANTIATE_TEST_SUITE_P(Boards, BoardComm,
                         ::testing::Values(BoardCase{"example", &mc_board_example_desc, false},
                                           BoardCase{"odrive36", &mc_board_odrive36_desc, false},
                                           BoardCase{"vesc6", &mc_board_vesc6_desc, true}),
                         [](const auto &tp) { return std::string(tp.param.name); });

} // namespace
