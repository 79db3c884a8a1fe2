// Shared helpers of the simulator validation tests.
#ifndef MCSIM_TEST_SIM_TEST_UTIL_HPP
#define MCSIM_TEST_SIM_TEST_UTIL_HPP

#include <Eigen/Core>

namespace mcsim_test {

constexpr double kPi = 3.14159265358979323846;

// Wraps a 4-state plant and integrates, next to its state, the energies that
// flow through it: [4] input, [5] copper loss, [6] viscous friction B w^2,
// [7] load (incl. Coulomb) tau_load w. The same RK4 integrates them, so the
// balance E_in = E_cu + E_fric + E_load + dE_mag + dE_kin holds to the
// integrator's truncation error (no separate quadrature error).
template <class Plant>
struct EnergyAudit {
  using State = Eigen::Matrix<double, 8, 1>;
  using Input = typename Plant::Input;
  const Plant* plant = nullptr;

  State deriv(double t_s, const State& xa, const Input& u) const {
    const typename Plant::State x = xa.template head<4>();
    State d;
    d.template head<4>() = plant->deriv(t_s, x, u);
    const double w = x(2);
    d(4) = plant->input_power_w(x, u);
    d(5) = plant->copper_loss_w(x);
    d(6) = plant->params().B_nms_rad * w * w;
    d(7) = plant->load_nm(t_s, x) * w;
    return d;
  }

  // Residual of the energy balance between xa0 and xa1 [J].
  double residual_j(const State& xa0, const State& xa1) const {
    const typename Plant::State x0 = xa0.template head<4>();
    const typename Plant::State x1 = xa1.template head<4>();
    const double d_stored = plant->magnetic_energy_j(x1) - plant->magnetic_energy_j(x0) +
                            plant->kinetic_energy_j(x1) - plant->kinetic_energy_j(x0);
    const double e_in = xa1(4) - xa0(4);
    const double e_out = (xa1(5) - xa0(5)) + (xa1(6) - xa0(6)) + (xa1(7) - xa0(7));
    return e_in - e_out - d_stored;
  }
};

}  // namespace mcsim_test

#endif  // MCSIM_TEST_SIM_TEST_UTIL_HPP
