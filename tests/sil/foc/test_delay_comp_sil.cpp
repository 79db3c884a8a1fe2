// The current loop's computation-delay compensation (kernels/foc README,
// "Computation-delay compensation") on the high-pole-count motor of the
// library, the U8-class 21-pole-pair outrunner (sim/motors/u8-class-kv100.toml)
// on the 56 V ODrive v3.6 board: the rotor held at a speed by a flywheel,
// the drive in current mode, a q then a d current step. The drive is the
// image's: configured from the files' parameter table by the firmware's
// builder (params_from_files -> mc_params_to_drive_cfg, sim/cli/
// app_params.hpp), stepped with hal_host::sil_period. With the
// compensation the loop holds up to omega_e T = 0.6 rad and its rise time
// stays the design's; the same run with the compensation switched off
// (mc_foc_f32_set_delay_comp 0 on the test's own drive after its init, a
// direct kernel call: the sampled angle for the inverse Park, as before)
// loses control, which is what the test is for.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>

#include "app_params.hpp"
#include "dyno_rig.hpp"
#include "hal_host/sil_rig.hpp"
#include "motor_file.hpp"
#include "plant_from_files.hpp"
#include "rise_timer.hpp"

extern "C" {
#include "foc/mc_foc.h"
#include "mc_drive.h"
#include "mc_params.h"
}

namespace {

struct Result {
  uint32_t faults = 0;
  double iq_ratio = std::nan(""), id_ratio = std::nan("");  // rise / (ln 9 / bw)
  double omega_end_m_rad_s = 0, omega_target_m_rad_s = 0;
  double dev_max_a = 0;  // largest |i - i_ref| once each step has risen (3 design rise times on)
};

// omega_e T of the run; pwm_hz overrides the board's PWM rate (the 54 V bus
// reaches omega_e T = 0.6 at 16 kHz: 457 rad/s, 25 V of back-EMF).
Result run(double we_t, double pwm_hz, bool compensate) {
  mcsim::MotorFiles f =
      mcsim::load_motor_files(std::string(MCSIM_MOTORS_DIR) + "/u8-class-kv100.toml",
                              std::string(MCSIM_MOTORS_DIR) + "/odrive-v36-56v.toml");
  f.board.pwm_hz = pwm_hz;
  // the bus below the 56 V version's rating, its limit and the drive's trip
  // there (vbus_board_max_v; its description's nominal supply is 48 V; its
  // divider reads up to 62.7 V)
  f.board.vbus_v = 54.0;
  const double T = 1.0 / pwm_hz;
  const double w_m = we_t / (T * f.motor.pole_pairs);
  // A flywheel of 100 rotor inertias (a dyno), brought to speed by the dyno's
  // torque over t_ramp while the drive holds zero current (the loop crosses
  // every omega_e T below the target on the way), then left to coast: the
  // current steps move its speed by < 0.1 %.
  // The drive knows the motor's own inertia (its gains, among them the
  // encoder tracking loop's resolution bound, mc_gains.h); the dyno is the
  // plant's.
  mcsim::MotorFiles drive_f = f;
  f.motor.j_kgm2 *= 100.0;
  const double t_ramp = 0.04;
  const double tau_dyno = -f.motor.j_kgm2 * w_m / t_ramp;  // negative load: driving
  // The drive from the files' table (every gain derived, CURRENT mode),
  // the dead-time compensation off (parameter dead_time_comp = 0): the test
  // isolates the computation delay; with the table's default (on) the
  // dead-time voltage no longer slows the steps and the d step at 0.45 rad
  // rises in 0.72 of the design's time (0.79 with it off), the delay's lead
  // alone (the criterion below is the library's, for the loop as designed).
  mc_params_t p =
      mcsim::params_from_files(drive_f, mcsim::Params(mcsim::app_gain_params(drive_f), {}));
  p.dead_time_comp = 0u;
  const mc_gains_t g = mcsim::resolve_params(p).g;
  const std::function<double(double)> load = [t_ramp, tau_dyno](double t) {
    return t < t_ramp ? tau_dyno : 0.0;
  };
  mcsim::DynoRig rig(f, p, &load);
  hal_host::PmsmBoard& board = rig.board;
  mc_drive_t& d = rig.d;
  if (!compensate) {
    EXPECT_EQ(mc_foc_f32_set_delay_comp(&d.foc, 0.0f), MC_FOC_ERR_NONE);
  }
  const double design = std::log(9.0) / g.cur_bw_rad_s;
  const double i_step = 0.5 * g.i_rated_eff_a;
  // 10 ms at speed before the first step (the encoder's tracking loop settles)
  const double t_iq = t_ramp + 0.01, t_id = t_iq + 12 * design + 2e-3,
               t_end = t_id + 12 * design + 2e-3;
  mcsim::RiseTimer rq(t_iq, 0.0, i_step), rd(t_id, 0.0, 0.5 * i_step);
  Result r;
  for (long k = 0; board.t_s() < t_end; ++k) {
    const double t = board.t_s();
    const double idr = t >= t_id ? -0.5 * i_step : 0.0, iqr = t >= t_iq ? i_step : 0.0;
    EXPECT_EQ(mc_drive_set_current_ref(&d, static_cast<float>(idr), static_cast<float>(iqr)), 0);
    double id = 0, iq = 0;
    board.true_dq_a(&id, &iq);
    rq.add(t, iq);
    rd.add(t, -id);  // the d step is negative: time it on -i_d rising to +i_step/2
    if ((t >= t_iq + 3 * design && t < t_id) || t >= t_id + 3 * design) {
      r.dev_max_a = std::max(r.dev_max_a, std::max(std::abs(id - idr), std::abs(iq - iqr)));
    }
    if (d.faults != 0u) break;
    hal_host::sil_period(board, d);
  }
  r.faults = d.faults;
  r.omega_end_m_rad_s = board.state()(2);
  r.omega_target_m_rad_s = w_m;
  r.iq_ratio = rq.rise_s() / design;
  r.id_ratio = rd.rise_s() / design;
  return r;
}

// The design's rise ln 9 / bw within 25 % (the library's criterion,
// tests/sil/motors: the delay alone moves it by up to ~20 % at the derived
// bw T = 0.12; measured 0.78 ... 1.17 here); the current within 10 % of the
// step once risen (measured up to 8.7 %: the PWM ripple at 16 kHz and the
// decoupling's remaining error at speed ring for a few periods after each
// step).
void expect_controlled(const Result& r, double i_step) {
  EXPECT_EQ(r.faults, 0u);
  // the run was at the omega_e T it claims (friction and the steps: < 1 %)
  EXPECT_NEAR(r.omega_end_m_rad_s, r.omega_target_m_rad_s, 0.01 * r.omega_target_m_rad_s);
  EXPECT_NEAR(r.iq_ratio, 1.0, 0.25);
  EXPECT_NEAR(r.id_ratio, 1.0, 0.25);
  EXPECT_LE(r.dev_max_a, 0.1 * i_step);
}

}  // namespace

