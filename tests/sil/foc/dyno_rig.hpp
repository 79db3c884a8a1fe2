// The drive of a files' parameter table in CURRENT mode on the simulated
// board, its rotor driven by a dyno (a load torque that is a function of
// time): shared by the current-loop SIL tests of this folder that hold the
// rotor at a speed (test_delay_comp_sil, test_dead_time_sil). The drive is
// the image's: mc_params_to_drive_cfg on the table, stepped with
// hal_host::sil_period by the test.
#pragma once

#include <gtest/gtest.h>

#include <functional>

#include "hal_host/sil_rig.hpp"
#include "plant_from_files.hpp"

extern "C" {
#include "mc_drive.h"
#include "mc_params.h"
}

namespace mcsim {

struct DynoRig {
  // plant: the files the plant is built from (its inertia may include the
  // dyno's); p: the drive's table; load: the dyno's torque [N m] at t [s]
  // (positive: braking), kept by the caller for the rig's life.
  DynoRig(const MotorFiles& plant, const mc_params_t& p, const std::function<double(double)>* load)
      : board(board_cfg(plant, load)) {
    mc_drive_cfg_t dc{};
    EXPECT_EQ(mc_params_to_drive_cfg(&p, &dc), MC_PARAMS_OK);
    dead_time_comp = dc.dead_time_comp;
    EXPECT_EQ(mc_drive_init(&d, &dc, board.hal()), MC_DRIVE_CFG_OK);
    EXPECT_EQ(mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT), 0);
  }
  DynoRig(const DynoRig&) = delete;
  DynoRig& operator=(const DynoRig&) = delete;

  hal_host::PmsmBoard board;
  mc_drive_t d{};
  bool dead_time_comp = false;  // as the builder set it from the table

 private:
  static hal_host::PmsmBoardConfig board_cfg(const MotorFiles& f,
                                             const std::function<double(double)>* load) {
    hal_host::PmsmBoardConfig bc = build_board_cfg(f);
    attach_load(bc, load);
    return bc;
  }
};

}  // namespace mcsim
