// Issue 21 items 2 and 3 through the scenarios for any motor: regen-stop
// (DC link, regen current limit, brake chopper) and field-weakening (MTPA,
// voltage-feedback field weakening).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "mc_drive.h"
#include "motor_library.hpp"

namespace mcsim {
namespace {

using testlib::Case;
using testlib::files;

std::map<std::string, double> run(const std::string& scen, const MotorFiles& f,
                                  const testlib::Sets& sets, const std::string& tag) {
  return testlib::run_scenario(scen, f, sets, tag);
}

class RegenStop : public ::testing::TestWithParam<Case> {};

// A full-speed stop at the configured deceleration never trips on
// over-voltage, with and without the brake resistor; the energy balance
// over the stop (source + kinetic + magnetic = resistor + source R +
// windings and friction + capacitor) closes within 1 % of the kinetic
// energy; the resistor takes energy only when fitted.
TEST_P(RegenStop, FullSpeedStopBelowTripEnergyBalanced) {
  const MotorFiles f = files(GetParam());
  for (const char* brake : {"on", "off"}) {
    SCOPED_TRACE(std::string("brake=") + brake);
    const auto r = run("regen-stop", f, {{"brake", brake}}, brake);
    EXPECT_EQ(r.at("faults"), 0.0);
    EXPECT_LT(r.at("vbus_peak_v"), r.at("vbus_trip_v"));
    EXPECT_LT(std::abs(r.at("energy_balance_rel_err")), 0.01);
    EXPECT_TRUE(std::isfinite(r.at("stop_time_s")));
    if (std::string(brake) == "on") {
      EXPECT_GE(r.at("brake_energy_j"), 0.0);
    } else {
      EXPECT_EQ(r.at("brake_energy_j"), 0.0);
    }
  }
}

// With the resistor the stop follows the reference ramp (within 10 %),
// and the resistor takes most of the kinetic energy on the motors whose
// braking power lifts the bus above the chopper's threshold.
TEST(RegenStopBrake, ResistorTakesTheEnergyAndTheRampHolds) {
  const auto r =
      run("regen-stop", files({"odrive-d5065", "odrive-v36-24v"}), {{"brake", "on"}}, "");
  EXPECT_NEAR(r.at("stop_time_s"), r.at("stop_time_ramp_s"), 0.1 * r.at("stop_time_ramp_s"));
  EXPECT_GT(r.at("brake_energy_j"), 0.5 * r.at("kinetic_j"));
}

// Field weakening on the salient (IPM, Lq/Ld = 2) motor: MTPA torque per
// ampere within 1 % of the analytic optimum at 25..100 % rated current (and
// above the id = 0 torque constant), then a speed ramp to 2.5x base speed
// that holds without fault, the current inside its limit, the d current
// above the demagnetisation bound.
TEST(FieldWeakening, SalientMtpaAndRampTo2p5xBase) {
  const auto r = run("field-weakening", files({"ipm-representative-48v", ""}), {}, "");
  EXPECT_EQ(r.at("faults"), 0.0);
  EXPECT_LT(r.at("mtpa_rel_err_max"), 0.01);
  EXPECT_GT(r.at("mtpa_t_per_a_over_kt_max"), 1.05);
  EXPECT_NEAR(r.at("target_over_base"), 2.5, 1e-9);
  EXPECT_NEAR(r.at("omega_final_rad_s"), r.at("target_speed_rad_s"),
              0.02 * r.at("target_speed_rad_s"));
  EXPECT_LE(r.at("i_peak_a"), 1.05 * r.at("i_limit_a"));
  EXPECT_GE(r.at("id_min_a"), r.at("id_demag_bound_a") - 0.05 * r.at("i_limit_a"));
  // Past the point where the rectifier would conduct on a loss of control.
  EXPECT_GT(r.at("target_speed_rad_s"), r.at("omega_uncontrolled_gen_rad_s"));
}

// Non-salient motors: the MTPA d current is zero (what the loop leaves is
// current-loop noise, below 1 % of rated), the torque per ampere is kt.
TEST(FieldWeakening, NonSalientUnaffected) {
  const MotorFiles f = files({"odrive-d5065", "odrive-v36-24v"});
  const auto r = run("field-weakening", f, {}, "");
  EXPECT_EQ(r.at("faults"), 0.0);
  EXPECT_LT(r.at("mtpa_id_abs_max_a"), 0.01 * f.motor.i_rated_a);
  EXPECT_LT(r.at("mtpa_rel_err_max"), 0.01);
  EXPECT_NEAR(r.at("omega_final_rad_s"), r.at("target_speed_rad_s"),
              0.02 * r.at("target_speed_rad_s"));
}

// Active short circuit (the asc_enable parameter) on the salient motor at
// 2.5x base speed, where its line-to-line back-EMF peak exceeds the 48 V
// bus, on a supply that cannot sink current: the encoder lost (an ENCODER
// fault, one of MC_DRIVE_ASC_FAULTS) with the bridge opened
// pumps the bus through the diodes past its trip; with the short the bus
// stays at the supply and the rotor is braked, as long as the short's
// transient current stays below the over-current trip: it settles towards
// flux / Ld = 100 A but overshoots from the field-weakening operating point
// (by up to |v| / (omega_e Ld) = 50 A here). The board's 125 A sensing puts
// the trip at 122.5 A, which the transient crosses: the drive then opens
// the bridge (the over-current rule) and the bus is pumped after all. With
// 250 A sensing and the trip at 245 A (switches rated for ~2 flux / Ld, as
// the app README asks) the short holds.
TEST(ActiveShortCircuit, FaultAtTopSpeedKeepsTheBusBelowTheTrip) {
  const MotorFiles f = files({"ipm-representative-48v", ""});
  const auto off = run("field-weakening", f, {{"fault", "1"}, {"asc", "off"}}, "asc_off");
  const auto on = run("field-weakening", f,
                      {{"fault", "1"}, {"asc", "on"}, {"fault_i_sense_max_a", "250"}}, "asc_on");
  const auto stock = run("field-weakening", f, {{"fault", "1"}, {"asc", "on"}}, "asc_stock");
  // The case the short is for: back-EMF above the bus when the fault comes.
  EXPECT_GT(off.at("fault_emf_over_vbus"), 1.0);
  EXPECT_GT(on.at("fault_emf_over_vbus"), 1.0);
  // Without it the diodes rectify the back-EMF into the bus: beyond the trip.
  EXPECT_GT(off.at("fault_vbus_peak_v"), off.at("fault_vbus_trip_v"));
  EXPECT_EQ(off.at("fault_asc_time_s"), 0.0);
  // With it the bus never rises above the supply by more than 2 % (the
  // ripple of the PWM periods before the short; measured below it).
  EXPECT_LT(on.at("fault_vbus_peak_v"), on.at("fault_vbus_trip_v"));
  EXPECT_LT(on.at("fault_vbus_peak_v"), 1.02 * on.at("fault_vbus_before_v"));
  // The short holds for the whole run (50 ms, to within one period).
  EXPECT_GT(on.at("fault_asc_time_s"), 0.05 - 1e-4);
  // Its current stays below the trip, and it brakes.
  EXPECT_LT(on.at("fault_i_phase_peak_a"), on.at("fault_i_trip_a"));
  EXPECT_LT(on.at("fault_torque_min_nm"), 0.0);
  EXPECT_LT(on.at("fault_omega_end_rad_s"), on.at("fault_omega_m_rad_s"));
  // On the stock board the transient trips the over-current and the bridge
  // opens (the fallback), so the bus is pumped: what the README warns of.
  EXPECT_GT(stock.at("fault_i_phase_peak_a"), stock.at("fault_i_trip_a"));
  EXPECT_NE(static_cast<uint32_t>(stock.at("fault_bits")) & MC_DRIVE_FAULT_OVERCURRENT, 0u);
  EXPECT_LT(stock.at("fault_asc_time_s"), 0.05);
}

INSTANTIATE_TEST_SUITE_P(Library, RegenStop, ::testing::ValuesIn(testlib::library()),
                         testlib::case_name);

}  // namespace
}  // namespace mcsim
