#include "plant_from_files.hpp"

#include <algorithm>

namespace mcsim {

void record_files(const MotorFiles& f, Summary& s) {
  const MotorSpec& m = f.motor;
  const BoardSpec& b = f.board;
  s.set_text("motor", m.name);
  s.set_text("motor_file", m.file);
  s.set_text("board", b.name);
  s.set_text("board_file", b.file);
  s.set("motor.r_ohm", m.r_ohm);
  s.set("motor.ld_h", m.ld_h);
  s.set("motor.lq_h", m.lq_h);
  s.set("motor.flux_wb", m.flux_wb);
  s.set("motor.pole_pairs", m.pole_pairs);
  s.set("motor.j_kgm2", m.j_kgm2);
  s.set("motor.b_nm_s_rad", m.b_nm_s_rad);
  s.set("motor.i_max_a", m.i_max_a);
  s.set("motor.i_rated_a", m.i_rated_a);
  s.set("motor.speed_max_rad_s", m.speed_max_rad_s);
  s.set("motor.speed_rated_rad_s", m.speed_rated_rad_s);
  s.set("board.vbus_v", b.vbus_v);
  s.set("board.pwm_hz", b.pwm_hz);
  s.set("board.dead_time_s", b.dead_time_s);
  s.set("board.current_sensors", b.current_sensors);
  s.set("board.i_sense_max_a", b.i_sense_max_a);
  s.set("board.adc_bits", b.adc_bits);
  s.set("board.encoder_cpr", static_cast<double>(b.encoder_cpr));
  s.set("board.delay_periods", b.delay_periods);
  if (b.dc_link_c_f > 0.0) {
    s.set("board.dc_link_c_f", b.dc_link_c_f);
    s.set("board.source_r_ohm", b.source_r_ohm);
    s.set("board.source_sink", b.source_sink ? 1.0 : 0.0);
    s.set("board.brake_r_ohm", b.brake_r_ohm);
  }
}

hal_host::PmsmBoardConfig build_board_cfg(const MotorFiles& f) {
  const MotorSpec& m = f.motor;
  const BoardSpec& b = f.board;
  hal_host::PmsmBoardConfig bc;
  bc.motor.R_ohm = m.r_ohm;
  bc.motor.Ld_h = m.ld_h;
  bc.motor.Lq_h = m.lq_h;
  bc.motor.flux_wb = m.flux_wb;
  bc.motor.pole_pairs = m.pole_pairs;
  bc.motor.J_kgm2 = m.j_kgm2;
  bc.motor.B_nms_rad = m.b_nm_s_rad;
  bc.motor.cogging.slots = m.slots;  // the plant's cogging (none by default)
  bc.motor.cogging.amplitude_nm = m.cogging_nm;
  bc.motor.cogging.phase_rad = m.cogging_phase_rad;
  for (int k = 0; k < mcsim::CoggingParams::kMaxHarmonics; ++k) {
    bc.motor.cogging.harmonic_nm[k] = m.cogging_h_nm[k];
    bc.motor.cogging.harmonic_phase_rad[k] = m.cogging_h_phase_rad[k];
  }
  bc.inverter.t_pwm_s = 1.0 / b.pwm_hz;
  bc.inverter.t_dead_s = b.dead_time_s;
  bc.inverter.i_dead_band_a = std::max(1e-3, 0.01 * m.i_rated_a);
  bc.vbus_v = b.vbus_v;
  bc.current_sensor.full_scale_a = b.adc_full_scale_a();
  bc.current_sensor.bits = b.adc_bits;
  bc.vbus_sensor.full_scale_v = b.vbus_full_scale_v();
  bc.vbus_sensor.bits = b.adc_bits;
  // No encoder (encoder_cpr = 0): the board model still has one, which no
  // scenario reads (the sensored scenarios refuse such a board).
  bc.encoder.counts_per_rev = b.encoder_cpr > 0 ? static_cast<int>(b.encoder_cpr) : 4096;
  bc.substeps = 4;
  bc.three_shunts = (b.current_sensors == 3);
  bc.delay_periods = b.delay_periods;
  if (b.dc_link_c_f > 0.0) {
    bc.dc_link_enabled = true;
    bc.dc_link.source_v = b.vbus_v;
    bc.dc_link.source_r_ohm = b.source_r_ohm;
    bc.dc_link.source_sink = b.source_sink;
    bc.dc_link.c_f = b.dc_link_c_f;
    bc.dc_link.brake_r_ohm = b.brake_r_ohm;
  }
  return bc;
}

void attach_load(hal_host::PmsmBoardConfig& bc, const std::function<double(double)>* load_nm) {
  if (load_nm == nullptr || !*load_nm) return;
  bc.motor.load.kind = LoadKind::kFunction;
  bc.motor.load.fn = [](double t, double, double, const void* ctx) {
    return (*static_cast<const std::function<double(double)>*>(ctx))(t);
  };
  bc.motor.load.fn_ctx = load_nm;
}

}  // namespace mcsim
