// observer-test-motor with the q31 sensorless plug-in
// (firmware/app/mc_ctrl_sensorless_q31) against the f32 one
// (mc_ctrl_sensorless), both through the drive on the same simulated board
// (test motor of paper 002, 8 kHz, 12-bit currents over +-20 A, one-period
// delay): the trajectories of speed, observer angle error and currents stay
// within the bounds below, and the q31 run meets the f32 run's acceptance
// criteria (tests/sil/observer). Plus the plug-in's own contract: invalid
// config and bases rejected with a specific error, NaN -> fault.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <vector>

#include "mc_record.hpp"
#include "scenarios/observer_sil.hpp"

namespace {

using mcsim::observer::LoadSteps;
using mcsim::observer::Sil;
using mcsim::observer::SilOptions;

constexpr double kPi = 3.14159265358979323846;
constexpr double kRpm = 2 * kPi / 60.0;

void report(const char* what, double v, double bound, const char* unit) {
  std::printf("[ measured ] %-52s %.4g %s (bound %.4g)\n", what, v, unit, bound);
  mc_record(what, v, bound, unit);  // for the documents (tools/docs); bound 0: none
}

struct Trace {
  std::vector<double> t, w, ang, id, iq, tau;
  std::vector<int> phase;
  uint32_t handovers = 0, fallbacks = 0, faults = 0;
  long k_handover = -1;
};

Trace run(bool q31, double t_end, const std::function<double(double)>& ref, LoadSteps load) {
  const auto m = mcsim::observer::test_motor_300w();
  SilOptions o;
  o.q31 = q31;
  Sil sil(m, o, mcsim::observer::default_ctrl_cfg(m, o), std::move(load));
  Trace r;
  const long n = std::lround(t_end / sil.board().period_s());
  for (long k = 0; k < n; ++k) {
    EXPECT_EQ(sil.set_speed_ref(static_cast<float>(ref(sil.t_s()))), 0u);
    sil.step();
    double id = 0, iq = 0;
    sil.board().true_dq_a(&id, &iq);
    r.t.push_back(sil.t_s());
    r.w.push_back(sil.board().state()(2));
    r.ang.push_back(sil.angle_error());
    r.id.push_back(id);
    r.iq.push_back(iq);
    r.tau.push_back(sil.board().torque_nm());
    r.phase.push_back(static_cast<int>(sil.tm().phase));
    if (r.k_handover < 0 && sil.tm().handovers == 1) r.k_handover = k;
    if (sil.drive().faults != 0u) {
      r.faults = sil.drive().faults;
      break;
    }
  }
  r.handovers = sil.tm().handovers;
  r.fallbacks = sil.tm().fallbacks;
  return r;
}

double max_diff(const std::vector<double>& a, const std::vector<double>& b, const Trace& tr,
                double t0, double t1) {
  double d = 0;
  for (size_t k = 0; k < std::min(a.size(), b.size()); ++k) {
    if (tr.t[k] >= t0 && tr.t[k] < t1) d = std::max(d, std::abs(a[k] - b[k]));
  }
  return d;
}

double max_abs(const std::vector<double>& a, const Trace& tr, double t0, double t1) {
  double d = 0;
  for (size_t k = 0; k < a.size(); ++k) {
    if (tr.t[k] >= t0 && tr.t[k] < t1) d = std::max(d, std::abs(a[k]));
  }
  return d;
}

// Profile 0 of observer-test-motor (the acceptance run): I-f start,
// hand-over, 200 r/min, full-load (3 N m) step at 1 s held 1 s, 2.5 s.
//
// Where the two runs differ, and the bounds:
// - Timing: the q31 plug-in counts the 400 ALIGN steps exactly, the f32 one
//   sums dt = 125 us in float and reaches 0.05 s one step later: the whole
//   start-up (I-f ramp, hand-over) runs one PWM period earlier in q31. At
//   most one period apart (asserted); the rotor accelerates at most at
//   3 N m / 5e-3 kg m^2 = 600 rad/s^2, so one period is worth 0.075 rad/s:
//   bound 0.15 rad/s on the whole run.
// - Arithmetic: per step the q31 observer angle is within 1.3e-6 rad of the
//   f32 one (tests/unit/q31); the loops then see different ADC codes now
//   and then (one LSB = 40 A / 4096 = 9.8 mA). One current LSB moves the
//   observer's flux e = x - L i by L LSB = 1.1e-5 Wb, 1.0e-4 rad on
//   0.11 Wb: angle error difference bound 2e-3 rad (20 such LSB; the
//   acceptance bound on the angle error itself is 5e-3 rad). Currents in
//   closed loop: i_d within 0.05 A (5 LSB), i_q within 0.15 A (15 LSB, 2 %
//   of the 6.8 A torque limit; the speed PI turns a speed difference dw
//   into kp dw = 0.76 A/(rad/s) dw of i_q); speed within 0.1 rad/s in closed
//   loop (2 % of the 4.9 rad/s load-step dip).
TEST(Q31Sensorless, TestMotorLoadStepTracksTheF32Loop) {
  const double w0 = 200 * kRpm;
  auto ref = [w0](double) { return w0; };
  const LoadSteps load{{{1.0, 3.0}, {2.0, 0.0}}};
  const Trace a = run(false, 2.5, ref, load);
  const Trace q = run(true, 2.5, ref, load);
  ASSERT_EQ(a.faults, 0u);
  ASSERT_EQ(q.faults, 0u);
  ASSERT_EQ(a.t.size(), q.t.size());
  ASSERT_GT(q.k_handover, 0);
  ASSERT_GT(a.k_handover, 0);
  const auto kh = static_cast<size_t>(q.k_handover);
  const double t_ho = q.t[kh];
  std::printf("hand-over: f32 step %ld, q31 step %ld\n", a.k_handover, q.k_handover);
  EXPECT_LE(std::abs(a.k_handover - q.k_handover), 1);

  const double dw = max_diff(a.w, q.w, a, 0.0, 9.0);
  const double dw_closed = max_diff(a.w, q.w, a, t_ho + 0.3, 9.0);
  const double dang = max_diff(a.ang, q.ang, a, t_ho + 0.3, 9.0);
  const double did = max_diff(a.id, q.id, a, t_ho + 0.3, 9.0);
  const double diq = max_diff(a.iq, q.iq, a, t_ho + 0.3, 9.0);
  std::vector<double> ea(a.w.size()), eq(q.w.size());
  for (size_t k = 0; k < ea.size(); ++k) ea[k] = a.w[k] - w0;
  for (size_t k = 0; k < eq.size(); ++k) eq[k] = q.w[k] - w0;
  const double dip_a = max_abs(ea, a, 1.0, 2.0);
  const double dip_q = max_abs(eq, q, 1.0, 2.0);
  const double final_q = max_abs(eq, q, 1.6, 2.0);
  const double ang_q = max_abs(q.ang, q, 0.6, 9.0);
  // hand-over torque step per period within 3 periods of the switch
  double jump = 0;
  for (size_t k = kh - 3; k <= kh + 3; ++k)
    jump = std::max(jump, std::abs(q.tau[k] - q.tau[k - 1]));
  report("|omega f32 - q31|, whole run", dw, 0.15, "rad/s");
  report("|omega f32 - q31|, closed loop", dw_closed, 0.1, "rad/s");
  report("|angle error f32 - q31|, closed loop", dang, 2e-3, "rad");
  report("|i_d f32 - q31|, closed loop", did, 0.05, "A");
  report("|i_q f32 - q31|, closed loop", diq, 0.15, "A");
  report("load-step dip f32", dip_a / kRpm, 60, "r/min");
  report("load-step dip q31", dip_q / kRpm, 60, "r/min");
  report("q31 |speed error| 0.6 s after the step", final_q / kRpm, 0.5, "r/min");
  report("q31 |angle error| after 0.6 s", ang_q, 5e-3, "rad");
  report("q31 hand-over torque step per period", jump, 0.03, "N m");
  EXPECT_LE(dw, 0.15);
  EXPECT_LE(dw_closed, 0.1);
  EXPECT_LE(dang, 2e-3);
  EXPECT_LE(did, 0.05);
  EXPECT_LE(diq, 0.15);
  // the f32 run's acceptance criteria (tests/sil/observer): dip < 60 r/min
  // (measured 47 in f32), < 0.5 r/min 0.6 s after the step, angle error
  // < 5e-3 rad, torque step at the hand-over < 1 % of rated per period
  EXPECT_EQ(q.phase.back(), MC_CTRL_SLS_CLOSED);
  EXPECT_LT(dip_q / kRpm, 60.0);
  EXPECT_LT(final_q / kRpm, 0.5);
  EXPECT_LT(ang_q, 5e-3);
  EXPECT_LT(jump, 0.03);
  // and the metric itself agrees with the f32 run's within 2 % (dip)
  EXPECT_NEAR(dip_q, dip_a, 0.02 * dip_a);
}

// Profile 3 (start-stop with 30 % load): closed loop at 300 r/min, stop at
// 0.8 s: the q31 fallback to I-f (magnitude from |iq|, load angle by
// atan2/isqrt) and holding the load at standstill. Bounds as above, the
// whole run compared (the one-period start-up shift is inside the speed
// bound: the acceleration here is at most 0.5 rated torque / J = 300
// rad/s^2); the fallback instants may differ by a few periods as the
// speed estimates cross the threshold with different rounding (asserted:
// at most 3). At the fallback i_d steps from 0 to I cos(delta) = 2.4 A
// (I = 2.7 A, delta = asin(1.36 / 2.7)) at the current loop's 628 rad/s,
// up to 0.19 A per period: i_d bound 0.3 A; i_q 0.15 A as above.
TEST(Q31Sensorless, StartStopFallsBackAndHoldsLikeTheF32Loop) {
  auto ref = [](double t) { return t < 0.8 ? 300 * kRpm : 0.0; };
  const LoadSteps load{{{0.0, 0.9}}};
  const Trace a = run(false, 2.0, ref, load);
  const Trace q = run(true, 2.0, ref, load);
  ASSERT_EQ(a.faults, 0u);
  ASSERT_EQ(q.faults, 0u);
  ASSERT_EQ(a.t.size(), q.t.size());
  const double dw = max_diff(a.w, q.w, a, 0.0, 9.0);
  const double diq = max_diff(a.iq, q.iq, a, 0.0, 9.0);
  const double did = max_diff(a.id, q.id, a, 0.0, 9.0);
  const double w_end = max_abs(q.w, q, 1.7, 9.0);
  long k_fb_a = -1, k_fb_q = -1;
  for (size_t k = 1; k < a.t.size(); ++k) {
    if (k_fb_a < 0 && a.phase[k] == MC_CTRL_SLS_IF && a.phase[k - 1] == MC_CTRL_SLS_CLOSED)
      k_fb_a = static_cast<long>(k);
    if (k_fb_q < 0 && q.phase[k] == MC_CTRL_SLS_IF && q.phase[k - 1] == MC_CTRL_SLS_CLOSED)
      k_fb_q = static_cast<long>(k);
  }
  std::printf("fallback: f32 step %ld, q31 step %ld\n", k_fb_a, k_fb_q);
  report("start-stop |omega f32 - q31|", dw, 0.15, "rad/s");
  report("start-stop |i_d f32 - q31|", did, 0.3, "A");
  report("start-stop |i_q f32 - q31|", diq, 0.15, "A");
  report("start-stop q31 |omega| after 1.7 s", w_end, 0.05, "rad/s");
  EXPECT_LE(dw, 0.15);
  EXPECT_LE(did, 0.3);
  EXPECT_LE(diq, 0.15);
  ASSERT_GT(k_fb_a, 0);
  ASSERT_GT(k_fb_q, 0);
  EXPECT_LE(std::abs(k_fb_a - k_fb_q), 3);
  EXPECT_EQ(q.handovers, 1u);
  EXPECT_EQ(q.fallbacks, 1u);
  EXPECT_EQ(q.phase.back(), MC_CTRL_SLS_IF);
  EXPECT_LT(w_end, 0.05);  // the f32 test's standstill bound
}

// The low-speed case of tests/sil/observer with its realistic errors: 2 us
// dead time of which the controller compensates 80 % (the q31 dead-time
// compensation in the loop), 0.02 A current noise (the same seeded
// sequence in both runs), R 10 % high, half load, fallback off; 200 r/min
// ramped down to 100 r/min. The q31 run holds it as the f32 run does
// (mean within 3 r/min, angle error < 0.2 rad). Its mean angle error over
// the last 0.5 s, set by the model errors to about 0.11 rad, agrees with
// the f32 run's within 5 mrad (4 %): the q31 dead-time compensation itself
// (2.6 V per leg) is within 1.5e-5 V of the f32 one on the same currents
// (measured open loop), worth < 1e-5 rad; what remains is the noise-driven
// trajectories differing sample by sample (ADC codes one LSB apart, 1e-4
// rad each, see above), averaged over 4000 samples.
struct LowSpeed {
  double w_mean_rpm = 0, ang_mean = 0, ang_max = 0;
  uint32_t faults = 0;
};

LowSpeed low_speed(bool q31, double rpm) {
  const auto m = mcsim::observer::test_motor_300w();
  SilOptions o;
  o.q31 = q31;
  o.dead_time_s = 2e-6;
  o.dead_comp_frac = 0.8;
  o.noise_rms_a = 0.02;
  o.r_error = 0.1;
  o.lowspeed_fallback = false;
  Sil sil(m, o, mcsim::observer::default_ctrl_cfg(m, o), LoadSteps{{{0.6, 1.5}}});
  LowSpeed r;
  long n = 0;
  const long steps = std::lround(2.2 / sil.board().period_s());
  for (long k = 0; k < steps; ++k) {
    const double t = sil.t_s();
    const double w = t < 0.8 ? 200.0 : (t < 1.3 ? 200.0 + (rpm - 200.0) * (t - 0.8) / 0.5 : rpm);
    EXPECT_EQ(sil.set_speed_ref(static_cast<float>(w * kRpm)), 0u);
    sil.step();
    if (sil.drive().faults != 0u) {
      r.faults = sil.drive().faults;
      return r;
    }
    if (sil.t_s() > 1.7) {
      r.w_mean_rpm += sil.board().state()(2) / kRpm;
      r.ang_mean += sil.angle_error();
      r.ang_max = std::max(r.ang_max, std::abs(sil.angle_error()));
      ++n;
    }
  }
  r.w_mean_rpm /= static_cast<double>(n);
  r.ang_mean /= static_cast<double>(n);
  return r;
}

TEST(Q31Sensorless, LowSpeedWithDeadTimeAndNoiseLikeTheF32Loop) {
  const LowSpeed a = low_speed(false, 100.0);
  const LowSpeed q = low_speed(true, 100.0);
  ASSERT_EQ(a.faults, 0u);
  ASSERT_EQ(q.faults, 0u);
  report("100 r/min f32 mean speed", a.w_mean_rpm, 0, "r/min");
  report("100 r/min q31 |mean speed - 100|", std::abs(q.w_mean_rpm - 100.0), 3, "r/min");
  report("100 r/min f32 mean angle error", a.ang_mean, 0, "rad");
  report("100 r/min q31 mean angle error", q.ang_mean, 0, "rad");
  report("100 r/min f32 max angle error", a.ang_max, 0, "rad");
  report("100 r/min q31 max angle error", q.ang_max, 0.2, "rad");
  report("100 r/min |mean angle error f32 - q31|", std::abs(a.ang_mean - q.ang_mean), 5e-3, "rad");
  EXPECT_NEAR(q.w_mean_rpm, 100.0, 3.0);
  EXPECT_LT(q.ang_max, 0.2);
  EXPECT_LE(std::abs(a.ang_mean - q.ang_mean), 5e-3);
}

// The plug-in's contract: the f32 plug-in's validation with its bits,
// _SCALE for bases, nothing written on error; a non-finite measurement
// is refused with _MEAS and changes nothing (the drive faults on it).
mc_ctrl_sls_q31_cfg_t good_cfg() {
  const auto m = mcsim::observer::test_motor_300w();
  SilOptions o;
  return mcsim::observer::q31_ctrl_cfg(m, mcsim::observer::default_ctrl_cfg(m, o));
}

uint32_t init_expect_untouched(const mc_ctrl_sls_q31_cfg_t& cfg) {
  mc_ctrl_sls_q31_t c;
  std::memset(&c, 0xA5, sizeof c);
  const uint32_t err = mc_ctrl_sls_q31_init(&c, &cfg);
  if (err != 0u) {
    const auto* p = reinterpret_cast<const unsigned char*>(&c);
    EXPECT_TRUE(std::all_of(p, p + sizeof c, [](unsigned char b) { return b == 0xA5; }))
        << "a refused init wrote into the instance (bits " << err << ")";
  }
  return err;
}

TEST(Q31Sensorless, InvalidConfigRejectedWithSpecificError) {
  mc_ctrl_sls_q31_t c{};
  ASSERT_EQ(init_expect_untouched(good_cfg()), 0u);
  EXPECT_EQ(mc_ctrl_sls_q31_init(nullptr, nullptr), MC_CTRL_SLS_ERR_NULL);
  EXPECT_EQ(mc_ctrl_sls_q31_init(&c, nullptr), MC_CTRL_SLS_ERR_NULL);
  // the f32 rules, with the f32 plug-in's bits
  {
    auto q = good_cfg();
    q.f.l_h = -1.0f;
    mc_ctrl_sls_t f{};
    const uint32_t f32_bits = mc_ctrl_sls_init(&f, &q.f);
    EXPECT_NE(f32_bits, 0u);
    EXPECT_EQ(init_expect_untouched(q), f32_bits);
    EXPECT_EQ(f32_bits & MC_CTRL_SLS_ERR_MOTOR, MC_CTRL_SLS_ERR_MOTOR);
  }
  {
    auto q = good_cfg();
    q.f.speed_kp_a_s_rad = std::numeric_limits<float>::quiet_NaN();
    EXPECT_EQ(init_expect_untouched(q), MC_CTRL_SLS_ERR_SPEED);
  }
  {
    auto q = good_cfg();  // the duty-side dead-time correction is f32 only
    q.f.dead_comp_duty = true;
    mc_ctrl_sls_t f{};
    EXPECT_EQ(mc_ctrl_sls_init(&f, &q.f), 0u);
    EXPECT_EQ(init_expect_untouched(q), MC_CTRL_SLS_ERR_TIMING);
  }
  {
    auto q = good_cfg();  // hand-over within 2x the critical speed
    q.f.handover_speed_rad_s = 2.0f * q.f.omega_crit_m_rad_s;
    EXPECT_EQ(init_expect_untouched(q), MC_CTRL_SLS_ERR_STARTUP);
  }
  // bases
  const float bad[] = {0.0f, -1.0f, std::numeric_limits<float>::quiet_NaN(),
                       std::numeric_limits<float>::infinity()};
  for (float v : bad) {
    for (int which = 0; which < 4; ++which) {
      auto q = good_cfg();
      float* b[] = {&q.i_base_a, &q.v_base_v, &q.omega_base_e_rad_s, &q.flux_base_wb};
      *b[which] = v;
      EXPECT_EQ(init_expect_untouched(q), MC_CTRL_SLS_ERR_SCALE) << "base " << which << " = " << v;
    }
  }
  {
    auto q = good_cfg();  // bus above the voltage base
    q.v_base_v = 0.9f * q.f.vbus_max_v;
    EXPECT_EQ(init_expect_untouched(q), MC_CTRL_SLS_ERR_SCALE);
  }
  {
    auto q = good_cfg();  // the fallback's 1.25 iq_max not representable
    q.i_base_a = 1.2f * q.f.iq_max_a;
    EXPECT_EQ(init_expect_untouched(q), MC_CTRL_SLS_ERR_SCALE);
  }
  {
    auto q = good_cfg();  // the PLL's limit above the speed base
    q.omega_base_e_rad_s = 1.5f * q.f.speed_max_rad_s * static_cast<float>(q.f.pole_pairs);
    EXPECT_EQ(init_expect_untouched(q), MC_CTRL_SLS_ERR_SCALE);
  }
  {
    auto q = good_cfg();  // flux base below the flux: the observer refuses it
    q.flux_base_wb = 0.5f * q.f.flux_wb;
    EXPECT_EQ(init_expect_untouched(q), MC_CTRL_SLS_ERR_SCALE | MC_CTRL_SLS_ERR_OBSERVER);
  }
}

TEST(Q31Sensorless, NonFiniteInputsRefusedAndNothingChanges) {
  const auto cfg = good_cfg();
  mc_ctrl_sls_q31_t c{};
  ASSERT_EQ(mc_ctrl_sls_q31_init(&c, &cfg), 0u);
  ASSERT_EQ(mc_ctrl_sls_q31_set_speed_ref(&c, 20.0f), 0u);
  mc_drive_meas_t m{};
  m.ia_a = 0.5f;
  m.ib_a = -0.2f;
  m.ic_a = -0.3f;
  m.vbus_v = 200.0f;
  mc_drive_out_t out{};
  for (int k = 0; k < 50; ++k) ASSERT_EQ(mc_ctrl_sls_q31_fast(&c, &m, &out), 0u);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  for (int which = 0; which < 3; ++which) {
    for (float v : {nan, inf, -inf}) {
      mc_drive_meas_t bad = m;
      float* f[] = {&bad.ia_a, &bad.ib_a, &bad.vbus_v};
      *f[which] = v;
      mc_ctrl_sls_q31_t before = c;
      mc_drive_out_t o2 = out;
      EXPECT_EQ(mc_ctrl_sls_q31_fast(&c, &bad, &o2), MC_CTRL_SLS_ERR_MEAS);
      EXPECT_EQ(std::memcmp(&before, &c, sizeof c), 0) << "state changed on a refused step";
    }
  }
  // speed reference: NaN or beyond the limit refused, the previous kept
  const q31_t cmd = c.omega_cmd;
  EXPECT_EQ(mc_ctrl_sls_q31_set_speed_ref(&c, nan), MC_CTRL_SLS_ERR_REF);
  EXPECT_EQ(mc_ctrl_sls_q31_set_speed_ref(&c, 1.01f * cfg.f.speed_max_rad_s), MC_CTRL_SLS_ERR_REF);
  EXPECT_EQ(c.omega_cmd, cmd);
  // a dead bus: the current loop refuses the step (the drive faults)
  mc_drive_meas_t dead = m;
  dead.vbus_v = 0.0f;
  EXPECT_EQ(mc_ctrl_sls_q31_fast(&c, &dead, &out) & MC_CTRL_SLS_ERR_FOC, MC_CTRL_SLS_ERR_FOC);
  EXPECT_EQ(mc_ctrl_sls_q31_fast(nullptr, &m, &out), MC_CTRL_SLS_ERR_NULL);
}

// Through the drive: a NaN current from the board's ADC faults the drive
// in the period that sees it and opens the bridge, with the q31 plug-in
// running as with the f32 one; and the plug-in, handed such a sample as
// the drive would hand it, refuses it.
TEST(Q31Sensorless, NanMeasurementFaultsTheDrive) {
  const auto m = mcsim::observer::test_motor_300w();
  SilOptions o;
  o.q31 = true;
  Sil sil(m, o, mcsim::observer::default_ctrl_cfg(m, o), LoadSteps{});
  for (int k = 0; k < 2000; ++k) {  // 0.25 s: I-f start, hand-over
    ASSERT_EQ(sil.set_speed_ref(static_cast<float>(200 * kRpm)), 0u);
    sil.step();
  }
  ASSERT_EQ(sil.drive().faults, 0u);
  ASSERT_EQ(sil.tm().phase, MC_CTRL_SLS_CLOSED);
  ASSERT_TRUE(sil.board().pwm_enabled());
  hal_host::PmsmBoard::Injection inj;
  inj.nan_ia = true;
  sil.board().inject(inj);
  sil.step();
  EXPECT_EQ(sil.drive().faults, MC_DRIVE_FAULT_MEAS_NAN);
  EXPECT_FALSE(sil.board().pwm_enabled());
  mc_drive_meas_t bad{};
  bad.ia_a = std::numeric_limits<float>::quiet_NaN();
  bad.vbus_v = 200.0f;
  mc_drive_out_t out{};
  EXPECT_EQ(mc_ctrl_sls_q31_fast(&sil.ctrl_q31(), &bad, &out), MC_CTRL_SLS_ERR_MEAS);
}

}  // namespace
