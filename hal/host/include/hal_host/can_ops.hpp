// The HAL's CAN ops table (hal/can.h) for a host backend class with
// send/receive/get_status members: one table per class, ctx = the object.
#ifndef HAL_HOST_CAN_OPS_HPP
#define HAL_HOST_CAN_OPS_HPP

#include "hal/can.h"

namespace hal_host {

template <class T>
const mc_hal_can_ops_t* can_ops() {
  static const mc_hal_can_ops_t ops = {
      [](void* ctx, const mc_hal_can_frame_t* f) { return static_cast<T*>(ctx)->send(f); },
      [](void* ctx, mc_hal_can_frame_t* f) { return static_cast<T*>(ctx)->receive(f); },
      [](void* ctx, mc_hal_can_status_t* s) { return static_cast<T*>(ctx)->get_status(s); }};
  return &ops;
}

}  // namespace hal_host

#endif  // HAL_HOST_CAN_OPS_HPP
