#include "hal_host/hall_input.hpp"

#include <stdexcept>
#include <string>

namespace hal_host {

namespace {

int hall_read(void* ctx, uint32_t* p_code) {
  return static_cast<HallInput*>(ctx)->read(p_code);
}

}  // namespace

HallInput::HallInput(const PmsmBoard& board, const mcsim::HallParams& p, double theta_m0_rad)
    : board_(board) {
  const mcsim::Status st = hall_.configure(p);
  if (st != mcsim::Status::kOk) {
    throw std::invalid_argument("Hall sensors: the plant's model refuses its parameters (" +
                                std::string(mcsim::status_name(st)) + ")");
  }
  hall_.reset(theta_m0_rad);
  ops_.read = hall_read;
  dev_.ops = &ops_;
  dev_.ctx = this;
}

void HallInput::set_fault(mcsim::HallFault f, int sensor, double at_s) {
  if ((f == mcsim::HallFault::kStuckLow || f == mcsim::HallFault::kStuckHigh) &&
      (sensor < 0 || sensor > 2)) {
    throw std::invalid_argument("Hall sensors: no sensor " + std::to_string(sensor));
  }
  fault_ = f;
  fault_sensor_ = sensor;
  fault_at_s_ = at_s;
}

int HallInput::read(uint32_t* p_code) noexcept {
  if (fault_at_s_ >= 0.0 && board_.t_s() >= fault_at_s_) {
    (void)hall_.set_fault(fault_, fault_sensor_);  // checked by set_fault()
    fault_at_s_ = -1.0;
  }
  *p_code = hall_.sample(board_.rotor_frame_state()(3));
  return 0;
}

}  // namespace hal_host
