// The two-node thermal network (mcsim/thermal.hpp) against its closed
// forms: steady rises P R_th, the first-order and two-node transients, R(T)
// of copper and the feedback it gives, the defaults from a rating, the
// energy balance; and plugged into the PMSM power stage, R and flux
// following the temperatures during a run.
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "mcsim/pmsm_power_stage.hpp"
#include "mcsim/thermal.hpp"

namespace {

using mcsim::Status;
using mcsim::ThermalModel;
using mcsim::ThermalParams;

ThermalParams network(double alpha) {
  ThermalParams p;
  p.ambient_c = 25.0;
  p.r_wh_k_w = 0.8;
  p.r_ha_k_w = 2.2;
  p.c_w_j_k = 40.0;
  p.c_h_j_k = 400.0;
  p.t_ref_c = 25.0;
  p.alpha_cu_1_k = alpha;
  p.t_w0_c = p.t_h0_c = 25.0;
  return p;
}

// |i|^2 giving copper loss p_w with R_ref = r_ohm (at T_ref).
double isq_for(double p_w, double r_ohm) {
  return p_w / (1.5 * r_ohm);
}

TEST(SimThermal, SteadyRiseIsLossTimesThermalResistance) {
  // alpha = 0: a constant loss. T_w - T_a = P (R_wh + R_ha), T_h - T_a =
  // P R_ha. Run 30 slow time constants (~ C_h (R_wh + R_ha) = 1200 s): the
  // transient left is e^-30 of 60 K, below 1e-9 K; bound 1e-6 K.
  ThermalModel m;
  ASSERT_EQ(m.configure(network(0.0)), Status::kOk);
  const double p_w = 20.0, r = 0.1;
  for (int k = 0; k < 3600; ++k) m.advance(10.0, 10, isq_for(p_w, r), 0.0, r);
  EXPECT_NEAR(m.winding_c() - 25.0, p_w * (0.8 + 2.2), 1e-6);
  EXPECT_NEAR(m.housing_c() - 25.0, p_w * 2.2, 1e-6);
  EXPECT_NEAR(m.winding_c(), m.steady_winding_c(p_w, 0.0), 1e-6);
}

TEST(SimThermal, WindingAloneRisesWithItsFirstOrderTimeConstant) {
  // The housing's capacity made huge (it stays at ambient over the run):
  // T_w - T_a = P R_wh (1 - e^(-t / tau_w)), tau_w = C_w R_wh = 32 s.
  // Housing drift over 3 tau_w: P t / C_h = 20 * 96 / 1e9 K; RK4 at 0.1 s
  // steps: (h / tau)^5 ~ 1e-13. Bound 1e-6 K.
  ThermalParams p = network(0.0);
  p.c_h_j_k = 1.0e9;
  ThermalModel m;
  ASSERT_EQ(m.configure(p), Status::kOk);
  const double p_w = 20.0, tau = p.c_w_j_k * p.r_wh_k_w;
  for (int k = 1; k <= 960; ++k) {
    m.advance(0.1, 1, isq_for(p_w, 0.1), 0.0, 0.1);
    const double t = 0.1 * k;
    ASSERT_NEAR(m.winding_c() - 25.0, p_w * p.r_wh_k_w * (1.0 - std::exp(-t / tau)), 1e-6)
        << "t=" << t;
  }
}

TEST(SimThermal, TwoNodeTransientMatchesTheMatrixExponential) {
  // x = (T_w - T_a, T_h - T_a): x' = A x + b, A = C^-1 G; the closed form
  // x(t) = x_inf + V e^(L t) V^-1 (x0 - x_inf) from A's two real
  // eigenvalues. RK4 at 1 s steps against time constants of 24 s and 1300 s:
  // error ~ (h / 24)^4 * 60 K per step; bound 1e-5 K over 3000 s.
  const ThermalParams p = network(0.0);
  ThermalModel m;
  ASSERT_EQ(m.configure(p), Status::kOk);
  const double p_w = 15.0;
  Eigen::Matrix2d a;
  a << -1.0 / (p.c_w_j_k * p.r_wh_k_w), 1.0 / (p.c_w_j_k * p.r_wh_k_w),
      1.0 / (p.c_h_j_k * p.r_wh_k_w), -(1.0 / p.r_wh_k_w + 1.0 / p.r_ha_k_w) / p.c_h_j_k;
  const Eigen::Vector2d b(p_w / p.c_w_j_k, 0.0);
  const Eigen::Vector2d x_inf = -a.inverse() * b;
  Eigen::EigenSolver<Eigen::Matrix2d> es(a);
  const Eigen::Matrix2d v = es.eigenvectors().real();
  const Eigen::Vector2d lam = es.eigenvalues().real();
  ASSERT_LT(lam.maxCoeff(), 0.0);
  const Eigen::Vector2d c = v.inverse() * (-x_inf);  // x0 = 0
  for (int k = 1; k <= 3000; ++k) {
    m.advance(1.0, 1, isq_for(p_w, 0.2), 0.0, 0.2);
    const double t = k;
    const Eigen::Vector2d e(c(0) * std::exp(lam(0) * t), c(1) * std::exp(lam(1) * t));
    const Eigen::Vector2d x = x_inf + v * e;
    ASSERT_NEAR(m.winding_c() - 25.0, x(0), 1e-5) << "t=" << t;
    ASSERT_NEAR(m.housing_c() - 25.0, x(1), 1e-5) << "t=" << t;
  }
}

TEST(SimThermal, CopperResistanceFollowsTemperature) {
  ThermalParams p = network(0.00393);
  p.t_ref_c = 25.0;
  ThermalModel m;
  ASSERT_EQ(m.configure(p), Status::kOk);
  // R(T)/R(25) = (1 + a (T - 20)) / (1 + a 5): 1 at 25 C; at 125 C
  // 1.4127 / 1.01965 = 1.38548 (exact to rounding: 1e-12).
  EXPECT_NEAR(m.resistance_factor_at(25.0), 1.0, 1e-15);
  EXPECT_NEAR(m.resistance_factor_at(125.0), (1.0 + 0.00393 * 105.0) / (1.0 + 0.00393 * 5.0),
              1e-12);
  // The feedback R(T) gives at a constant current: P = g (1 + a (T_w - 20))
  // with g = 3/2 |i|^2 R_ref / (1 + a (T_ref - 20)); the steady state of
  // T_w = T_a + P R_tot is T_w = (T_a + g R_tot (1 - 20 a)) / (1 - g a R_tot).
  const double isq = 100.0, r_ref = 0.1, a = 0.00393, r_tot = 3.0;
  for (int k = 0; k < 3600; ++k) m.advance(10.0, 10, isq, 0.0, r_ref);
  const double g = 1.5 * isq * r_ref / (1.0 + a * 5.0);
  const double t_w = (25.0 + g * r_tot * (1.0 - 20.0 * a)) / (1.0 - g * a * r_tot);
  // Converged (bound as SteadyRise: 1e-6 K).
  EXPECT_NEAR(m.winding_c(), t_w, 1e-6);
  // Higher than without the feedback: 15 W at 25 C would give 70 C.
  EXPECT_GT(m.winding_c(), 25.0 + 15.0 * 3.0 + 5.0);
}

TEST(SimThermal, MagnetFluxFallsWithItsTemperature) {
  ThermalParams p = network(0.0);
  p.beta_magnet_1_k = -0.0012;
  p.magnet_winding_weight = 0.25;
  p.t_w0_c = 105.0;
  p.t_h0_c = 65.0;
  ThermalModel m;
  ASSERT_EQ(m.configure(p), Status::kOk);
  // T_m = 65 + 0.25 * 40 = 75 C; flux factor 1 - 0.0012 * 50 = 0.94.
  EXPECT_NEAR(m.magnet_c(), 75.0, 1e-12);
  EXPECT_NEAR(m.flux_factor(), 0.94, 1e-12);
}

TEST(SimThermal, RatingGivesTheRatedRiseAndTimeConstants) {
  mcsim::ThermalRating r;
  r.r_ohm = 0.05;
  r.i_rated_a = 20.0;
  r.rise_k = 80.0;
  r.ambient_c = 25.0;
  r.t_ref_c = 25.0;
  r.winding_share = 0.3;
  r.tau_winding_s = 20.0;
  r.tau_housing_s = 600.0;
  ThermalParams p;
  ASSERT_EQ(mcsim::thermal_from_rating(r, &p), Status::kOk);
  EXPECT_NEAR(p.c_w_j_k * p.r_wh_k_w, 20.0, 1e-12);
  EXPECT_NEAR(p.c_h_j_k * p.r_ha_k_w, 600.0, 1e-10);
  EXPECT_NEAR(p.r_wh_k_w / (p.r_wh_k_w + p.r_ha_k_w), 0.3, 1e-15);
  // At the rated current the winding settles exactly at ambient + rise,
  // R(T) included (bound 1e-6 K after 30 slow time constants).
  ThermalModel m;
  ASSERT_EQ(m.configure(p), Status::kOk);
  for (int k = 0; k < 2000; ++k) m.advance(10.0, 10, r.i_rated_a * r.i_rated_a, 0.0, r.r_ohm);
  EXPECT_NEAR(m.winding_c(), 105.0, 1e-6);
  // Bad ratings refused, output untouched.
  ThermalParams q = p;
  r.winding_share = 1.0;
  EXPECT_EQ(mcsim::thermal_from_rating(r, &q), Status::kBadThermal);
  EXPECT_EQ(q.r_wh_k_w, p.r_wh_k_w);
  // Heat capacity from masses (CRC Handbook specific heats).
  EXPECT_NEAR(mcsim::heat_capacity_j_k(0.1, 0.5, 0.2), 38.5 + 224.5 + 179.4, 1e-12);
}

TEST(SimThermal, EnergyBalancesAndIronLossesHeatTheHousing) {
  ThermalParams p = network(0.00393);
  p.iron_k_h_w_hz = 0.01;
  p.iron_k_e_w_hz2 = 2.0e-5;
  ThermalModel m;
  ASSERT_EQ(m.configure(p), Status::kOk);
  const double we = 2.0 * 3.14159265358979323846 * 500.0;  // 500 Hz electrical
  // P_fe = 0.01 * 500 + 2e-5 * 500^2 = 10 W.
  EXPECT_NEAR(m.iron_loss_w(we), 10.0, 1e-12);
  EXPECT_NEAR(m.iron_loss_w(-we), 10.0, 1e-12);
  for (int k = 0; k < 600; ++k) m.advance(1.0, 4, 50.0, we, 0.1);
  // Heat in = heat stored + heat to ambient, to rounding (the energies are
  // integrated by the same RK4 as the temperatures): 1e-9 relative.
  const auto& e = m.energy();
  EXPECT_NEAR(e.copper_j + e.iron_j, m.stored_j() + e.ambient_j, 1e-9 * (e.copper_j + e.iron_j));
  EXPECT_NEAR(e.iron_j, 6000.0, 1e-6);
  // The housing is warmer than with copper losses alone.
  ThermalModel m2;
  p.iron_k_h_w_hz = p.iron_k_e_w_hz2 = 0.0;
  ASSERT_EQ(m2.configure(p), Status::kOk);
  for (int k = 0; k < 600; ++k) m2.advance(1.0, 4, 50.0, we, 0.1);
  EXPECT_GT(m.housing_c(), m2.housing_c() + 1.0);
  // The friction that takes exactly the iron losses from the shaft:
  // B w^2 + T_c |w| = P_fe(p w) at every speed (rounding: 1e-12 W).
  double b = 0.0, tc = 0.0;
  ThermalModel m3;
  p.iron_k_h_w_hz = 0.01;
  p.iron_k_e_w_hz2 = 2.0e-5;
  ASSERT_EQ(m3.configure(p), Status::kOk);
  m3.iron_loss_friction(7, &b, &tc);
  for (const double wm : {1.0, 50.0, 400.0}) {
    EXPECT_NEAR(b * wm * wm + tc * wm, m3.iron_loss_w(7.0 * wm), 1e-12 * (1.0 + wm * wm));
  }
}

TEST(SimThermal, InvalidParametersAreRefused) {
  ThermalModel m;
  ThermalParams ok = network(0.00393);
  ASSERT_EQ(m.configure(ok), Status::kOk);
  ThermalParams p = ok;
  p.r_wh_k_w = 0.0;
  EXPECT_EQ(m.configure(p), Status::kBadThermal);
  p = ok;
  p.c_h_j_k = -1.0;
  EXPECT_EQ(m.configure(p), Status::kBadThermal);
  p = ok;
  p.beta_magnet_1_k = 0.01;
  EXPECT_EQ(m.configure(p), Status::kBadThermal);
  p = ok;
  p.ambient_c = NAN;
  EXPECT_EQ(m.configure(p), Status::kNotFinite);
  EXPECT_EQ(m.params().r_wh_k_w, ok.r_wh_k_w);  // kept
  // A stage with a bad thermal network is refused as a whole.
  mcsim::PmsmPowerStageParams sp;
  sp.thermal_enabled = true;
  sp.thermal = ok;
  sp.thermal.r_ha_k_w = -2.0;
  mcsim::PmsmPowerStage st;
  EXPECT_EQ(st.configure(sp), Status::kBadThermal);
}

TEST(SimThermal, PowerStageResistanceAndFluxFollowTheTemperatures) {
  // A constant d-axis voltage on a rotor held at th_e = 0 (Ld = Lq: no
  // torque from i_d; the rotor does not move): i_d = V / R(T_w) at steady
  // state, and the winding heats until T_w = T_a + 3/2 V^2 / R(T_w) R_tot.
  // Small capacities (time constants 0.02 s and 0.1 s, the slow mode about
  // 0.16 s) so 3 s of 20 kHz periods settle.
  mcsim::PmsmPowerStageParams sp;
  sp.motor.R_ohm = 0.5;
  sp.motor.Ld_h = sp.motor.Lq_h = 1.0e-4;
  sp.motor.flux_wb = 0.01;
  sp.motor.pole_pairs = 4;
  sp.motor.J_kgm2 = 1.0e-3;
  sp.vbus_v = 24.0;
  sp.thermal_enabled = true;
  ThermalParams& th = sp.thermal;
  th.ambient_c = 25.0;
  th.t_ref_c = 25.0;
  th.r_wh_k_w = 1.0;
  th.r_ha_k_w = 2.0;
  th.c_w_j_k = 0.02;
  th.c_h_j_k = 0.05;
  th.beta_magnet_1_k = -0.0012;
  th.magnet_winding_weight = 0.0;
  mcsim::PmsmPowerStage st;
  ASSERT_EQ(st.configure(sp), Status::kOk);
  ASSERT_NE(st.thermal(), nullptr);
  // v_alpha = 3 V: phase voltages (3, -1.5, -1.5) V about mid-bus.
  const double va = 3.0;
  const Eigen::Vector3d duty(0.5 + va / 24.0, 0.5 - 0.5 * va / 24.0, 0.5 - 0.5 * va / 24.0);
  for (int k = 0; k < 60000; ++k) ASSERT_EQ(st.advance(duty, true), Status::kOk);
  const ThermalModel& m = *st.thermal();
  // Closed-form steady state by fixed point (converges: the loop gain
  // P a R_tot / (R / R_ref) is about 0.2).
  const double a = 0.00393;
  double t_w = 25.0;
  for (int it = 0; it < 100; ++it) {
    const double r = 0.5 * (1.0 + a * (t_w - 20.0)) / (1.0 + a * 5.0);
    t_w = 25.0 + 1.5 * va * va / r * 3.0;
  }
  const double r_hot = 0.5 * (1.0 + a * (t_w - 20.0)) / (1.0 + a * 5.0);
  // 3 s is ~19 slow time constants (e^-19 of ~65 K: 4e-7 K); the period's
  // loss by the trapezoid of its ends: ~1e-9. Bound 1e-3 K.
  EXPECT_NEAR(m.winding_c(), t_w, 1e-3);
  // The plant's R and flux are the model's (exactly what it was set to).
  EXPECT_DOUBLE_EQ(st.plant().params().R_ohm, 0.5 * m.resistance_factor());
  EXPECT_DOUBLE_EQ(st.plant().params().flux_wb, 0.01 * m.flux_factor());
  EXPECT_LT(st.plant().params().flux_wb, 0.01 * (1.0 - 0.0012 * 10.0));  // the magnet is warm
  // The current is V / R(T_w): 1e-3 relative (R known to ~1e-5 from the
  // temperature bound; no motion, the d-axis current is DC).
  EXPECT_NEAR(st.rotor_frame_state()(0), va / r_hot, 1e-3 * va / r_hot);
  EXPECT_NEAR(st.rotor_frame_state()(3), 0.0, 1e-9);  // the rotor stayed at 0
  // The same stage without the model keeps R: the current is V / R_ref.
  sp.thermal_enabled = false;
  mcsim::PmsmPowerStage cold;
  ASSERT_EQ(cold.configure(sp), Status::kOk);
  EXPECT_EQ(cold.thermal(), nullptr);
  for (int k = 0; k < 2000; ++k) ASSERT_EQ(cold.advance(duty, true), Status::kOk);
  EXPECT_NEAR(cold.rotor_frame_state()(0), va / 0.5, 1e-6);
}

}  // namespace
