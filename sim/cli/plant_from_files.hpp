// The simulated board and motor from the motor and board files
// (motor_file.hpp): the plant's configuration (hal_host::PmsmBoardConfig)
// and the files' values in a run's summary. The drive's side is not here:
// the application boots the files' parameter table (app_params.hpp) and
// the firmware's C builders configure the drive from it.
#pragma once

#include <functional>

#include "hal_host/pmsm_board.hpp"
#include "motor_file.hpp"
#include "scenario.hpp"

namespace mcsim {

/// The plant for the files: the motor (cogging included), the inverter,
/// the sensors and the DC link (a source resistance and a capacitor when
/// the board file gives one).
hal_host::PmsmBoardConfig build_board_cfg(const MotorFiles& f);

/// The load torque load_nm(t) [N m] opposing positive rotation on the
/// plant bc (load_nm, kept alive by the caller; null or empty: none).
void attach_load(hal_host::PmsmBoardConfig& bc, const std::function<double(double)>* load_nm);

/// Every motor and board value into the summary (motor.*, board.*).
void record_files(const MotorFiles& f, Summary& s);

}  // namespace mcsim
