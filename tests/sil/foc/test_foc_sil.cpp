// The firmware's FOC current loop in closed loop with the simulated board
// (hal/host + sim): step response against the designed bandwidth and
// against an independent discrete-time model of the same loop, steady
// state, d/q decoupling, and safe torque off on a fault.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "foc_sil.hpp"

namespace {

constexpr double kPi = 3.14159265358979323846;

struct StepResult {
  std::vector<double> t, id, iq;
};

// Run the drive in current mode with an iq step at t_step (and optionally an
// id step at t_id), recording the true plant dq currents each period.
StepResult run_steps(mcsim::FocSil& sil, double iq_step, double t_step, double id_step, double t_id,
                     double duration) {
  StepResult r;
  mc_drive_t& d = sil.drive();
  EXPECT_EQ(mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT), 0);
  const long n = std::lround(duration / sil.board().period_s());
  for (long k = 0; k <= n; ++k) {
    const double t = sil.board().t_s();
    EXPECT_EQ(mc_drive_set_current_ref(&d, static_cast<float>(t >= t_id ? id_step : 0.0),
                                       static_cast<float>(t >= t_step ? iq_step : 0.0)),
              0);
    double id, iq;
    sil.board().true_dq_a(&id, &iq);
    r.t.push_back(t);
    r.id.push_back(id);
    r.iq.push_back(iq);
    sil.step();
  }
  EXPECT_EQ(d.faults, 0u);
  return r;
}

// 10-90 % rise time of y after t0 for a step of size a (linear interpolation).
double rise_time(const std::vector<double>& t, const std::vector<double>& y, double t0, double a) {
  auto cross = [&](double level) {
    for (size_t k = 1; k < t.size(); ++k) {
      if (t[k - 1] < t0) continue;
      const double y0 = y[k - 1] / a, y1 = y[k] / a;
      if (y0 < level && y1 >= level) return t[k - 1] + (t[k] - t[k - 1]) * (level - y0) / (y1 - y0);
    }
    return std::nan("");
  };
  return cross(0.9) - cross(0.1);
}

// Independent reference: the same loop as a scalar discrete-time system.
// R-L plant under ZOH, i[k+1] = a i[k] + b v_applied[k], a = exp(-RT/L),
// b = (1 - a)/R; PI with the integral by backward Euler, v[k] = kp e[k] +
// I[k], I[k] = I[k-1] + ki T e[k]; v_applied[k] = v[k - delay]. Written
// from the equations, not from the firmware or the simulator.
double reference_rise_time(double R, double L, double T, double kp, double ki, int delay) {
  const double a = std::exp(-R * T / L), b = (1.0 - a) / R;
  double i = 0.0, I = 0.0, v_prev = 0.0;
  std::vector<double> t, y;
  for (int k = 0; k < 4000; ++k) {
    const double e = 1.0 - i;
    I += ki * T * e;
    const double v = kp * e + I;
    t.push_back(k * T);
    y.push_back(i);
    i = a * i + b * (delay ? v_prev : v);
    v_prev = v;
  }
  return rise_time(t, y, 0.0, 1.0);
}

class FocSilStep : public ::testing::TestWithParam<int> {};

TEST_P(FocSilStep, RiseTimeMatchesDesignAndDiscreteModel) {
  mcsim::FocSilOptions o;
  o.bw_rad_s = 2.0 * kPi * 200.0;  // bw T = 0.063 at 20 kHz
  o.delay_periods = GetParam();
  o.J_kgm2 = 0.1;  // motor on a dyno flywheel: the current loop at near-locked rotor
  mcsim::FocSil sil(o);
  const StepResult r = run_steps(sil, 2.0, 0.002, 0.0, 1.0, 0.02);
  const double measured = rise_time(r.t, r.iq, 0.002, 2.0);
  const double designed = std::log(9.0) / o.bw_rad_s;
  const auto m = mcsim::paper002_test_motor();
  const double ref = reference_rise_time(m.R_ohm, m.Lq_h, 1.0 / o.pwm_hz, sil.designed_kp(),
                                         sil.designed_ki(), o.delay_periods);
  RecordProperty("rise_ratio_to_design", std::to_string(measured / designed));
  // Issue requirement: within 20 % of the designed first-order rise time
  // ln(9)/bw. (The sampled loop and the delay make it differ: 0.97 with no
  // delay, 0.90 with one period, per the reference model.)
  EXPECT_NEAR(measured / designed, 1.0, 0.20);
  // Against the independent discrete model: 3 %. What differs between the
  // two: 12-bit current ADC (9.8 mA LSB, 0.5 % of the step), the back-EMF of
  // the slowly accelerating rotor (< 0.05 V, fed forward), the encoder's
  // angle quantisation, and crossing times interpolated on a 50 us grid
  // (about 1.5 % of a 1.6 ms rise).
  EXPECT_NEAR(measured / ref, 1.0, 0.03) << "measured " << measured << " s, reference " << ref;
}

