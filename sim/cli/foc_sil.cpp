#include "foc_sil.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "hal_host/sil_rig.hpp"

namespace mcsim {

mcsim::PmsmParams paper002_test_motor() {
  mcsim::PmsmParams p;
  p.R_ohm = 0.675;
  p.Ld_h = 1.14e-3;
  p.Lq_h = 1.14e-3;
  p.flux_wb = 0.11;
  p.pole_pairs = 4;
  p.J_kgm2 = 1.0e-3;
  p.B_nms_rad = 1.0e-4;
  return p;
}

FocSil::FocSil(const FocSilOptions& o) : opt_(o) {
  hal_host::PmsmBoardConfig bc;
  bc.motor = paper002_test_motor();
  bc.motor.J_kgm2 = o.J_kgm2;
  bc.motor.load = mcsim::load_constant(o.load_nm);
  bc.inverter.t_pwm_s = 1.0 / o.pwm_hz;
  bc.vbus_v = o.vbus_v;
  bc.current_sensor.full_scale_a = 20.0;
  bc.current_sensor.bits = 12;
  bc.current_sensor.noise_rms_a = o.noise_rms_a;
  bc.vbus_sensor.full_scale_v = 400.0;
  bc.encoder.counts_per_rev = 8192;
  bc.substeps = o.substeps;
  bc.three_shunts = o.three_shunts;
  bc.delay_periods = o.delay_periods;
  bc.omega_m0_rad_s = o.omega_m0_rad_s;
  bc.theta_m0_rad = o.theta_m0_rad;
  board_ = std::make_unique<hal_host::PmsmBoard>(bc);

  float kp = 0.0f, ki = 0.0f;
  const auto& m = bc.motor;
  if (mc_foc_f32_gains_from_bandwidth(static_cast<float>(m.R_ohm), static_cast<float>(m.Ld_h),
                                      static_cast<float>(o.bw_rad_s), &kp, &ki) != 0u) {
    throw std::invalid_argument("current-loop bandwidth rejected by the firmware");
  }
  kp_ = kp;
  ki_ = ki;
  mc_drive_cfg_t dc{};
  dc.foc.r_ohm = static_cast<float>(m.R_ohm);
  dc.foc.ld_h = static_cast<float>(m.Ld_h);
  dc.foc.lq_h = static_cast<float>(m.Lq_h);
  dc.foc.flux_wb = static_cast<float>(m.flux_wb);
  dc.foc.kp_d_v_per_a = kp;
  dc.foc.ki_d_v_per_as = ki;
  dc.foc.kp_q_v_per_a = kp;
  dc.foc.ki_q_v_per_as = ki;
  dc.foc.dt_s = static_cast<float>(1.0 / o.pwm_hz);
  dc.foc.aw = MC_PI_AW_CLAMP;
  dc.foc.kaw_per_s = 0.0f;
  dc.foc.limit_mode = MC_SVPWM_LIMIT_CIRCLE;
  dc.foc.v_limit_ratio = 0.95f;
  dc.foc.v_abs_max_v = static_cast<float>(o.vbus_v);
  dc.foc.decouple = true;
  dc.pole_pairs = static_cast<uint32_t>(m.pole_pairs);
  dc.encoder_offset_rad = 0.0f;
  dc.speed_pll_bw_rad_s = static_cast<float>(o.speed_pll_bw_rad_s);
  dc.slow_loop_div = o.slow_loop_div;
  dc.i_max_a = 10.0f;
  dc.i_trip_a = 15.0f;
  dc.vbus_min_v = static_cast<float>(0.5 * o.vbus_v);
  dc.vbus_max_v = static_cast<float>(1.5 * o.vbus_v);
  // Supervision: 1.5x rated speed (1000 r/min), the power stage's 100 degC,
  // stall = 90 % of i_max below 1 rad/s for half a second.
  dc.omega_max_rad_s = 1.5f * 1000.0f * 2.0f * 3.14159265f / 60.0f;
  dc.temp_max_c = 100.0f;
  dc.stall_current_frac = 0.9f;
  dc.stall_speed_rad_s = 1.0f;
  dc.stall_time_s = 0.5f;
  // Three shunts: the phase currents must sum to zero within 1 A (12-bit
  // ADC at 20 A full scale: 3 LSB of rounding is 15 mA; 1 A is a fault).
  dc.i_unbalance_max_a = o.three_shunts ? 1.0f : 0.0f;
  // Open phase: a phase commanded 1 A or more must carry at least a quarter
  // of it (0.25 A: 25 LSB of the 12-bit, 20 A converter), net over 2 ms, or
  // 2/bw when the loop is slower: a reversing reference takes the current
  // across +-25 % in about 0.5/bw plus the one-period delay (0.45 ms at
  // 200 Hz), and the PIs need longer to wind up to the 110 V limit on the
  // error a broken phase leaves (at most the 14 A reference: 20 V + 12 kV/s,
  // 7.5 ms at 200 Hz; both times scale with 1/bw).
  dc.open_phase_i_min_a = 1.0f;
  dc.open_phase_time_s = static_cast<float>(std::max(2.0e-3, 2.0 / o.bw_rad_s));
  const uint32_t err = mc_drive_init(&drive_, &dc, board_->hal());
  if (err != MC_DRIVE_CFG_OK) {
    throw std::invalid_argument("drive configuration rejected, MC_DRIVE_CFG bits 0x" +
                                std::to_string(err));
  }
}

void FocSil::step() {
  (void)hal_host::sil_period(*board_, drive_);
}

}  // namespace mcsim
