// pi2d-motor through the drive: the PI^2D plug-in and the cascade on the
// simulated 0.3 kW motor, reduced run (ramp up, rated-load step, no ramp
// down) to keep the test short.
#include <cmath>

#include <gtest/gtest.h>

#include "scenarios/pi2d_sil.hpp"

namespace {

TEST(Pi2dMotor, TracksRatedSpeedAndRejectsRatedLoadThroughTheDrive) {
  mcsim::pi2d::MotorOptions o;
  o.ramp_s = 0.2;
  o.t_load_s = 0.4;
  o.t_down_s = 10.0;  // no ramp down in this reduced run
  const double w_r = 1000.0 * 2.0 * 3.14159265358979 / 60.0;
  double w_end = 0.0, nu_end = 0.0;
  const mcsim::pi2d::MotorMetrics m =
      mcsim::pi2d::run_motor(o, true, 0.7, [&](const mcsim::pi2d::MotorSample& s) {
        w_end = s.omega_m;
        nu_end = s.nu;
      });
  EXPECT_EQ(m.faults, 0u);
  // At rated speed 0.3 s after the rated-load step: within 1 % (the
  // scenario's settling band); measured error 0.02 rad/s.
  EXPECT_NEAR(w_end, w_r, 0.01 * w_r);
  // The adaptive term has taken up the load: nu -> tau_L + B w = 3.01 N m
  // (measured 2.9 at 0.3 s after the step; 10 % band for the remaining
  // transient of the slow nu).
  EXPECT_NEAR(nu_end, 3.0 + 1e-4 * w_r, 0.3);
  // Inside the current limit (9 A), and the dip within what the linear
  // design gives (load / (J * 3 wn) ~ 17 rad/s upper estimate).
  EXPECT_LT(m.peak_current_a, 9.0 + 0.5);
  EXPECT_LT(m.load_dip_rad_s, 17.0);
  EXPECT_LT(m.settle_after_load_s, 0.2);

  // The cascade under the same conditions also settles (sanity of the
  // comparison), with a larger dip (no double-integral action).
  const mcsim::pi2d::MotorMetrics c =
      mcsim::pi2d::run_motor(o, false, 0.7, [](const mcsim::pi2d::MotorSample&) {});
  EXPECT_EQ(c.faults, 0u);
  EXPECT_GT(c.load_dip_rad_s, m.load_dip_rad_s);
  EXPECT_LT(c.settle_after_load_s, 0.25);
}

}  // namespace
