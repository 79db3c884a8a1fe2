// See stepper_common_leg_stage.hpp.
#include "mcsim/stepper_common_leg_stage.hpp"

#include <cmath>

#include "mcsim/integrator.hpp"
#include "util.hpp"

namespace mcsim {

namespace {

using Plant = Stepper2Ph;

// The plant with the currents flagged in `held` kept at zero (an open
// winding): their derivatives are zero and they enter the torque as zero.
struct HeldAtZero {
  using State = Plant::State;
  using Input = Plant::Input;
  const Plant* plant;
  bool held[2];
  State deriv(double t_s, const State& x, const Input& u) const {
    State x0 = x;
    for (int j = 0; j < 2; ++j) {
      if (held[j]) x0(j) = 0.0;
    }
    State dx = plant->deriv(t_s, x0, u);
    for (int j = 0; j < 2; ++j) {
      if (held[j]) dx(j) = 0.0;
    }
    return dx;
  }
};

// The windings in series between legs 1 and 2 (the common leg carries no
// current): v_1 - v_2 = d_v is given, the floating common node makes
// i_a + i_b stay zero: v_a + v_b = -(e_a + e_b), v_a - v_b = d_v, with the
// back-EMFs e_a = K w sin(N th), e_b = -K w cos(N th) of Stepper2Ph.
struct Series {
  using State = Plant::State;
  using Input = Plant::Input;
  const Plant* plant;
  double d_v;
  State deriv(double t_s, const State& x, const Input& /*u*/) const {
    const Stepper2PhParams& p = plant->params();
    const double nth = static_cast<double>(p.rotor_teeth) * x(Plant::kThetaM);
    const double w = x(Plant::kOmegaM);
    const double e_sum = p.Km_nm_a * w * (std::sin(nth) - std::cos(nth));
    const Input u(0.5 * (d_v - e_sum), 0.5 * (-d_v - e_sum));
    return plant->deriv(t_s, x, u);
  }
};

// Pole voltage of a conducting leg with the switches open: 0 for current
// out of the leg (lower diode), vbus for current into it (upper diode).
double clamp_pole(double i_leg, double vbus) {
  return (i_leg > 0.0) ? 0.0 : vbus;
}

}  // namespace

Status StepperCommonLegStageParams::validate() const {
  const Status sm = motor.validate();
  if (sm != Status::kOk) return sm;
  const Status si = inverter.validate();
  if (si != Status::kOk) return si;
  if (substeps < 1) return Status::kBadStepCount;
  if (!(vbus_v > 0.0) || !detail::all_finite({vbus_v, theta_m0_rad})) return Status::kNotFinite;
  return Status::kOk;
}

Status StepperCommonLegStage::configure(const StepperCommonLegStageParams& p) {
  const Status s = p.validate();
  if (s != Status::kOk) return s;
  p_ = p;
  (void)plant_.configure(p.motor);  // validated above
  (void)inverter_.configure(p.inverter);
  x_ = State::Zero();
  x_(Plant::kThetaM) = p.theta_m0_rad;
  t_s_ = 0.0;
  period_count_ = 0;
  v_applied_ = Eigen::Vector2d::Zero();
  p_in_w_ = 0.0;
  return Status::kOk;
}

void StepperCommonLegStage::freewheel(double h_s, int n) {
  const double vbus = (p_.vbus_v > 0.0) ? p_.vbus_v : 0.0;
  double e_in = 0.0;
  for (int k = 0; k < n; ++k) {
    const double t = t_s_ + k * h_s;
    const double ia = x_(Plant::kIa), ib = x_(Plant::kIb);
    const double i3 = -(ia + ib);
    State x1 = x_;
    Eigen::Vector2d u = Eigen::Vector2d::Zero();
    if (ia == 0.0 && ib == 0.0) {
      const HeldAtZero open{&plant_, {true, true}};
      x1 = rk4_step(open, t, x_, u, h_s);
    } else if (ia != 0.0 && ib != 0.0 && i3 != 0.0) {
      const double v3 = clamp_pole(i3, vbus);
      u << clamp_pole(ia, vbus) - v3, clamp_pole(ib, vbus) - v3;
      x1 = rk4_step(plant_, t, x_, u, h_s);
      const bool za = x1(Plant::kIa) * ia <= 0.0, zb = x1(Plant::kIb) * ib <= 0.0;
      const bool z3 = -(x1(Plant::kIa) + x1(Plant::kIb)) * i3 <= 0.0;
      if (za || zb) {
        if (za) x1(Plant::kIa) = 0.0;
        if (zb) x1(Plant::kIb) = 0.0;
      } else if (z3) {
        const double s = 0.5 * (x1(Plant::kIa) - x1(Plant::kIb));
        x1(Plant::kIa) = s;
        x1(Plant::kIb) = -s;
      }
    } else if (i3 != 0.0) {
      // One winding alone across its legs; the other held open.
      const int j = (ia != 0.0) ? 0 : 1;
      u(j) = clamp_pole(x_(j), vbus) - clamp_pole(i3, vbus);
      const HeldAtZero one{&plant_, {j == 1, j == 0}};
      x1 = rk4_step(one, t, x_, u, h_s);
      if (x1(j) * x_(j) <= 0.0) x1(j) = 0.0;
      x1(1 - j) = 0.0;
    } else {
      // i_a = -i_b: in series between legs 1 and 2.
      const Series ser{&plant_, clamp_pole(ia, vbus) - clamp_pole(ib, vbus)};
      x1 = rk4_step(ser, t, x_, u, h_s);
      const double s = (x1(Plant::kIa) * ia <= 0.0) ? 0.0 : 0.5 * (x1(Plant::kIa) - x1(Plant::kIb));
      x1(Plant::kIa) = s;
      x1(Plant::kIb) = -s;
      // The winding voltages of the sub-step's start, for v_applied().
      const double nth = static_cast<double>(p_.motor.rotor_teeth) * x_(Plant::kThetaM);
      const double e_sum = p_.motor.Km_nm_a * x_(Plant::kOmegaM) * (std::sin(nth) - std::cos(nth));
      u << 0.5 * (ser.d_v - e_sum), 0.5 * (-ser.d_v - e_sum);
    }
    e_in += 0.5 * h_s * (u(0) * (ia + x1(Plant::kIa)) + u(1) * (ib + x1(Plant::kIb)));
    x_ = x1;
    v_applied_ = u;
  }
  p_in_w_ = e_in / (h_s * n);
}

Status StepperCommonLegStage::advance(const Eigen::Vector3d& duty, bool switching) {
  const double T = p_.inverter.t_pwm_s;
  const int n = p_.substeps;
  if (!std::isfinite(t_s_)) return Status::kNotFinite;
  if (!switching) {
    freewheel(T / n, n);
  } else {
    const Eigen::Vector2d i0(x_(Plant::kIa), x_(Plant::kIb));
    v_applied_ = inverter_.voltages_v(duty, p_.vbus_v, i0);
    const Status s = advance_zoh(plant_, v_applied_, t_s_, T, n, &x_);
    if (s != Status::kOk) return s;
    const Eigen::Vector2d i1(x_(Plant::kIa), x_(Plant::kIb));
    p_in_w_ = 0.5 * v_applied_.dot(i0 + i1);
  }
  ++period_count_;
  t_s_ = static_cast<double>(period_count_) * T;
  return Status::kOk;
}

}  // namespace mcsim
