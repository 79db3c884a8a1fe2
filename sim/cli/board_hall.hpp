// The simulated board's Hall sensors (--set board.encoder=hall): the
// plant's model (mcsim::HallSensors, sim/include/mcsim/hall.hpp) read by
// the board through the HAL contract the images use (hal/hall.h:
// hal_host::HallInput), the drive binding the Hall kernel to it
// (encoder_type 1, firmware/app/drive/mc_drive_hall.h).
//
// Board keys (motor_file.hpp BoardSpec; only with encoder = "hall"):
//   hall_offset_e_rad      sensor A's electrical angle (default 0: the
//                          drive's default table is then the sensors')
//   hall_hysteresis_e_rad  the sensors' full band (default 0)
//   hall_edge_error_e_rad  placement error of every edge, rising +e,
//                          falling -e (default 0)
//   hall_fault             none (default), all_low (000: the supply lost),
//                          all_high (111: the connector off)
//   hall_fault_at_s        from this time of the run on (default 0: from
//                          power-up)
// encoder_cpr is then 6 pole_pairs whatever the board says: the Hall's
// edges per mechanical turn, which the gains' encoder bound (mc_gains.c,
// mc_gains_enc_bw_quant_rad_s) and the drive's validation take.
#pragma once

#include <cstdint>
#include <string>

#include "mcsim/hall.hpp"
#include "motor_file.hpp"

namespace mcsim {

struct AppSetup;

/// encoder_cpr = 6 pole_pairs for a Hall board; the model's parameters
/// checked together (UsageError naming the keys when the band and the
/// edge error leave an edge out of order).
void check_hall(MotorFiles& f);

/// The plant's Hall model of the files' board (pole pairs, 120-degree
/// placement, the keys above).
HallParams hall_params_of(const MotorFiles& f);

/// A Hall board: the setup's Hall inputs (AppSetup::hall).
void set_board_hall(const MotorFiles& f, AppSetup& s);

/// The encoder_offset_rad the drive needs with the default table (sector 0
/// from the angle 0) on this model: sensor A's angle, where sector 0 (code
/// 5) begins; the edges' errors (+e rising, -e falling) and the band
/// cancel over the six edges and both directions.
double hall_true_offset(const MotorFiles& f);

/// MC_HALL_ERR_* bits by name ("ILLEGAL|SEQUENCE"; "none").
std::string hall_err_names(uint32_t bits);

}  // namespace mcsim
