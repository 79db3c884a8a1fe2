// mcsim/thermal.hpp: the motor's temperatures, a two-node thermal network
// (winding, housing) to ambient, with the copper losses following the
// winding's resistance R(T) and the magnet's flux falling with its
// temperature. The plant's own physics, written independently of the
// firmware's estimator (issue 33 item 3), so the two can be compared.
//
//   C_w dT_w/dt = P_cu - (T_w - T_h) / R_wh
//   C_h dT_h/dt = (T_w - T_h) / R_wh + P_fe - (T_h - T_a) / R_ha
//
//   P_cu = 3/2 R(T_w) |i_dq|^2         (amplitude-invariant dq, 3 phases)
//   R(T) = R_ref (1 + a (T - 20)) / (1 + a (T_ref - 20)),   a = 0.00393 / K
//   P_fe = k_h f_e + k_e f_e^2,        f_e = p |w_m| / 2 pi  (optional, 0 by default)
//   flux(T_m) = flux_ref (1 + b (T_m - T_ref)),             b = -0.0012 / K
//   T_m = T_h + m (T_w - T_h)           (magnet between housing and winding)
//
// Sources of the constants and the structure:
// - Copper: a = 0.00393 / K at 20 C (IEC 60028, the international standard
//   of resistance for annealed copper); R_ref is the motor's R_ohm measured at T_ref (maxon's
//   catalogue gives the terminal resistance at 25 C, the default here).
// - NdFeB: the reversible temperature coefficient of remanence is about
//   -0.11 to -0.12 %/K (e.g. Arnold Magnetic Technologies' N-grade data);
//   b = -0.0012 / K, settable (SmCo is about -0.035 %/K, ferrite -0.2 %/K).
//   Linear and reversible: no irreversible demagnetisation is modelled.
// - Two nodes: winding-housing R_th1 and housing-ambient R_th2 with the
//   winding's and the motor's thermal time constants, the model small-motor
//   catalogues (maxon: "thermal resistance winding-housing / housing-ambient",
//   "thermal time constant winding / motor", computed as heat capacity times
//   thermal resistance) publish for every motor.
// - Iron losses: Steinmetz's split into hysteresis (linear in frequency)
//   and eddy current (quadratic) losses at a given flux density. They heat
//   the housing node (the stator iron sits in it). The energy they take
//   from the shaft is the plant's friction: iron_loss_friction() gives the
//   viscous and Coulomb terms that dissipate exactly P_fe, to add to
//   PmsmParams (B, load.coulomb_nm) when the mechanical energy must balance.
//
// Defaults from a rating (thermal_from_rating): the total resistance
// R_wh + R_ha makes the steady winding rise at the rated current exactly the
// rated rise (80 K: the IEC 60034-1 limit by resistance for insulation
// class B (130), the usual continuous rating of small motors), split by
// winding_share; the capacities from the time constants tau_w = C_w R_wh
// (winding) and tau_h = C_h R_ha (housing), or from masses and specific
// heats (heat_capacity_j_k: copper 385, iron 449, aluminium 897 J/(kg K), the
// CRC Handbook's values at 25 C). The defaults of ThermalRating (share 0.3,
// tau_w 30 s, tau_h 900 s) are of the order small-motor catalogues give for
// 50-500 W motors; a motor's own values replace them.
//
// Integration: RK4 over each advance() with the inputs held (h is a PWM
// period, the time constants are seconds: the truncation error is
// negligible), the energies (copper, iron, to ambient) integrated as states
// by the same RK4, so C_w dT_w + C_h dT_h = E_cu + E_fe - E_amb holds to
// rounding. Nothing allocates; no firmware header.
#ifndef MCSIM_THERMAL_HPP
#define MCSIM_THERMAL_HPP

#include "mcsim/status.hpp"

namespace mcsim {

struct ThermalParams {
  double ambient_c = 25.0;
  double r_wh_k_w = 1.0;               // winding -> housing [K/W], > 0
  double r_ha_k_w = 3.0;               // housing -> ambient [K/W], > 0
  double c_w_j_k = 30.0;               // winding (copper) heat capacity [J/K], > 0
  double c_h_j_k = 300.0;              // housing (iron, case) heat capacity [J/K], > 0
  double t_ref_c = 25.0;               // temperature of the motor's R_ohm and flux_wb
  double alpha_cu_1_k = 0.00393;       // copper, at 20 C; in [0, 0.01]
  double beta_magnet_1_k = -0.0012;    // magnet flux per K; in [-0.01, 0]
  double magnet_winding_weight = 0.0;  // T_m = T_h + m (T_w - T_h), m in [0, 1]
  double iron_k_h_w_hz = 0.0;          // hysteresis loss per electrical Hz [W/Hz] >= 0
  double iron_k_e_w_hz2 = 0.0;         // eddy loss per Hz^2 [W/Hz^2] >= 0
  double t_w0_c = 25.0;                // initial winding temperature
  double t_h0_c = 25.0;                // initial housing temperature

