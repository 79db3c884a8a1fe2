// The power-up alignment and the index search on the simulated board: the
// paper-002 test motor (0.3 kW, 4 pole pairs) on hal_host::PmsmBoard, the
// drive (firmware/app/drive) in CTRL mode with the plug-in, its encoder
// offset unknown (0). The encoder counts from the rotor's angle at
// power-up (theta_m0), as an incremental encoder does; its index mark is
// at index_angle_rad. The offset the drive needs is then p theta_m0.
#include <gtest/gtest.h>

#include <cerrno>
#include <cmath>
#include <memory>
#include <random>

#include "hal_host/pmsm_board.hpp"
#include "hal_host/sil_rig.hpp"
extern "C" {
#include "mc_ctrl_align.h"
#include "mc_drive.h"
}

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kPwmHz = 20000.0;
constexpr int kPolePairs = 4;
constexpr double kFlux = 0.11;
constexpr double kJ = 1.0e-3;
constexpr double kIAlign = 2.0;                   // A
constexpr double kKt = 1.5 * kPolePairs * kFlux;  // N m per A at 90 degrees
constexpr double kHold = kKt * kIAlign;           // 1.32 N m

double wrap_2pi(double x) {
  double w = std::fmod(x, 2.0 * kPi);
  return (w < 0.0) ? w + 2.0 * kPi : w;
}

double wrap_pi(double x) {
  return wrap_2pi(x + kPi) - kPi;
}

struct Sil {
  std::unique_ptr<hal_host::PmsmBoard> board;
  mc_drive_cfg_t dc{};
  mc_drive_t d{};

  Sil(double theta_m0, double load_nm, bool index, double index_at,
      uint32_t angle_ref = MC_DRIVE_ANGLE_REF_STORED) {
    hal_host::PmsmBoardConfig bc;
    bc.motor.R_ohm = 0.675;
    bc.motor.Ld_h = 1.14e-3;
    bc.motor.Lq_h = 1.14e-3;
    bc.motor.flux_wb = kFlux;
    bc.motor.pole_pairs = kPolePairs;
    bc.motor.J_kgm2 = kJ;
    bc.motor.B_nms_rad = 1.0e-4;
    bc.motor.load = mcsim::load_constant(load_nm);
    bc.inverter.t_pwm_s = 1.0 / kPwmHz;
    bc.vbus_v = 48.0;
    bc.current_sensor.full_scale_a = 20.0;
    bc.vbus_sensor.full_scale_v = 100.0;
    bc.encoder.counts_per_rev = 8192;
    bc.encoder.has_index = index;
    bc.encoder.index_angle_rad = index_at;
    bc.theta_m0_rad = theta_m0;
    board = std::make_unique<hal_host::PmsmBoard>(bc);

    float kp = 0.0f, ki = 0.0f;
    EXPECT_EQ(
        mc_foc_f32_gains_from_bandwidth(0.675f, 1.14e-3f, 2.0f * 3.14159265f * 500.0f, &kp, &ki),
        0u);
    dc.foc.r_ohm = 0.675f;
    dc.foc.ld_h = 1.14e-3f;
    dc.foc.lq_h = 1.14e-3f;
    dc.foc.flux_wb = static_cast<float>(kFlux);
    dc.foc.kp_d_v_per_a = kp;
    dc.foc.ki_d_v_per_as = ki;
    dc.foc.kp_q_v_per_a = kp;
    dc.foc.ki_q_v_per_as = ki;
    dc.foc.dt_s = static_cast<float>(1.0 / kPwmHz);
    dc.foc.aw = MC_PI_AW_CLAMP;
    dc.foc.limit_mode = MC_SVPWM_LIMIT_CIRCLE;
    dc.foc.v_limit_ratio = 0.95f;
    dc.foc.v_abs_max_v = 60.0f;
    dc.foc.decouple = true;
    dc.pole_pairs = kPolePairs;
    dc.encoder_offset_rad = 0.0f;  // unknown after a power-up
    dc.speed_pll_bw_rad_s = 1000.0f;
    dc.slow_loop_div = 20u;
    dc.i_max_a = 10.0f;
    dc.i_trip_a = 15.0f;
    dc.vbus_min_v = 10.0f;
    dc.vbus_max_v = 60.0f;
    // the encoder-step check on: the count's jump at the index is no
    // fault (the drive restarts its tracking there, INDEX)
    dc.omega_max_rad_s = 300.0f;
    dc.angle_ref = angle_ref;
    EXPECT_EQ(mc_drive_init(&d, &dc, board->hal()), MC_DRIVE_CFG_OK);
  }
  void step() { (void)hal_host::sil_period(*board, d); }
  // The sensored use of the angle: CURRENT mode from IDLE, iq 2 A for 20 ms
  // (the current loop settles, 500 Hz); the torque the plant makes.
  double torque_at_iq_2a() {
    EXPECT_EQ(mc_drive_set_mode(&d, MC_DRIVE_MODE_IDLE), 0);
    EXPECT_EQ(mc_drive_set_current_ref(&d, 0.0f, 2.0f), 0);
    EXPECT_EQ(mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT), 0);
    for (int n = 0; n < 400; ++n) {
      step();
    }
    EXPECT_EQ(d.faults, 0u);
    return board->torque_nm();
  }
};

