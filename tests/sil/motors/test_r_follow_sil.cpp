// Issue 33 item 2: the drive's R follows the winding estimate
// (winding_r_follow, firmware/app/drive/mc_drive_thermal.h), measured on a
// hot winding through the generic scenarios' plant_thermal keys: the
// plant's winding starts at 120 C (R 37 % above the table's r_ohm, taken
// at 25 C; the housing and the magnet at the ambient: a winding just after
// an overload), read by a motor thermistor, from which the drive's
// estimate starts. The D5065 on the 24 V ODrive v3.6: its electrical pole
// R/L (2500 rad/s) is near the current loop's bandwidth (1920 rad/s), so
// ki = R bw matters, and at low speed under load the observer's voltage
// model (it integrates v - R i) carries a large R i against a small
// back-EMF.
//
// Each case runs with R following (r_follow=1) and without (0) and records
// both (mc_record, quoted in firmware/app/README.md by tools/docs/gen_docs.py).
#include <gtest/gtest.h>

#include <map>
#include <string>

#include "mc_record.hpp"
#include "motor_library.hpp"

namespace mcsim {
namespace {

std::map<std::string, double> run(const std::string& scen, testlib::Sets s, const char* follow,
                                  std::map<std::string, std::string>* txt) {
  s.push_back({"plant_thermal", "on"});
  s.push_back({"t_winding0_c", "120"});
  s.push_back({"r_follow", follow});
  return testlib::run_scenario(scen, testlib::files({"odrive-d5065", "odrive-v36-24v"}), s,
                               std::string(".f") + follow, txt);
}

// Sensorless at 100 rad/s (twice the hand-over speed, a fifth of rated),
// 0.3 rated torque from standstill and a step to 0.9. Bound with R
// following: 0.01 rad, five times the same run's on a cold winding (0.0021
// rad, sensorless-speed-step without plant_thermal): the estimate drifts
// 3 K from the plant's winding over the run (it starts the housing node hot
// too), 1 % of R. Without: above 0.05 rad (measured 0.22 rad, the
// scenario's own verdict fails it: "angle error too large"), so the
// bound cannot hold by accident. The speed error at the end stays small
// both ways (the speed loop absorbs the angle error): recorded, not bounded.
TEST(RFollow, SensorlessAngleOnAHotWinding) {
  const testlib::Sets s = {{"speed_rad_s", "100"}, {"load_frac", "0.3"}, {"load_step_frac", "0.6"}};
  std::map<std::string, std::string> t1, t0;
  const auto on = run("sensorless-speed-step", s, "1", &t1);
  const auto off = run("sensorless-speed-step", s, "0", &t0);
  EXPECT_EQ(t1.at("verdict"), "pass") << t1.at("verdict_detail");
  EXPECT_EQ(on.at("faults"), 0.0);
  EXPECT_GT(on.at("t_winding_c"), 110.0);  // still hot at the end: the case is what it claims
  EXPECT_LE(on.at("angle_err_max_rad"), 0.01);
  EXPECT_GT(off.at("angle_err_max_rad"), 0.05);
  mc_record("sls.on.angle_err_max_rad", on.at("angle_err_max_rad"), 0.01);
  mc_record("sls.off.angle_err_max_rad", off.at("angle_err_max_rad"));
  mc_record("sls.on.angle_err_rms_rad", on.at("angle_err_rms_rad"));
  mc_record("sls.off.angle_err_rms_rad", off.at("angle_err_rms_rad"));
  mc_record("sls.on.omega_err_max_end_rad_s", on.at("omega_err_max_end_rad_s"));
  mc_record("sls.off.omega_err_max_end_rad_s", off.at("omega_err_max_end_rad_s"));
  mc_record("sls.t_winding_end_c", on.at("t_winding_c"));
  mc_record("sls.t_winding_est_end_c", on.at("t_winding_est_c"));
}

// The current loop's step (current-step): ki = R bw with R following keeps
// the 10-90 % rise within the scenario's [0.75, 1.25] of the first-order
// design; with the cold R the PI's zero misses the hot plant's pole and
// the rise is slower: above 1.25 (measured 1.38), the scenario's verdict
// fails it.
TEST(RFollow, CurrentStepOnAHotWinding) {
  std::map<std::string, std::string> t1, t0;
  const auto on = run("current-step", {}, "1", &t1);
  const auto off = run("current-step", {}, "0", &t0);
  EXPECT_EQ(t1.at("verdict"), "pass") << t1.at("verdict_detail");
  EXPECT_EQ(t0.at("verdict"), "rise time off design");
  for (const char* k : {"iq_rise_time_ratio", "id_rise_time_ratio"}) {
    EXPECT_GE(on.at(k), 0.75) << k;
    EXPECT_LE(on.at(k), 1.25) << k;
    EXPECT_GT(off.at(k), 1.25) << k;
  }
  mc_record("cur.on.iq_rise_time_ratio", on.at("iq_rise_time_ratio"), 1.25);
  mc_record("cur.off.iq_rise_time_ratio", off.at("iq_rise_time_ratio"));
  mc_record("cur.on.iq_settle_time_s", on.at("iq_settle_time_s"));
  mc_record("cur.off.iq_settle_time_s", off.at("iq_settle_time_s"));
}

}  // namespace
}  // namespace mcsim
