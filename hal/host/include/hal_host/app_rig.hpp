// hal_host::app_period(): one PWM period of the drive image, as the image's
// interrupts run it (firmware/targets/stm32f405/main.c), on the simulated
// board. The SIL's AppTarget (sim/cli/app_target_sil.cpp), through which
// every scenario that runs the drive application (the generic motor
// scenarios and can-telemetry) runs it, calls it, so what a scenario shows
// is the sequence the board runs:
//
//   1. board.sample()          TIM1 update -> injected conversions: the plant
//                              at the period start t_k is measured.
//   2. mc_app_can_rx_isr()     the CAN receive interrupt: the frames the bus
//                              delivered since the last period into the
//                              application's ring (CAN1_RX0 on the board, the
//                              CAN_RX frames before MEAS in the PIL link).
//   3. on_sampled()            optional probe of the state the interrupt sees.
//   4. mc_app_fast_step()      ADC_IRQHandler's body: the drive's fast step
//                              (current loop, law, supervision of the sample).
//   5. mc_app_slow_step()      PendSV's body, when the fast step says it is
//                              due: the drive's slow step and the
//                              application's slow work (commands, timeout,
//                              telemetry). On the MCU PendSV runs right after
//                              the ADC interrupt, within the period.
//   6. on_controlled()         optional: the period's outputs are written, the
//                              plant still at t_k.
//   7. board.advance()         the plant from t_k to t_k + T with the duties
//                              and bridge state in force (the board applies
//                              its computation delay).
//
// Returns whether the slow step ran and how many frames the receive
// interrupt took from the HAL. The drive-alone rig (no application: the
// paper and kernel scenarios) is sil_rig.hpp's sil_period.
#ifndef HAL_HOST_APP_RIG_HPP
#define HAL_HOST_APP_RIG_HPP

#include "hal_host/sil_rig.hpp"
extern "C" {
#include "mc_app.h"
}

namespace hal_host {

struct AppPeriod {
  bool slow_ran = false;   // PendSV's body ran in this period
  uint32_t rx_frames = 0;  // frames the CAN receive interrupt took from the HAL
};

template <class OnSampled = NoHook, class OnControlled = NoHook>
inline AppPeriod app_period(SimBoard& board, mc_app_t& app, OnSampled&& on_sampled = OnSampled{},
                            OnControlled&& on_controlled = OnControlled{}) {
  AppPeriod r;
  board.sample();
  r.rx_frames = mc_app_can_rx_isr(&app);
  on_sampled();
  r.slow_ran = mc_app_fast_step(&app);
  if (r.slow_ran) mc_app_slow_step(&app);
  on_controlled();
  board.advance();
  return r;
}

}  // namespace hal_host

#endif  // HAL_HOST_APP_RIG_HPP
