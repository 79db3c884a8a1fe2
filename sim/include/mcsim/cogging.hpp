// mcsim/cogging.hpp: the cogging (detent) torque of a slotted PM motor: the
// attraction between the magnets and the stator teeth, a torque that
// depends only on the mechanical angle and has zero mean over a turn.
//
// Periodicity: the co-energy of the magnets against the slotted stator
// repeats whenever the rotor has moved by the angle after which both the
// slot pattern and the pole pattern coincide again, i.e. lcm(Q, 2p) times
// per mechanical turn for Q slots and 2p poles (Zhu and Howe, "Influence
// of design parameters on cogging torque in permanent magnet machines",
// IEEE Trans. Energy Conversion 15(4), 2000: the fundamental cogging order
// is the least common multiple of the slot and pole numbers; its multiples
// are the harmonics). Examples: 12 slots / 14 poles: 84 periods per turn;
// 9 slots / 6 poles: 18; 12 slots / 8 poles: 24.
//
// Torque on the rotor (positive accelerates positive rotation):
//
//   tau_cog(th) = sum_{k=1..K} A_k sin(k N th + phi_k),   N = lcm(Q, 2p)
//
// with A_1 = amplitude_nm (the motor file's cogging_nm, the peak of the
// fundamental), phi_1 = phase_rad, and the optional harmonics k = 2..4. It
// is the negative gradient of the potential
//
//   W(th) = sum_k A_k / (k N) cos(k N th + phi_k)
//
// (tau_cog = -dW/dth), so it does no work over a period: energy_j() is W
// for an energy balance. Every plant adds it to its torque balance:
//   J dw/dt = tau_e + tau_cog(th) - B w - load(t, th, w).
// Defaults: slots = 0 or amplitudes 0 = no cogging (bit for bit the plant
// without it).
#ifndef MCSIM_COGGING_HPP
#define MCSIM_COGGING_HPP

#include <cmath>

#include "mcsim/status.hpp"

namespace mcsim {

struct CoggingParams {
  static constexpr int kMaxHarmonics = 3;               // orders 2N, 3N, 4N
  int slots = 0;                                        // stator slots Q; 0 = no cogging
  double amplitude_nm = 0.0;                            // A_1 >= 0: peak of the fundamental [N m]
  double phase_rad = 0.0;                               // phi_1
  double harmonic_nm[kMaxHarmonics] = {0.0, 0.0, 0.0};  // A_2..A_4 >= 0
  double harmonic_phase_rad[kMaxHarmonics] = {0.0, 0.0, 0.0};  // phi_2..phi_4

  // kOk, kNotFinite, kBadCogging (slots < 0 or above 1000, an amplitude < 0).
  Status validate() const;
  // slots > 0 and some amplitude > 0.
  bool active() const;
};

// lcm(slots, 2 pole_pairs): cogging periods per mechanical turn (0 when
// slots or pole_pairs is not positive).
int cogging_order(int slots, int pole_pairs);

class CoggingTorque {
 public:
  // Validates c (and pole_pairs >= 1: kBadPolePairs); on error keeps the
  // previous configuration.
  Status configure(const CoggingParams& c, int pole_pairs);
  bool active() const { return active_; }
  int order_per_rev() const { return order_; }
  // tau_cog(th) [N m]; 0 when not active.
  double torque_nm(double theta_m_rad) const { return active_ ? eval(theta_m_rad, false) : 0.0; }
  // W(th) [J] with tau_cog = -dW/dth; 0 when not active.
  double energy_j(double theta_m_rad) const { return active_ ? eval(theta_m_rad, true) : 0.0; }

 private:
  double eval(double theta_m_rad, bool potential) const;
  static constexpr int kOrders = 1 + CoggingParams::kMaxHarmonics;
  bool active_ = false;
  int order_ = 0;
  // Per harmonic k = 1..4: A_k, A_k cos(phi_k), A_k sin(phi_k).
  double a_[kOrders] = {0.0, 0.0, 0.0, 0.0};
  double ac_[kOrders] = {0.0, 0.0, 0.0, 0.0};
  double as_[kOrders] = {0.0, 0.0, 0.0, 0.0};
};

}  // namespace mcsim

#endif  // MCSIM_COGGING_HPP
