#include "board_hall.hpp"

#include <cmath>
#include <string>

#include "app_target.hpp"
#include "scenario.hpp"

namespace mcsim {

HallParams hall_params_of(const MotorFiles& f) {
  HallParams h;
  const BoardSpec& b = f.board;
  h.pole_pairs = f.motor.pole_pairs;
  h.spacing = HallSpacing::k120;
  h.offset_e_rad = b.hall_offset_e_rad;
  h.hysteresis_e_rad = b.hall_hysteresis_e_rad;
  for (int k = 0; k < 6; ++k) {
    h.edge_error_e_rad[k] = (k % 2 == 0) ? b.hall_edge_error_e_rad : -b.hall_edge_error_e_rad;
  }
  return h;
}

void check_hall(MotorFiles& f) {
  BoardSpec& b = f.board;
  if (b.encoder != kEncoderHall) return;
  b.encoder_cpr = 6L * f.motor.pole_pairs;
  if (hall_params_of(f).validate() != Status::kOk) {
    throw UsageError(
        "board.hall_hysteresis_e_rad " + std::to_string(b.hall_hysteresis_e_rad) +
        " and board.hall_edge_error_e_rad " + std::to_string(b.hall_edge_error_e_rad) +
        ": |edge error| + band / 2 must stay below 30 degrees el. (0.5236 rad), or the "
        "sensors' edges change order");
  }
  if (b.hall_fault != "none" && b.hall_fault != "all_low" && b.hall_fault != "all_high") {
    throw UsageError("board.hall_fault '" + b.hall_fault +
                     "': none, all_low (000: the supply lost) or all_high (111: the connector "
                     "off)");
  }
}

double hall_true_offset(const MotorFiles& f) {
  constexpr double kTwoPi = 6.28318530717958647692;
  const double a = std::fmod(f.board.hall_offset_e_rad, kTwoPi);
  return a < 0.0 ? a + kTwoPi : a;
}

std::string hall_err_names(uint32_t bits) {
  // MC_HALL_ERR_* (bits 0..3) and the hand-over's fallback
  // (MC_DRIVE_HALL_ERR_OBS_DISAGREE, _OBS_NAN: bits 8, 9)
  static const char* const names[] = {"NULL", "CFG", "ILLEGAL", "SEQUENCE",     "",
                                      "",     "",    "",        "OBS_DISAGREE", "OBS_NAN"};
  std::string s;
  for (uint32_t i = 0; i < 10u; ++i) {
    if (names[i][0] == '\0') continue;
    if ((bits & (1u << i)) != 0u) s += (s.empty() ? "" : "|") + std::string(names[i]);
  }
  return s.empty() ? "none" : s;
}

void set_board_hall(const MotorFiles& f, AppSetup& s) {
  if (f.board.encoder != kEncoderHall) return;
  s.hall = true;
  s.hall_params = hall_params_of(f);
  s.hall_fault = f.board.hall_fault == "all_low"    ? HallFault::kAllLow
                 : f.board.hall_fault == "all_high" ? HallFault::kAllHigh
                                                    : HallFault::kNone;
  s.hall_fault_at_s = f.board.hall_fault_at_s;
}

}  // namespace mcsim