mc_ctrl_align_cfg_t align_cfg(const mc_drive_cfg_t& dc) {
  mc_ctrl_align_cfg_t c{};
  c.foc = dc.foc;
  c.pole_pairs = kPolePairs;
  c.i_max_a = dc.i_max_a;
  c.i_align_a = static_cast<float>(kIAlign);
  c.t_ramp_s = 0.05f;
  c.t_settle_s = 0.1f;
  c.t_timeout_s = 2.0f;
  c.still_band_m_rad = 4.0f * 6.2831853f / 8192.0f;  // 4 counts
  c.sweep_e_rad = static_cast<float>(kPi / 2.0);
  c.omega_sweep_e_rad_s = 20.0f;
  c.sweep_tol_e_rad = 0.3f;
  c.load_tol_e_rad = 0.05f;
  // damping ratio 0.7 on the vector's spring k = kt i p (rad mech.)
  c.damping_a_s_rad = static_cast<float>(2.0 * 0.7 * std::sqrt(kHold * kPolePairs * kJ) / kKt);
  c.travel_max_m_rad = static_cast<float>(1.5 * (kPi + 1.5 * kPi) / kPolePairs);
  return c;
}

mc_ctrl_align_result_t run_align(Sil& s, mc_ctrl_align_t& al, double t_max_s = 10.0) {
  const mc_ctrl_align_cfg_t c = align_cfg(s.dc);
  EXPECT_EQ(mc_ctrl_align_init(&al, &c), MC_CTRL_ALIGN_ERR_NONE);
  EXPECT_EQ(mc_drive_attach_ctrl(&s.d, mc_ctrl_align_ops(&al)), 0);
  EXPECT_EQ(mc_drive_set_mode(&s.d, MC_DRIVE_MODE_CTRL), 0);
  mc_ctrl_align_result_t r{};
  const long n = std::lround(t_max_s * kPwmHz);
  for (long k = 0; k < n && r.status == MC_CTRL_ALIGN_RUNNING; ++k) {
    s.step();
    (void)mc_ctrl_align_get_result(&al, &r);
  }
  return r;
}

}  // namespace

// Eight power-ups at random rotor angles on a drive whose angle is ALIGN
// (an incremental encoder without index): CURRENT is refused until the
// alignment ran (NEED_ALIGN); the offset found is p theta_m0 within 0.02
// rad el. (the count's step, 4 x 2 pi / 8192 = 3.1e-3 rad el., and where
// the rotor comes to rest on the vector within omega_still). Then the
// drive, given that offset, makes torque in the direction and of the size
// its q current asks for, at every power-up (a check of the offset's use,
// not only its value: kt iq, 2 %, cos of the offset error > 0.999 and the
// plant's cogging-free torque).
TEST(AlignSil, OffsetAtRandomPowerUpAngles) {
  std::mt19937_64 rng(20260531u);
  std::uniform_real_distribution<double> angle(0.0, 2.0 * kPi);
  for (int k = 0; k < 8; ++k) {
    const double th0 = angle(rng);
    Sil s(th0, 0.0, false, 0.0, MC_DRIVE_ANGLE_REF_ALIGN);
    EXPECT_EQ(mc_drive_angle_state(&s.d), MC_DRIVE_ANGLE_NEED_ALIGN);
    EXPECT_EQ(mc_drive_set_mode(&s.d, MC_DRIVE_MODE_CURRENT), -EACCES);
    mc_ctrl_align_t al{};
    const mc_ctrl_align_result_t r = run_align(s, al);
    ASSERT_EQ(r.status, MC_CTRL_ALIGN_DONE) << k << " fail " << r.fail;
    const double err = wrap_pi(r.offset_e_rad - wrap_2pi(kPolePairs * th0));
    EXPECT_LE(std::fabs(err), 0.02) << k << " theta_m0 " << th0;
    EXPECT_EQ(s.d.faults, 0u);
    // bounded motion: the snap and the sweeps, within the limit
    EXPECT_LE(r.travel_peak_m_rad, align_cfg(s.dc).travel_max_m_rad);
    ASSERT_EQ(mc_drive_set_mode(&s.d, MC_DRIVE_MODE_IDLE), 0);
    ASSERT_EQ(mc_drive_set_encoder_offset(&s.d, r.offset_e_rad), 0);
    EXPECT_NEAR(s.torque_at_iq_2a(), kKt * 2.0, 0.02 * kKt * 2.0) << k;
  }
}