class DelayCompSil : public ::testing::TestWithParam<double> {};

// omega_e T from where the uncompensated loop tripped (0.3) to 0.6 rad (ten
// samples per electrical period), 16 kHz.
TEST_P(DelayCompSil, CurrentLoopHoldsAndMeetsItsRiseTime) {
  const mcsim::MotorFiles f =
      mcsim::load_motor_files(std::string(MCSIM_MOTORS_DIR) + "/u8-class-kv100.toml",
                              std::string(MCSIM_MOTORS_DIR) + "/odrive-v36-56v.toml");
  const double i_step = 0.5 * mcsim::files_params_eff(f).g.i_rated_eff_a;
  const Result r = run(GetParam(), 16000.0, true);
  expect_controlled(r, i_step);
  RecordProperty("iq_rise_ratio", std::to_string(r.iq_ratio));
  RecordProperty("id_rise_ratio", std::to_string(r.id_ratio));
  RecordProperty("dev_max_a", std::to_string(r.dev_max_a));
}

INSTANTIATE_TEST_SUITE_P(OmegaT, DelayCompSil, ::testing::Values(0.3, 0.45, 0.6));

// The control arm: the same run at 0.3 rad with the compensation off (the
// sampled angle for the inverse Park and the measured currents in the
// decoupling, the kernel as it was) trips OVERCURRENT (measured: the
// currents diverge during the run-up; at 0.2 rad it still runs, with a rise
// ratio of 0.53), so the test above tells the two apart.
TEST(DelayCompSilOff, UncompensatedLoopLosesControlAtPointThree) {
  const Result r = run(0.3, 16000.0, false);
  const bool lost = (r.faults != 0u) || !(std::abs(r.iq_ratio - 1.0) <= 0.25) ||
                    !(std::abs(r.id_ratio - 1.0) <= 0.25) || !(r.dev_max_a <= 1.0);
  RecordProperty("faults", std::to_string(r.faults));
  EXPECT_TRUE(lost) << "faults " << r.faults << ", rise ratios " << r.iq_ratio << " / "
                    << r.id_ratio << ", deviation " << r.dev_max_a << " A";
}
