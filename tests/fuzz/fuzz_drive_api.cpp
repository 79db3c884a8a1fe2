// libFuzzer target: the drive application under arbitrary measurements and
// API calls (fake HAL). Each 8-byte record of the input is one event: a
// sample with arbitrary float bits (NaN, inf, huge, denormal), an encoder
// count, a current reference, a mode change, a clear-faults request, a
// fault-line change, or a tick jump; then a fast step (and the slow step when
// due). Invariants checked after every step, whatever the input:
//  - the bridge is enabled only in CURRENT or CTRL mode with no fault;
//  - every duty the drive ever wrote is in [0, 1];
//  - in FAULT mode the bridge is off.
#include <cstdint>
#include <cstdlib>
#include <cstring>

extern "C" {
#include "mc_drive.h"
#include "mc_hal_fake.h"
}

namespace {

float f32_from(const uint8_t* p) {
  float f;
  std::memcpy(&f, p, sizeof f);
  return f;
}

mc_drive_cfg_t good_cfg() {
  mc_drive_cfg_t c{};
  c.foc.r_ohm = 0.1f;
  c.foc.ld_h = 100e-6f;
  c.foc.lq_h = 100e-6f;
  c.foc.flux_wb = 0.01f;
  c.foc.kp_d_v_per_a = c.foc.kp_q_v_per_a = 0.1f;
  c.foc.ki_d_v_per_as = c.foc.ki_q_v_per_as = 100.0f;
  c.foc.dt_s = 50e-6f;
  c.foc.aw = MC_PI_AW_CLAMP;
  c.foc.limit_mode = MC_SVPWM_LIMIT_CIRCLE;
  c.foc.v_limit_ratio = 1.0f;
  c.foc.v_abs_max_v = 40.0f;
  c.foc.decouple = true;
  c.pole_pairs = 4u;
  c.speed_pll_bw_rad_s = 500.0f;
  c.slow_loop_div = 10u;
  c.i_max_a = 20.0f;
  c.i_trip_a = 30.0f;
  c.vbus_min_v = 10.0f;
  c.vbus_max_v = 60.0f;
  c.omega_max_rad_s = 500.0f;
  c.temp_max_c = 90.0f;
  c.stall_current_frac = 0.9f;
  c.stall_speed_rad_s = 1.0f;
  c.stall_time_s = 0.1f;
  c.i_unbalance_max_a = 2.0f;
  c.open_phase_i_min_a = 1.0f;
  c.open_phase_time_s = 1.0e-3f;
  return c;
}

bool duty_ok(float x) {
  return x >= 0.0f && x <= 1.0f;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static mc_hal_fake_t fake;
  static mc_drive_t d;
  mc_hal_fake_config_t fc;
  if (mc_hal_fake_config_default(&fc) != 0 || mc_hal_fake_init(&fake, &fc) != 0) std::abort();
  const mc_drive_cfg_t cfg = good_cfg();
  if (mc_drive_init(&d, &cfg, &fake.board) != MC_DRIVE_CFG_OK) std::abort();
  (void)mc_hal_fake_adc_set_temp(&fake, 30.0f, 30.0f, MC_HAL_ADC_TEMP_VALID_ALL);
  (void)mc_hal_fake_encoder_set(&fake, 0u, MC_HAL_ENCODER_FLAG_VALID);

  for (size_t i = 0; i + 8 <= size; i += 8) {
    const uint8_t* r = data + i;
    const float a = f32_from(r + 1);
    const float b = f32_from(r + 4);  // overlaps a on purpose: more bit patterns
    switch (r[0] % 8u) {
      case 0:
        (void)mc_hal_fake_adc_set_sample(&fake, a, b, -(a + b), 24.0f, MC_HAL_ADC_VALID_ALL);
        break;
      case 1:
        (void)mc_hal_fake_adc_set_sample(&fake, a, 0.0f, 0.0f, b, r[7] & 0x0Fu);
        break;
      case 2:
        (void)mc_hal_fake_encoder_set(
            &fake, (uint32_t)(r[1] | (r[2] << 8)) % fc.encoder_counts_per_rev, r[3] & 3u);
        break;
      case 3:
        (void)mc_drive_set_current_ref(&d, a, b);
        break;
      case 4:
        (void)mc_drive_set_mode(&d, (mc_drive_mode_t)(r[1] % 3u == 2u ? 0 : r[1] % 3u));
        break;
      case 5:
        (void)mc_drive_clear_faults(&d);
        break;
      case 6:
        (void)mc_hal_fake_fault_set_inputs(&fake, r[1] & MC_HAL_FAULT_ALL);
        break;
      default:
        (void)mc_hal_fake_tick_advance(&fake, r[1]);
        break;
    }
    if (mc_drive_fast_step(&d)) mc_drive_slow_step(&d);
    const bool running = d.mode == MC_DRIVE_MODE_CURRENT || d.mode == MC_DRIVE_MODE_CTRL;
    if (fake.pwm3.enabled && (!running || d.faults != 0u)) std::abort();
    if (d.mode == MC_DRIVE_MODE_FAULT && fake.pwm3.enabled) std::abort();
    if (!duty_ok(fake.pwm3.duty_a) || !duty_ok(fake.pwm3.duty_b) || !duty_ok(fake.pwm3.duty_c)) {
      std::abort();
    }
  }
  return 0;
}