// A load it can hold but that would bias the offset (0.3 N m, 23 % of the
// 1.32 N m the 2 A vector holds: asin(0.23) = 0.23 rad el. of error):
// refused, MC_CTRL_ALIGN_ERR_LOAD, the drive in FAULT with the bridge off.
// A load above the holding torque: the rotor is dragged off the vector:
// SLIP, named by the plug-in before any protection of the drive trips.
TEST(AlignSil, RefusedUnderALoadItCannotHold) {
  {
    Sil s(1.3, 0.3, false, 0.0);
    mc_ctrl_align_t al{};
    const mc_ctrl_align_result_t r = run_align(s, al);
    ASSERT_EQ(r.status, MC_CTRL_ALIGN_FAILED);
    EXPECT_EQ(r.fail, MC_CTRL_ALIGN_ERR_LOAD);
    EXPECT_GT(std::fabs(r.load_shift_e_rad), 0.05);
    EXPECT_EQ(s.d.mode, MC_DRIVE_MODE_FAULT);
    EXPECT_NE(s.d.faults & MC_DRIVE_FAULT_CONTROL, 0u);
    EXPECT_FALSE(s.board->pwm_enabled());
  }
  {
    Sil s(1.3, 1.5 * kHold, false, 0.0);
    mc_ctrl_align_t al{};
    const mc_ctrl_align_result_t r = run_align(s, al);
    ASSERT_EQ(r.status, MC_CTRL_ALIGN_FAILED);
    EXPECT_EQ(r.fail, MC_CTRL_ALIGN_ERR_SLIP);
    // named before the drive's own protection would trip (the rotor
    // dragged away gathers speed, the back-EMF winds the current up)
    EXPECT_EQ(s.d.first_fault, MC_DRIVE_FAULT_CONTROL);
    EXPECT_FALSE(s.board->pwm_enabled());
  }
}

namespace {

mc_ctrl_idx_cfg_t idx_cfg(const mc_drive_cfg_t& dc, const mc_hal_encoder_t* enc) {
  mc_ctrl_idx_cfg_t c{};
  c.foc = dc.foc;
  c.pole_pairs = kPolePairs;
  c.i_max_a = dc.i_max_a;
  c.i_search_a = static_cast<float>(kIAlign);
  c.t_ramp_s = 0.05f;
  c.omega_search_e_rad_s = 40.0f;  // 10 rad/s mechanical
  c.damping_a_s_rad = static_cast<float>(2.0 * 0.7 * std::sqrt(kHold * kPolePairs * kJ) / kKt);
  c.travel_max_m_rad = static_cast<float>(1.1 * 2.0 * kPi);
  c.first_direction = 1;
  c.p_enc = enc;
  return c;
}

}  // namespace

