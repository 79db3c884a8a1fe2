// hal_host::sil_period(): one PWM period of the software-in-the-loop rig,
// run the way the MCU runs it. Every scenario and SIL test that closes the
// loop around the drive goes through it, so the timing is written once:
//
//   1. board.sample()        the ADC/encoder trigger at the period start t_k
//                            (TIM1 update -> injected conversions); the
//                            plant state at t_k is measured.
//   2. on_sampled()          optional: inputs the application writes before
//                            the interrupt reads them (references, a
//                            cascade's outer loop), and probes of the state
//                            the interrupt will see.
//   3. mc_drive_fast_step()  the current-loop interrupt (ADC end of
//      mc_drive_slow_step()  conversion); the slow step runs right after it
//                            when the drive's scheduler says it is due (on
//                            the MCU a lower-priority task the interrupt
//                            releases; it finishes within the period).
//   4. on_controlled()       optional: the period's outputs are written, the
//                            plant is still at t_k (recording a row).
//   5. board.advance()       the plant from t_k to t_k + T with the duties
//                            in force (the board applies its computation
//                            delay and the enable/gate-kill state).
//
// The hooks are callables taking no argument (lambdas; inlined, nothing is
// allocated). Returns true when the slow step ran.
#ifndef HAL_HOST_SIL_RIG_HPP
#define HAL_HOST_SIL_RIG_HPP

#include "hal_host/sim_board.hpp"
extern "C" {
#include "mc_drive.h"
}

namespace hal_host {

// The hook that does nothing (the default of both hooks).
struct NoHook {
  void operator()() const noexcept {}
};

template <class OnSampled = NoHook, class OnControlled = NoHook>
inline bool sil_period(SimBoard& board, mc_drive_t& drive, OnSampled&& on_sampled = OnSampled{},
                       OnControlled&& on_controlled = OnControlled{}) {
  board.sample();
  on_sampled();
  const bool slow_due = mc_drive_fast_step(&drive);
  if (slow_due) mc_drive_slow_step(&drive);
  on_controlled();
  board.advance();
  return slow_due;
}

}  // namespace hal_host

#endif  // HAL_HOST_SIL_RIG_HPP