INSTANTIATE_TEST_SUITE_P(Delay, FocSilStep, ::testing::Values(0, 1));

TEST(FocSil, SteadyStateAndDecoupling) {
  mcsim::FocSilOptions o;
  o.bw_rad_s = 2.0 * kPi * 200.0;
  o.J_kgm2 = 0.1;
  mcsim::FocSil sil(o);
  const StepResult r = run_steps(sil, 2.0, 0.001, -1.0, 0.015, 0.03);
  auto mean = [&](const std::vector<double>& y, double t0, double t1) {
    double s = 0.0;
    int n = 0;
    for (size_t k = 0; k < r.t.size(); ++k) {
      if (r.t[k] >= t0 && r.t[k] < t1) {
        s += y[k];
        ++n;
      }
    }
    return s / n;
  };
  // Mean over 5 ms windows: within 1 % of the reference. The integral action
  // removes any offset; what is left is the ADC quantisation (9.8 mA LSB,
  // 0.5 % of 2 A) averaged over the window.
  EXPECT_NEAR(mean(r.iq, 0.008, 0.0149), 2.0, 0.02);
  EXPECT_NEAR(mean(r.iq, 0.024, 0.03), 2.0, 0.02);
  EXPECT_NEAR(mean(r.id, 0.024, 0.03), -1.0, 0.01);
  // Ripple and d->q coupling: iq stays within 0.15 A of 2 A from 5 ms after
  // its step, through the id step. Cross-coupling omega_e L i is fed forward;
  // what moves iq is the speed estimate of the encoder tracking loop
  // (1000 rad/s): at this low speed each new 8192-count encoder edge kicks it,
  // and the back-EMF feed-forward omega_e psi passes that into v_q. Measured
  // about 0.085 A; a lower tracking bandwidth trades this for lag when the
  // rotor accelerates (README, current loop).
  double worst = 0.0;
  for (size_t k = 0; k < r.t.size(); ++k) {
    if (r.t[k] >= 0.006) worst = std::max(worst, std::abs(r.iq[k] - 2.0));
  }
  RecordProperty("iq_worst_deviation_a", std::to_string(worst));
  EXPECT_LT(worst, 0.15);
}

TEST(FocSil, FaultOpensSwitchesAndCurrentsDecay) {
  // A hardware fault input trips the gate kill; the drive sees it in its
  // slow loop and goes to FAULT; the plant's currents freewheel through the
  // diodes into the 200 V bus and reach zero: L di/dt = -(vbus + ...), i.e.
  // 2 A in about 12 us, within the next PWM period (50 us).
  mcsim::FocSilOptions o;
  o.bw_rad_s = 2.0 * kPi * 200.0;
  o.J_kgm2 = 0.1;
  mcsim::FocSil sil(o);
  run_steps(sil, 2.0, 0.0, 0.0, 1.0, 0.01);
  sil.board().set_fault_inputs(MC_HAL_FAULT_OVERCURRENT);
  sil.step();  // the switches open at once (break input)
  double id, iq;
  sil.board().true_dq_a(&id, &iq);
  EXPECT_FALSE(sil.board().pwm_enabled());
  EXPECT_NEAR(std::hypot(id, iq), 0.0, 1e-9) << "currents must have decayed within one period";
  for (unsigned k = 0; k < o.slow_loop_div; ++k) sil.step();
  EXPECT_EQ(sil.drive().mode, MC_DRIVE_MODE_FAULT);
  EXPECT_EQ(sil.drive().faults, MC_DRIVE_FAULT_HW_INPUT);
  sil.board().true_dq_a(&id, &iq);
  EXPECT_EQ(std::hypot(id, iq), 0.0) << "open circuit: no current while back-EMF < vbus";
}

}  // namespace