// The index search from random power-up angles: found within one turn
// going forward; from then on the encoder's count is referenced to the
// mark (the plant's index is at 1.0 rad): count = floor((theta - 1.0)
// cpr / 2 pi) mod cpr, within one count.
TEST(AlignSil, IndexSearchFindsTheMark) {
  std::mt19937_64 rng(77u);
  std::uniform_real_distribution<double> angle(0.0, 2.0 * kPi);
  for (int k = 0; k < 4; ++k) {
    const double th0 = angle(rng);
    Sil s(th0, 0.0, true, 1.0, MC_DRIVE_ANGLE_REF_INDEX);
    // the offset stored relative to the index: the d axis at the mark
    s.d.cfg.encoder_offset_rad = static_cast<float>(wrap_2pi(kPolePairs * 1.0));
    EXPECT_EQ(mc_drive_angle_state(&s.d), MC_DRIVE_ANGLE_NEED_INDEX);
    EXPECT_EQ(mc_drive_set_mode(&s.d, MC_DRIVE_MODE_CURRENT), -EACCES);
    mc_ctrl_idx_t ix{};
    const mc_ctrl_idx_cfg_t c = idx_cfg(s.dc, s.board->hal()->encoder);
    ASSERT_EQ(mc_ctrl_idx_init(&ix, &c), MC_CTRL_ALIGN_ERR_NONE);
    ASSERT_EQ(mc_drive_attach_ctrl(&s.d, mc_ctrl_idx_ops(&ix)), 0);
    ASSERT_EQ(mc_drive_set_mode(&s.d, MC_DRIVE_MODE_CTRL), 0);
    mc_ctrl_idx_result_t r{};
    for (long n = 0; n < 400000 && r.status == MC_CTRL_ALIGN_RUNNING; ++n) {
      s.step();
      (void)mc_ctrl_idx_get_result(&ix, &r);
    }
    ASSERT_EQ(r.status, MC_CTRL_ALIGN_DONE) << k << " fail " << r.fail;
    EXPECT_EQ(r.direction, 1);
    EXPECT_LE(r.travel_peak_m_rad, 2.0 * kPi + kPi / kPolePairs);  // a turn and the snap
    mc_hal_encoder_sample_t smp{};
    ASSERT_EQ(mc_hal_encoder_read(s.board->hal()->encoder, &smp), 0);
    EXPECT_NE(smp.flags & MC_HAL_ENCODER_FLAG_INDEX, 0u);
    const double th = s.board->state()(3);
    const double want = wrap_2pi(th - 1.0) * 8192.0 / (2.0 * kPi);
    double dc = static_cast<double>(smp.count) - want;
    dc -= 8192.0 * std::round(dc / 8192.0);
    EXPECT_LE(std::fabs(dc), 1.0) << k;
    // the stored offset now holds: sensored torque as the q current asks
    // (the tolerance of OffsetAtRandomPowerUpAngles)
    EXPECT_EQ(mc_drive_angle_state(&s.d), MC_DRIVE_ANGLE_KNOWN);
    EXPECT_NEAR(s.torque_at_iq_2a(), kKt * 2.0, 0.02 * kKt * 2.0) << k;
  }
}

// An encoder without an index: the search turns travel_max each way and
// fails by name, the bridge off; the rotor never went further than the
// bound and the rotor's coasting past it.
TEST(AlignSil, IndexSearchWithoutAMarkFailsBounded) {
  Sil s(0.4, 0.0, false, 0.0);
  mc_ctrl_idx_t ix{};
  const mc_ctrl_idx_cfg_t c = idx_cfg(s.dc, s.board->hal()->encoder);
  ASSERT_EQ(mc_ctrl_idx_init(&ix, &c), MC_CTRL_ALIGN_ERR_NONE);
  ASSERT_EQ(mc_drive_attach_ctrl(&s.d, mc_ctrl_idx_ops(&ix)), 0);
  ASSERT_EQ(mc_drive_set_mode(&s.d, MC_DRIVE_MODE_CTRL), 0);
  mc_ctrl_idx_result_t r{};
  for (long n = 0; n < 600000 && r.status == MC_CTRL_ALIGN_RUNNING; ++n) {
    s.step();
    (void)mc_ctrl_idx_get_result(&ix, &r);
  }
  ASSERT_EQ(r.status, MC_CTRL_ALIGN_FAILED);
  EXPECT_EQ(r.fail, MC_CTRL_ALIGN_ERR_NOT_FOUND);
  // coasting past the limit at 10 rad/s with the damped spring: < 0.05 rad
  EXPECT_LE(r.travel_peak_m_rad, c.travel_max_m_rad + 0.05);
  EXPECT_FALSE(s.board->pwm_enabled());
  EXPECT_NE(s.d.faults & MC_DRIVE_FAULT_CONTROL, 0u);
}
