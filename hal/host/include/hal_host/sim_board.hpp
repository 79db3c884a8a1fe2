// hal_host::SimBoard: what the SIL rig (sil_rig.hpp) needs of a simulated
// board: the HAL it binds, the ADC/encoder trigger at the start of a PWM
// period and the plant's advance over it. PmsmBoard and StepperBoard
// implement it.
#ifndef HAL_HOST_SIM_BOARD_HPP
#define HAL_HOST_SIM_BOARD_HPP

#include "hal/hal.h"

namespace hal_host {

class SimBoard {
 public:
  SimBoard() = default;
  SimBoard(const SimBoard&) = delete;
  SimBoard& operator=(const SimBoard&) = delete;

  // The HAL bound to this board (the drive is initialised with it).
  virtual const mc_hal_t* hal() const = 0;
  // ADC and encoder trigger at the start of the period: the measurements the
  // next fast step reads, taken from the plant state at t_s().
  virtual void sample() = 0;
  // The plant over one period with the duties (and enable) in force.
  virtual void advance() = 0;
  // Simulated time at the start of the next period [s].
  virtual double t_s() const = 0;
  // PWM (= control) period [s].
  virtual double period_s() const = 0;

 protected:
  // Boards are owned by their concrete type, never deleted through this.
  ~SimBoard() = default;
};

}  // namespace hal_host

#endif  // HAL_HOST_SIM_BOARD_HPP
