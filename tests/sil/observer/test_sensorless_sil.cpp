// Sensorless FOC (paper 002) through the firmware path: the drive in CTRL
// mode with the sensorless plug-in (firmware/app/mc_ctrl_sensorless) on the
// simulated board (hal_host::PmsmBoard, an independent plant model), test
// motor of Table I, 8 kHz current loop, 1.25 ms speed loop.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "scenarios/observer_sil.hpp"
extern "C" {
#include "observer/mc_iiobs.h"
}

namespace {

using mcsim::observer::LoadSteps;
using mcsim::observer::Sil;
using mcsim::observer::SilOptions;

constexpr double kPi = 3.14159265358979323846;
constexpr double kRpm = 2 * kPi / 60.0;

// Runs the drive at a speed reference; fn(sil) after each period.
template <class Ref, class Fn>
void run(Sil& sil, double t_end, Ref ref, Fn fn) {
  const long n = std::lround(t_end / sil.board().period_s());
  for (long k = 0; k < n; ++k) {
    ASSERT_EQ(mc_ctrl_sls_set_speed_ref(&sil.ctrl(), static_cast<float>(ref(sil.t_s()))), 0u);
    sil.step();
    ASSERT_EQ(sil.drive().faults, 0u) << "t = " << sil.t_s();
    fn(sil);
  }
}

// The acceptance test: from standstill (I-f start) to 200 r/min,
// then a full-load (3 N m) step at 1 s.
TEST(SensorlessSil, HoldsTestMotorAt200RpmThroughFullLoadStep) {
  const auto m = mcsim::observer::test_motor_300w();
  SilOptions o;
  LoadSteps load{{{1.0, m.rated_torque_nm}}};
  Sil sil(m, o, mcsim::observer::default_ctrl_cfg(m, o), load);
  const double w0 = 200 * kRpm;
  double err_max_load = 0, err_final = 0, ang_max = 0;
  run(
      sil, 1.8, [&](double) { return w0; },
      [&](Sil& s) {
        const double t = s.t_s(), w = s.board().state()(2);
        if (t > 1.0) err_max_load = std::max(err_max_load, std::abs(w - w0));
        if (t > 1.6) err_final = std::max(err_final, std::abs(w - w0));
        if (t > 0.6) ang_max = std::max(ang_max, std::abs(s.angle_error()));
      });
  std::printf(
      "200 r/min full-load step: max speed error %.2f r/min, after 0.6 s %.3f r/min, "
      "max angle error %.2e rad\n",
      err_max_load / kRpm, err_final / kRpm, ang_max);
  EXPECT_EQ(sil.ctrl().tm.phase, MC_CTRL_SLS_CLOSED);
  // Dip: a 3 N m step on J = 5e-3 kg m^2 with a 100 rad/s speed loop;
  // measured 47 r/min (23 %), bound 60 r/min.
  EXPECT_LT(err_max_load / kRpm, 60.0);
  // 0.6 s after the step the integral action has removed it: measured
  // 0.04 r/min (current quantisation), bound 0.5 r/min.
  EXPECT_LT(err_final / kRpm, 0.5);
  // Exact model: the observer error is only current quantisation; measured
  // 3.7e-4 rad.
  EXPECT_LT(ang_max, 5e-3);
}

// Light load with the paper's 2 us dead time, known exactly: compensated
// in the observer's voltage only, the phase currents near zero leave the
// current loop with the whole dead-time error and the speed oscillates;
// compensated in the duties (dead_comp_duty), it holds. Unloaded, 200 r/min,
// speed standard deviation and largest angle error over 0.8-1.3 s.
struct LightLoad {
  double speed_std_rpm = 0, ang_max = 0;
};

LightLoad light_load(bool duty) {
  const auto m = mcsim::observer::test_motor_300w();
  SilOptions o;
  o.dead_time_s = 2e-6;
  o.dead_comp_frac = 1.0;
  o.dead_comp_duty = duty;
  Sil sil(m, o, mcsim::observer::default_ctrl_cfg(m, o), LoadSteps{});
  double sum = 0, sum2 = 0;
  long n = 0;
  LightLoad r;
  run(
      sil, 1.3, [&](double) { return 200 * kRpm; },
      [&](Sil& s) {
        if (s.t_s() > 0.8) {
          const double w = s.board().state()(2) / kRpm;
          sum += w;
          sum2 += w * w;
          ++n;
          r.ang_max = std::max(r.ang_max, std::abs(s.angle_error()));
        }
      });
  const double mean = sum / static_cast<double>(n);
  r.speed_std_rpm = std::sqrt(std::max(0.0, sum2 / static_cast<double>(n) - mean * mean));
  return r;
}

TEST(SensorlessSil, LightLoadWithDeadTimeHoldsWithDutyCompensation) {
  const LightLoad obs_only = light_load(false);
  const LightLoad duty = light_load(true);
  std::printf(
      "unloaded 200 r/min, 2 us dead time: speed std %.2f r/min (observer only) vs "
      "%.2f (duties), angle error max %.3f vs %.4f rad\n",
      obs_only.speed_std_rpm, duty.speed_std_rpm, obs_only.ang_max, duty.ang_max);
  // With the duty correction: measured 4.3 r/min and 8 mrad; bounds 8 r/min
  // and 0.03 rad (the loop without dead time holds 0.02 r/min, so the bound
  // is about the oscillation, not the quantisation).
  EXPECT_LT(duty.speed_std_rpm, 8.0);
  EXPECT_LT(duty.ang_max, 0.03);
  // The reference without it: measured 25 r/min and 0.23 rad. Asserted so
  // that this test shows what the correction is for; at least 12 r/min.
  EXPECT_GT(obs_only.speed_std_rpm, 12.0);
}

// Duty-side correction (cfg.dead_comp_duty): the drive's current loop adds
// sat(i / band) dead_time / dt to each leg's duty (mc_drive_cfg_t
// .dead_time_comp, tested in tests/unit/app DeadTime*), and the law's
// observer takes the commanded voltage as applied; without it the observer
// subtracts its estimate of the dead-time error.
TEST(SensorlessSil, DutyCompensationLeavesTheObserverTheCommandedVoltage) {
  const auto m = mcsim::observer::test_motor_300w();
  SilOptions o;
  o.dead_time_s = 2e-6;
  mc_ctrl_sls_cfg_t cfg = mcsim::observer::default_ctrl_cfg(m, o);
  mc_ctrl_sls_t off{};
  mc_ctrl_sls_t on{};
  ASSERT_EQ(mc_ctrl_sls_init(&off, &cfg), 0u);
  cfg.dead_comp_duty = true;
  ASSERT_EQ(mc_ctrl_sls_init(&on, &cfg), 0u);
  mc_drive_meas_t meas{};
  meas.ia_a = 1.0f;
  meas.ib_a = -0.5f * cfg.dead_band_a;  // inside the linear band
  meas.ic_a = -(meas.ia_a + meas.ib_a);
  meas.vbus_v = static_cast<float>(m.vbus_v);
  meas.dt_s = cfg.dt_s;
  meas.i_max_a = 100.0f;
  meas.regen_scale = 1.0f;
  mc_drive_out_t a{};
  mc_drive_out_t b{};
  ASSERT_EQ(mc_ctrl_sls_fast(&off, &meas, &a), 0u);
  ASSERT_EQ(mc_ctrl_sls_fast(&on, &meas, &b), 0u);
  const float kd = cfg.dead_time_s / cfg.dt_s;
  ASSERT_GT(kd, 0.0f);
  // the same current references either way: the correction is the drive's
  EXPECT_EQ(a.id_ref_a, b.id_ref_a);
  EXPECT_EQ(a.iq_ref_a, b.iq_ref_a);
  // Before the first command the commanded voltage is zero: with the duty
  // correction the observer takes it as applied; without, it subtracts the
  // estimated dead-time error, from the mean of this sample and the
  // previous one (zero after init): legs at sat(0.5 / band) = 1,
  // sat(-0.25) = -0.25 and -1, so alpha = (2/3) kd vbus (1 + 1.25 / 2)
  // (1e-4 V: float rounding of a 3.5 V value).
  EXPECT_EQ(on.tm.v_alpha_obs_v, 0.0f);
  EXPECT_EQ(on.tm.v_beta_obs_v, 0.0f);
  EXPECT_NEAR(off.tm.v_alpha_obs_v, -(2.0 / 3.0) * kd * meas.vbus_v * 1.625, 1e-4);
}

// Hand-over I-f -> closed loop: no torque jerk. The largest torque change
// over one PWM period within 3 periods of the switch, against the same in
// the I-f phase before it.
TEST(SensorlessSil, HandoverHasNoTorqueJerk) {
  const auto m = mcsim::observer::test_motor_300w();
  SilOptions o;
  Sil sil(m, o, mcsim::observer::default_ctrl_cfg(m, o), LoadSteps{{{0.0, 0.9}}});
  const double T = sil.board().period_s();
  std::vector<double> t, tau;
  long k_switch = -1;
  run(
      sil, 0.4, [](double) { return 300 * kRpm; },
      [&](Sil& s) {
        t.push_back(s.t_s());
        tau.push_back(s.board().torque_nm());
        if (k_switch < 0 && s.ctrl().tm.handovers == 1) k_switch = static_cast<long>(t.size()) - 1;
      });
  ASSERT_GT(k_switch, 0);
  const auto ks = static_cast<size_t>(k_switch);
  double jump = 0, before = 0;
  for (size_t k = ks - 3; k <= ks + 3; ++k) jump = std::max(jump, std::abs(tau[k] - tau[k - 1]));
  for (size_t k = ks - static_cast<size_t>(0.02 / T); k < ks - 3; ++k)
    before = std::max(before, std::abs(tau[k] - tau[k - 1]));
  std::printf("hand-over at %.4f s: torque step per period %.2e N m (I-f before: %.2e N m)\n",
              t[ks], jump, before);
  // The switch changes the torque by less than 1 % of rated torque per
  // period (measured 1.3e-3 N m, 0.04 %; the I-f ramp before it 1.1e-4 N m,
  // the speed loop then takes 5 ms to add 0.33 N m): the torque is
  // continuous.
  EXPECT_LT(jump, 0.01 * m.rated_torque_nm);
  EXPECT_LT(jump, 10 * before + 1e-3);
  EXPECT_EQ(sil.ctrl().tm.phase, MC_CTRL_SLS_CLOSED);
}

// Start-stop with 30 % load: closed loop at 300 r/min, then stop: back to
// I-f at low speed and hold the load at standstill (damped).
TEST(SensorlessSil, StopsAndHoldsLoadAtStandstill) {
  const auto m = mcsim::observer::test_motor_300w();
  SilOptions o;
  Sil sil(m, o, mcsim::observer::default_ctrl_cfg(m, o), LoadSteps{{{0.0, 0.9}}});
  double wmax_end = 0;
  run(
      sil, 2.0, [](double t) { return t < 0.8 ? 300 * kRpm : 0.0; },
      [&](Sil& s) {
        if (s.t_s() > 1.7) wmax_end = std::max(wmax_end, std::abs(s.board().state()(2)));
      });
  std::printf("start-stop: hand-overs %u, fallbacks %u, |omega| after 1.7 s <= %.2e rad/s\n",
              sil.ctrl().tm.handovers, sil.ctrl().tm.fallbacks, wmax_end);
  EXPECT_EQ(sil.ctrl().tm.handovers, 1u);
  EXPECT_EQ(sil.ctrl().tm.fallbacks, 1u);
  EXPECT_EQ(sil.ctrl().tm.phase, MC_CTRL_SLS_IF);
  // Holding 0.9 N m at standstill with the damped I-f: settled within
  // 0.6 s of the stop (measured < 1e-3 rad/s), bound 0.05 rad/s.
  EXPECT_LT(wmax_end, 0.05);
}

// Reduced low-speed sweep with the realistic errors of the sweep scenario
// (2 us dead time, 80 % compensated; 0.02 A noise; R 10 % high; half
// load): 100 r/min holds, 20 r/min does not (the paper: trouble below
// about 50 r/min).
double low_speed_mean_rpm(double rpm, double* ang_max) {
  const auto m = mcsim::observer::test_motor_300w();
  SilOptions o;
  o.dead_time_s = 2e-6;
  o.dead_comp_frac = 0.8;
  o.noise_rms_a = 0.02;
  o.r_error = 0.1;
  o.lowspeed_fallback = false;
  Sil sil(m, o, mcsim::observer::default_ctrl_cfg(m, o), LoadSteps{{{0.6, 1.5}}});
  double sum = 0;
  long n = 0;
  *ang_max = 0;
  const long steps = std::lround(2.2 / sil.board().period_s());
  for (long k = 0; k < steps; ++k) {
    const double t = sil.t_s();
    const double r = t < 0.8 ? 200.0 : (t < 1.3 ? 200.0 + (rpm - 200.0) * (t - 0.8) / 0.5 : rpm);
    mc_ctrl_sls_set_speed_ref(&sil.ctrl(), static_cast<float>(r * kRpm));
    sil.step();
    if (sil.drive().faults) return std::nan("");
    if (sil.t_s() > 1.7) {
      sum += sil.board().state()(2);
      ++n;
      *ang_max = std::max(*ang_max, std::abs(sil.angle_error()));
    }
  }
  return sum / static_cast<double>(n) / kRpm;
}

TEST(SensorlessSil, LowSpeedLimitWithRealisticErrors) {
  double a100 = 0, a20 = 0;
  const double w100 = low_speed_mean_rpm(100.0, &a100);
  const double w20 = low_speed_mean_rpm(20.0, &a20);
  std::printf(
      "100 r/min: mean %.1f r/min, max angle error %.3f rad; 20 r/min: mean %.1f r/min, "
      "max angle error %.3f rad\n",
      w100, a100, w20, a20);
  // 100 r/min: holds within 3 r/min with < 0.2 rad error (measured 0.13)
  EXPECT_NEAR(w100, 100.0, 3.0);
  EXPECT_LT(a100, 0.2);
  // 20 r/min: lost (angle error beyond 0.35 rad, or the speed not held,
  // or a fault): the model errors dominate the few volts of back-EMF.
  EXPECT_TRUE(std::isnan(w20) || std::abs(w20 - 20.0) > 3.0 || a20 > 0.35);
}

// I&I observer (paper 002, Sec. IV) on the drive's quantised encoder angle
// (2048 counts) and the torque from the measured currents: converges to the
// true load after a full-load step.
TEST(SensorlessSil, IiObserverEstimatesLoadFromEncoder) {
  const auto m = mcsim::observer::test_motor_300w();
  SilOptions o;
  o.encoder_cpr = 2048;
  Sil sil(m, o, mcsim::observer::default_ctrl_cfg(m, o), LoadSteps{{{0.8, 3.0}}});
  mc_iiobs_f32_cfg_t ic{};
  ic.j_kgm2 = static_cast<float>(m.motor.J_kgm2);
  ic.f_nms_rad = static_cast<float>(m.motor.B_nms_rad);
  ic.a1 = 6.0f;
  ic.a2 = 8.5f;
  ic.k4 = 1.0f;
  ic.t_unit_s = 2.2929f / 60.0f;  // k1 / t_unit = 60 rad/s
  ic.dt_s = static_cast<float>(sil.board().period_s());
  ic.r_max = 1000.0f;
  mc_iiobs_f32_t ii{};
  ASSERT_EQ(mc_iiobs_f32_init(&ii, &ic), 0u);
  const double kt = 1.5 * m.motor.pole_pairs * m.motor.flux_wb;
  double tau_prev = 0, sum_l = 0, sum_w = 0;
  long n = 0;
  run(
      sil, 1.5, [](double) { return 400 * kRpm; },
      [&](Sil& s) {
        const auto& tm = s.drive().tm;
        const double c = std::cos(tm.theta_e_rad), sn = std::sin(tm.theta_e_rad);
        const double al = tm.ia_a, be = (tm.ia_a + 2.0 * tm.ib_a) / std::sqrt(3.0);
        const double tau = kt * (-sn * al + c * be);
        mc_iiobs_f32_step(&ii, tm.theta_m_rad, static_cast<float>(0.5 * (tau + tau_prev)));
        tau_prev = tau;
        if (s.t_s() > 1.2) {
          sum_l += mc_iiobs_f32_get_tau_load_nm(&ii) - 3.0;
          sum_w += mc_iiobs_f32_get_omega_m_rad_s(&ii) - s.board().state()(2);
          ++n;
        }
      });
  const double el = sum_l / static_cast<double>(n), ew = sum_w / static_cast<double>(n);
  std::printf("I&I after the load step: mean load error %.2e N m, mean speed error %.2e rad/s\n",
              el, ew);
  // Mean over 0.3 s, 0.4 s after the step (24 time constants of k1):
  // measured 1e-4 N m and 1e-3 rad/s; bounds 1 % of the load and 0.05 rad/s
  // (the encoder's 3 mrad quantisation, differentiated by the injection).
  EXPECT_LT(std::abs(el), 0.03);
  EXPECT_LT(std::abs(ew), 0.05);
  EXPECT_EQ(ii.flags, 0u);
}

}  // namespace
