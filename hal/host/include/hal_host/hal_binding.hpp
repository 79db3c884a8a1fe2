// hal_host::HalBinding<Board>: the C ops tables of the HAL bound to a C++
// simulated board's member functions, and the configuration check shared by
// the boards. A board provides the members its capabilities need
// (adc_read, pwm_set_duty, encoder_read, tick_read, fault_read, ...), all
// noexcept: they are called from C and must never throw across it. Only the
// tables a board uses are instantiated.
#ifndef HAL_HOST_HAL_BINDING_HPP
#define HAL_HOST_HAL_BINDING_HPP

#include <stdexcept>
#include <string>

#include "hal/hal.h"
#include "mcsim/status.hpp"

namespace hal_host {

// Throws std::invalid_argument naming the parameter set that was refused.
inline void check_config(mcsim::Status s, const char* what) {
  if (s != mcsim::Status::kOk) {
    throw std::invalid_argument(std::string(what) + ": " + mcsim::status_name(s));
  }
}

// The fault capability of a simulated board: inputs (gate-driver fault,
// over-current comparator) wired to the break input, the latched gate kill,
// and the release rule of hal/fault.h (refused while an input is asserted).
struct FaultLine {
  uint32_t active = 0;   // MC_HAL_FAULT_* asserted now
  uint32_t latched = 0;  // asserted since the last release
  bool killed = false;   // gate kill latched: all switches open

  void set_inputs(uint32_t mask) {
    active = mask & MC_HAL_FAULT_ALL;
    latched |= active;
    if (active != 0U) killed = true;  // comparator wired to the break input
  }
  void read(mc_hal_fault_status_t* st) const {
    st->active_mask = active;
    st->latched_mask = latched;
    st->gate_killed = killed;
  }
  // Returns false (nothing changed) while an input is still asserted.
  bool release() {
    if (active != 0U) return false;
    killed = false;
    latched = 0U;
    return true;
  }
};

template <class Board>
struct HalBinding {
  static Board* b(void* ctx) noexcept { return static_cast<Board*>(ctx); }

  static int adc_read(void* c, mc_hal_adc_sample_t* s) noexcept { return b(c)->adc_read(s); }
  static int adc_read_temp(void* c, mc_hal_adc_temp_t* t) noexcept {
    return b(c)->adc_read_temp(t);
  }
  static int pwm3_set(void* c, float x, float y, float z) noexcept {
    return b(c)->pwm_set_duty(x, y, z);
  }
  static int pwm2_set(void* c, float x, float y) noexcept { return b(c)->pwm_set_duty(x, y); }
  static int pwm_enable(void* c) noexcept { return b(c)->pwm_enable(); }
  static int pwm_disable(void* c) noexcept { return b(c)->pwm_disable(); }
  static int pwm3_state(void* c, mc_hal_pwm3_state_t* s) noexcept { return b(c)->pwm_get_state(s); }
  static int pwm2_state(void* c, mc_hal_pwm2_state_t* s) noexcept { return b(c)->pwm_get_state(s); }
  static int encoder_read(void* c, mc_hal_encoder_sample_t* s) noexcept {
    return b(c)->encoder_read(s);
  }
  static int tick_read(void* c, uint32_t* t) noexcept { return b(c)->tick_read(t); }
  static int tick_freq(void* c, uint32_t* hz) noexcept { return b(c)->tick_freq(hz); }
  static int fault_read(void* c, mc_hal_fault_status_t* s) noexcept { return b(c)->fault_read(s); }
  static void fault_kill(void* c) noexcept { b(c)->fault_gate_kill(); }
  static int fault_release(void* c) noexcept { return b(c)->fault_gate_release(); }

  static int brake_set(void* c, float d) noexcept { return b(c)->brake_set_duty(d); }

  static inline const mc_hal_adc_ops_t kAdc{&adc_read, &adc_read_temp};
  static inline const mc_hal_pwm3_ops_t kPwm3{&pwm3_set, &pwm_enable, &pwm_disable, &pwm3_state};
  static inline const mc_hal_pwm2_ops_t kPwm2{&pwm2_set, &pwm_enable, &pwm_disable, &pwm2_state};
  static inline const mc_hal_encoder_ops_t kEncoder{&encoder_read};
  static inline const mc_hal_tick_ops_t kTick{&tick_read, &tick_freq};
  static inline const mc_hal_fault_ops_t kFault{&fault_read, &fault_kill, &fault_release};
  static inline const mc_hal_brake_ops_t kBrake{&brake_set};
};

}  // namespace hal_host

#endif  // HAL_HOST_HAL_BINDING_HPP
