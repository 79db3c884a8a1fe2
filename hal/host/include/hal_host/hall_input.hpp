// hal_host::HallInput: the simulated board's three Hall inputs, the HAL
// capability hal/hall.h the images' mc_f405_hall offers, read from the
// plant's Hall model (mcsim::HallSensors: placement errors, hysteresis,
// faults) at the rotor's angle of the board's last sample (the ADC trigger
// at the period start: the fast step reads it between PmsmBoard::sample()
// and advance(), as the image reads its GPIOs right after the ADC).
//
// The plant powers up with the rotor at the board's theta_m0_rad (the
// sensors' states without hysteresis). set_fault() injects the model's
// faults (all low, all high, one sensor stuck) from the next read on.
#ifndef HAL_HOST_HALL_INPUT_HPP
#define HAL_HOST_HALL_INPUT_HPP

#include <cstdint>

#include "hal/hall.h"
#include "hal_host/pmsm_board.hpp"
#include "mcsim/hall.hpp"

namespace hal_host {

class HallInput {
 public:
  // Throws std::invalid_argument naming the refused parameter (the model's
  // validate()); board must outlive this.
  HallInput(const PmsmBoard& board, const mcsim::HallParams& p, double theta_m0_rad);
  HallInput(const HallInput&) = delete;
  HallInput& operator=(const HallInput&) = delete;

  const mc_hal_hall_t* hal() const { return &dev_; }
  // Throws std::invalid_argument for a sensor outside 0..2 with a stuck
  // fault. From the first read at or after the board's time at_s on (0:
  // the next read).
  void set_fault(mcsim::HallFault f, int sensor = 0, double at_s = 0.0);
  const mcsim::HallSensors& sensors() const { return hall_; }
  int read(uint32_t* p_code) noexcept;

 private:
  const PmsmBoard& board_;
  mcsim::HallSensors hall_;
  mcsim::HallFault fault_ = mcsim::HallFault::kNone;
  int fault_sensor_ = 0;
  double fault_at_s_ = -1.0;  // < 0: nothing pending
  mc_hal_hall_ops_t ops_{};
  mc_hal_hall_t dev_{};
};

}  // namespace hal_host

#endif  // HAL_HOST_HALL_INPUT_HPP
