// See pmsm_power_stage.hpp.
#include "mcsim/pmsm_power_stage.hpp"

#include <cmath>

#include "mcsim/integrator.hpp"
#include "util.hpp"

namespace mcsim {

namespace {

// The open-phase plant with the series current held at zero: open terminals
// (no current, no torque), only the mechanics move.
struct OpenPhaseNoCurrent {
  using State = PmsmOpenPhase::State;
  using Input = PmsmOpenPhase::Input;
  const PmsmOpenPhase* plant;
  State deriv(double t_s, const State& x, const Input& u) const {
    State x0 = x;
    x0(PmsmOpenPhase::kI) = 0.0;
    State dx = plant->deriv(t_s, x0, u);
    dx(PmsmOpenPhase::kI) = 0.0;
    return dx;
  }
};

// The healthy plant with its currents held at zero: open terminals (no
// current, no torque), only the mechanics move. Integrating the full model
// from zero current instead lets the back-EMF build a current inside the RK4
// stages, whose torque would brake the rotor although no current flows.
struct RotorFrameNoCurrent {
  using State = PmsmRotorFrame::State;
  using Input = PmsmRotorFrame::Input;
  const PmsmRotorFrame* plant;
  State deriv(double t_s, const State& x, const Input& u) const {
    State x0 = x;
    x0(0) = x0(1) = 0.0;
    State dx = plant->deriv(t_s, x0, u);
    dx(0) = dx(1) = 0.0;
    return dx;
  }
};

}  // namespace

Status PmsmPowerStageParams::validate() const {
  const Status sm = motor.validate();
  if (sm != Status::kOk) return sm;
  const Status si = inverter.validate();
  if (si != Status::kOk) return si;
  if (substeps < 1) return Status::kBadStepCount;
  if (!(vbus_v > 0.0) || !detail::all_finite({vbus_v, theta_m0_rad, omega_m0_rad_s})) {
    return Status::kNotFinite;
  }
  return thermal_enabled ? thermal.validate() : Status::kOk;
}

Status PmsmPowerStage::configure(const PmsmPowerStageParams& p) {
  const Status s = p.validate();
  if (s != Status::kOk) return s;
  p_ = p;
  (void)plant_.configure(p.motor);  // validated above
  (void)inverter_.configure(p.inverter);
  x_ = plant_.make_state(0.0, 0.0, p.omega_m0_rad_s, p.theta_m0_rad);
  t_s_ = 0.0;
  period_count_ = 0;
  duty_applied_ = Eigen::Vector3d::Constant(0.5);
  v_ab_applied_ = Eigen::Vector2d::Zero();
  open_circuit_ = true;
  open_phase_ = -1;
  open_fresh_ = true;
  open_i_a_ = 0.0;
  thermal_on_ = p.thermal_enabled;
  if (thermal_on_) {
    (void)thermal_.configure(p.thermal);  // validated above
    apply_temperatures();
  }
  return Status::kOk;
}

void PmsmPowerStage::apply_temperatures() {
  // R and flux at the present temperatures; a temperature so far out that
  // either would leave its range (R <= 0 below -234 C, flux < 0 hundreds of
  // K above T_ref) keeps the previous values.
  const double r = p_.motor.R_ohm * thermal_.resistance_factor();
  const double flux = p_.motor.flux_wb * thermal_.flux_factor();
  if (plant_.set_electrical(r, flux) == Status::kOk && open_phase_ >= 0) {
    (void)open_plant_.configure(plant_.params(), open_phase_);
  }
}

void PmsmPowerStage::thermal_period(double isq0) {
  const double isq1 = current_sq_a2();
  const double omega_e = static_cast<double>(p_.motor.pole_pairs) * x_(PmsmRotorFrame::kOmegaM);
  thermal_.advance(p_.inverter.t_pwm_s, 1, 0.5 * (isq0 + isq1), omega_e, p_.motor.R_ohm);
  apply_temperatures();
}

Status PmsmPowerStage::set_open_phase(int phase) {
  if (phase < -1 || phase > 2) return Status::kBadPhase;
  if (phase >= 0) {
    const Status s = open_plant_.configure(plant_.params(), phase);
    if (s != Status::kOk) return s;
  }
  if (phase != open_phase_) open_fresh_ = true;
  open_phase_ = phase;
  return Status::kOk;
}

Status PmsmPowerStage::set_load(const LoadTorque& load) {
  PmsmParams p = plant_.params();
  p.load = load;
  const Status s = p.validate();
  if (s != Status::kOk) return s;
  (void)plant_.configure(p);
  if (open_phase_ >= 0) (void)open_plant_.configure(p, open_phase_);
  p_.motor.load = load;
  return Status::kOk;
}

Eigen::Vector3d PmsmPowerStage::phase_currents_true_a() const {
  if (open_phase_ >= 0 && !open_fresh_) {
    PmsmOpenPhase::State xo = PmsmOpenPhase::State::Zero();
    xo(PmsmOpenPhase::kI) = open_i_a_;
    return open_plant_.phase_currents_a(xo);
  }
  return phase_currents_a();
}

void PmsmPowerStage::freewheel(double h_s, int n) {
  const double vbus = p_.vbus_v;
  const double pp = p_.motor.pole_pairs;
  for (int k = 0; k < n; ++k) {
    const double t = t_s_ + k * h_s;
    if (open_circuit_) {
      // Open circuit: currents stay zero unless the back-EMF exceeds vbus,
      // in which case the diode bridge conducts again.
      const double emf_ll_peak = std::sqrt(3.0) * std::abs(pp * x_(2)) * p_.motor.flux_wb;
      if (emf_ll_peak <= vbus) {
        x_(0) = x_(1) = 0.0;
        const PmsmRotorFrame::Input u = PmsmRotorFrame::Input::Zero();
        // Mechanics only: with zero current there is no torque, and the
        // electrical equations are not integrated (open terminals).
        const RotorFrameNoCurrent nc{&plant_};
        x_ = rk4_step(nc, t, x_, u, h_s);
        continue;
      }
      open_circuit_ = false;
    }
    // Diode freewheeling: pole at 0 V for current into the motor, at vbus
    // for current out of it; a phase with no current sits at mid-bus.
    const Eigen::Vector3d i = phase_currents_a();
    Eigen::Vector3d duty;
    for (int j = 0; j < 3; ++j) duty(j) = (i(j) > 0.0) ? 0.0 : ((i(j) < 0.0) ? 1.0 : 0.5);
    const Eigen::Vector2d v = inverter_.alpha_beta_v(duty, vbus, Eigen::Vector3d::Zero());
    const State before = x_;
    State x1 = rk4_step(plant_, t, x_, v, h_s);
    // The diodes block reverse current: if the current vector reversed
    // within the sub-step, it reached zero inside it. A current that starts
    // from zero (the back-EMF has just overcome the bus) cannot reverse.
    const bool was_flowing = (before(0) != 0.0) || (before(1) != 0.0);
    if (was_flowing && x1(0) * before(0) + x1(1) * before(1) <= 0.0) {
      x1(0) = x1(1) = 0.0;
      open_circuit_ = true;
    }
    x_ = x1;
    v_ab_applied_ = v;
  }
}

void PmsmPowerStage::advance_open_phase(const Eigen::Vector3d& duty, bool switching) {
  using OP = PmsmOpenPhase;
  const double T = p_.inverter.t_pwm_s;
  const int n = p_.substeps;
  const double h = T / n;
  const double vbus = p_.vbus_v;
  // Mechanics and (cos, sin) from x_ (re-synced there); the series current
  // carried over, or projected at the break.
  OP::State xo = open_plant_.from_rotor_frame(x_);
  if (!open_fresh_) xo(OP::kI) = open_i_a_;
  open_fresh_ = false;
  const int y = open_plant_.phase_y();
  const int z = open_plant_.phase_z();
  if (switching) {
    // The pair sees the difference of its two pole voltages (held over the
    // period, dead time evaluated at the period's start as on the healthy path).
    const Eigen::Vector3d i = open_plant_.phase_currents_a(xo);
    const Eigen::Vector3d vp = inverter_.pole_voltages_v(duty, vbus, i);
    const OP::Input u(vp(y) - vp(z));
    duty_applied_ = duty;
    // The commanded vector; the motor sees its part along the pair.
    v_ab_applied_ = inverter_.alpha_beta_v(duty, vbus, i);
    // advance_zoh fails only on a time that is not finite: then nothing moves.
    if (advance_zoh(open_plant_, u, t_s_, T, n, &xo) != Status::kOk) return;
  } else {
    duty_applied_ = Eigen::Vector3d::Constant(0.5);
    v_ab_applied_ = Eigen::Vector2d::Zero();
    for (int k = 0; k < n; ++k) {
      const double t = t_s_ + k * h;
      const double i0 = xo(OP::kI);
      const double e = open_plant_.line_emf_v(xo);
      if (i0 == 0.0 && std::abs(e) <= vbus) {
        // Diodes blocking: no current, mechanics only.
        const OpenPhaseNoCurrent nc{&open_plant_};
        xo = rk4_step(nc, t, xo, OP::Input::Zero(), h);
        xo(OP::kI) = 0.0;
        continue;
      }
      // Current i > 0 flows into y (its lower diode: pole at 0 V) and out of
      // z (upper diode: vbus): v_yz = -vbus; reversed for i < 0. From zero,
      // a line back-EMF beyond vbus drives the current the way it points.
      const double dir = (i0 != 0.0) ? i0 : -e;
      const OP::Input u((dir > 0.0) ? -vbus : vbus);
      OP::State x1 = rk4_step(open_plant_, t, xo, u, h);
      if (i0 != 0.0 && x1(OP::kI) * i0 <= 0.0) x1(OP::kI) = 0.0;  // diodes block reversal
      xo = x1;
    }
  }
  open_i_a_ = xo(OP::kI);
  open_circuit_ = (open_i_a_ == 0.0);
  x_ = open_plant_.to_rotor_frame(xo);
}

Status PmsmPowerStage::advance_special(const Eigen::Vector3d& duty, bool switching) {
  if (!std::isfinite(t_s_)) return Status::kNotFinite;
  const double isq0 = thermal_on_ ? current_sq_a2() : 0.0;
  const int n = p_.substeps;
  if (open_phase_ >= 0) {
    advance_open_phase(duty, switching);
  } else {
    freewheel(p_.inverter.t_pwm_s / n, n);
    duty_applied_ = Eigen::Vector3d::Constant(0.5);
  }
  end_period(isq0);
  return Status::kOk;
}

}  // namespace mcsim
