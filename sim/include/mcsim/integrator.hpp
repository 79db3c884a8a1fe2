// mcsim/integrator.hpp: fixed-step integration of any plant that provides
//   using State = <fixed-size Eigen vector>; using Input = <...>;
//   State deriv(double t, const State& x, const Input& u) const;
// and the control-timing helpers (zero-order hold over a control period,
// computation delay). Header-only templates; nothing here allocates.
//
// Timing of a drive, as the simulator reproduces it:
//   for each control period k (length T):
//     measure x(kT) -> controller -> u_new
//     u_applied = delay.push(u_new)       (u_new of 'delay' periods ago)
//     advance_zoh(plant, u_applied, kT, T, n_sub, &x)
#ifndef MCSIM_INTEGRATOR_HPP
#define MCSIM_INTEGRATOR_HPP

#include <array>
#include <cmath>
#include <cstddef>

#include "mcsim/status.hpp"

namespace mcsim {

// One classical 4-stage Runge-Kutta step of length h_s, input held constant.
template <class Plant>
typename Plant::State rk4_step(const Plant& plant, double t_s, const typename Plant::State& x,
                               const typename Plant::Input& u, double h_s) {
  using State = typename Plant::State;
  const double half = 0.5 * h_s;
  const State k1 = plant.deriv(t_s, x, u);
  const State x2 = x + half * k1;
  const State k2 = plant.deriv(t_s + half, x2, u);
  const State x3 = x + half * k2;
  const State k3 = plant.deriv(t_s + half, x3, u);
  const State x4 = x + h_s * k3;
  const State k4 = plant.deriv(t_s + h_s, x4, u);
  const State incr = (h_s / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
  return x + incr;
}

// Advances *x from t0_s over one control period period_s with n_sub equal RK4
// sub-steps and the input u held constant (zero-order hold).
// Errors (state unchanged): kBadStepCount (n_sub < 1), kBadPeriod
// (period_s <= 0 or not finite), kNotFinite (t0_s not finite).
template <class Plant>
Status advance_zoh(const Plant& plant, const typename Plant::Input& u, double t0_s, double period_s,
                   int n_sub, typename Plant::State* x) {
  if (n_sub < 1) {
    return Status::kBadStepCount;
  }
  if (!std::isfinite(period_s) || !(period_s > 0.0)) {
    return Status::kBadPeriod;
  }
  if (!std::isfinite(t0_s) || x == nullptr) {
    return Status::kNotFinite;
  }
  const double h_s = period_s / static_cast<double>(n_sub);
  typename Plant::State xk = *x;
  for (int k = 0; k < n_sub; ++k) {
    // t from the step index (no accumulated round-off in time).
    const double t_s = t0_s + static_cast<double>(k) * h_s;
    xk = rk4_step(plant, t_s, xk, u, h_s);
  }
  *x = xk;
  return Status::kOk;
}

// Computation delay of a whole number of control periods, 0..kCapacity, as a
// fixed-capacity ring buffer (FIFO) of inputs.
template <class Input, std::size_t kCapacity>
class InputDelay {
  static_assert(kCapacity >= 1U, "InputDelay needs a capacity of at least 1");

 public:
  InputDelay() { buf_.fill(Input::Zero()); }

  // delay_periods in [0, kCapacity]; the first delay_periods calls of push()
  // return 'initial'. Error (nothing changed): kDelayTooLong.
  Status configure(std::size_t delay_periods, const Input& initial) {
    if (delay_periods > kCapacity) {
      return Status::kDelayTooLong;
    }
    delay_ = delay_periods;
    head_ = 0U;
    buf_.fill(initial);
    return Status::kOk;
  }

  std::size_t delay() const { return delay_; }

  // Stores the newest input and returns the one to apply in this period:
  // u_new itself for a delay of 0, else the input pushed 'delay' calls ago.
  Input push(const Input& u_new) {
    if (delay_ == 0U) {
      return u_new;
    }
    Input out = buf_[head_];
    buf_[head_] = u_new;
    if (++head_ == delay_) {
      head_ = 0U;  // (no integer division once per period)
    }
    return out;
  }

 private:
  std::array<Input, kCapacity> buf_;
  std::size_t delay_ = 1U;
  std::size_t head_ = 0U;
};

}  // namespace mcsim

#endif  // MCSIM_INTEGRATOR_HPP