  // kOk, kNotFinite, kBadThermal (a resistance or capacity <= 0, a
  // coefficient out of its range, a temperature below -273.15 C).
  Status validate() const;
};

// The inputs of thermal_from_rating().
struct ThermalRating {
  double r_ohm = 0.1;       // phase resistance at t_ref_c [ohm]
  double i_rated_a = 10.0;  // continuous current (peak phase, amplitude-invariant) [A]
  double rise_k = 80.0;     // steady winding rise at i_rated_a [K]
  double ambient_c = 25.0;
  double t_ref_c = 25.0;
  double winding_share = 0.3;    // R_wh / (R_wh + R_ha), in (0, 1)
  double tau_winding_s = 30.0;   // C_w R_wh
  double tau_housing_s = 900.0;  // C_h R_ha
};

// A ThermalParams from a rating (the other fields at their defaults, the
// initial temperatures at ambient). kBadThermal for a rating <= 0 or a share
// outside (0, 1); *out unchanged on error.
Status thermal_from_rating(const ThermalRating& r, ThermalParams* out);

// Heat capacity [J/K] of the given masses [kg] of copper, iron (steel,
// laminations) and aluminium.
double heat_capacity_j_k(double copper_kg, double iron_kg, double aluminium_kg);
constexpr double kSpecificHeatCopperJKgK = 385.0;
constexpr double kSpecificHeatIronJKgK = 449.0;
constexpr double kSpecificHeatAluminiumJKgK = 897.0;

// Energies since configure() [J].
struct ThermalEnergy {
  double copper_j = 0.0;
  double iron_j = 0.0;
  double ambient_j = 0.0;  // conducted from the housing to ambient
};

class ThermalModel {
 public:
  // Validates p and starts at its initial temperatures; on error keeps
  // everything.
  Status configure(const ThermalParams& p);
  const ThermalParams& params() const { return p_; }

  // Advances by h_s (> 0, else nothing) with |i_dq|^2 [A^2] (the mean of
  // i_d^2 + i_q^2 over the interval), the electrical speed [rad/s] and the
  // motor's reference resistance r_ref_ohm [ohm], all held, in n RK4 steps.
  void advance(double h_s, int n, double i_sq_a2, double omega_e_rad_s, double r_ref_ohm);

  double winding_c() const { return t_w_; }
  double housing_c() const { return t_h_; }
  double magnet_c() const { return t_h_ + p_.magnet_winding_weight * (t_w_ - t_h_); }
  // R(T_w) / R_ref and flux(T_m) / flux_ref.
  double resistance_factor() const { return resistance_factor_at(t_w_); }
  double flux_factor() const;
  double resistance_factor_at(double t_winding_c) const;
  // Losses at the present state [W].
  double copper_loss_w(double i_sq_a2, double r_ref_ohm) const;
  double iron_loss_w(double omega_e_rad_s) const;
  const ThermalEnergy& energy() const { return e_; }
  // Heat stored above the initial temperatures [J].
  double stored_j() const;
  // Steady temperatures for a constant copper loss p_cu_w (R(T) ignored) and
  // iron loss p_fe_w: T_h = T_a + (P_cu + P_fe) R_ha, T_w = T_h + P_cu R_wh.
  double steady_winding_c(double p_cu_w, double p_fe_w) const;

  // Viscous coefficient B [N m s/rad] and Coulomb torque [N m] whose
  // dissipation B w^2 + T_c |w| equals P_fe(p w) at every speed.
  void iron_loss_friction(int pole_pairs, double* b_nms_rad, double* coulomb_nm) const;

 private:
  ThermalParams p_{};
  double t_w_ = 25.0, t_h_ = 25.0;
  ThermalEnergy e_{};
};

}  // namespace mcsim

#endif  // MCSIM_THERMAL_HPP
