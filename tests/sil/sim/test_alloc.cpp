// The simulation loop (delay buffer, inverter, plant integration, sensors)
// must not touch the heap. Global operator new is replaced in this test
// executable to count allocations while the loop runs.
#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <new>
#include <vector>
#include <cmath>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "mcsim/mcsim.hpp"
#include "mcsim/pmsm_rotor_frame.hpp"

namespace {
std::atomic<long> g_new_calls{0};
}  // namespace

void* operator new(std::size_t size) {
  g_new_calls.fetch_add(1, std::memory_order_relaxed);
  void* p = std::malloc(size == 0U ? 1U : size);
  if (p == nullptr) {
    throw std::bad_alloc();
  }
  return p;
}
void* operator new[](std::size_t size) {
  return operator new(size);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t /*size*/) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t /*size*/) noexcept {
  std::free(p);
}

namespace {

TEST(SimAlloc, ControlLoopDoesNotAllocate) {
  mcsim::PmsmParams mp;
  mp.load = mcsim::load_step(0.0, 0.01, 0.02);
  mcsim::PmsmAb motor;
  ASSERT_EQ(motor.configure(mp), mcsim::Status::kOk);
  mcsim::Inverter3Ph inv;
  mcsim::InverterParams ip;
  ip.t_dead_s = 0.5e-6;
  ASSERT_EQ(inv.configure(ip), mcsim::Status::kOk);
  mcsim::CurrentSensorParams cp;
  cp.noise_rms_a = 0.05;
  mcsim::CurrentSensor adc;
  ASSERT_EQ(adc.configure(cp), mcsim::Status::kOk);
  mcsim::Encoder enc;
  ASSERT_EQ(enc.configure(mcsim::EncoderParams{}), mcsim::Status::kOk);
  mcsim::InputDelay<Eigen::Vector3d, 3> delay;
  ASSERT_EQ(delay.configure(1U, Eigen::Vector3d::Constant(0.5)), mcsim::Status::kOk);

  mcsim::PmsmAb::State x = mcsim::PmsmAb::State::Zero();
  // The SIL board's plant and integrator, driven alongside.
  mcsim::PmsmRotorFrame rf;
  ASSERT_EQ(rf.configure(mp), mcsim::Status::kOk);
  mcsim::PmsmRotorFrame::State xr = rf.make_state(0.0, 0.0, 0.0, 0.0);
  const double period_s = ip.t_pwm_s;
  double checksum = 0.0;
  const long before = g_new_calls.load();
  for (int k = 0; k < 2000; ++k) {
    const double t_s = k * period_s;
    const Eigen::Vector3d i_abc = mcsim::inverse_clarke(x.head<2>());
    const double ia_meas = adc.sample_a(i_abc(0));
    const mcsim::EncoderReading r = enc.sample(x(3));
    // Open-loop "controller": rotating duty vector.
    const double th = 2.0 * 3.14159265358979 * 50.0 * t_s;
    const Eigen::Vector3d duty_new(0.5 + 0.1 * std::cos(th), 0.5 + 0.1 * std::cos(th - 2.0944),
                                   0.5 + 0.1 * std::cos(th + 2.0944));
    const Eigen::Vector3d duty = delay.push(duty_new);
    const mcsim::PmsmAb::Input u = inv.alpha_beta_v(duty, 24.0, i_abc);
    ASSERT_EQ(mcsim::advance_zoh(motor, u, t_s, period_s, 4, &x), mcsim::Status::kOk);
    ASSERT_EQ(rf.advance_zoh(u, t_s, period_s, 4, &xr), mcsim::Status::kOk);
    checksum += ia_meas + r.angle_rad;
  }
  const long after = g_new_calls.load();
  EXPECT_EQ(after - before, 0);  // exact: not a single heap allocation
  EXPECT_TRUE(std::isfinite(checksum));
  EXPECT_GT(std::fabs(x(2)), 1.0);  // the loop really drove the motor
  EXPECT_GT(std::fabs(xr(2)), 1.0);
}

TEST(SimAlloc, PowerStagesDoNotAllocate) {
  // Every path of the power stages: switching, diode freewheel, open phase
  // switching and freewheeling; the stepper's bridges on and off.
  mcsim::PmsmPowerStageParams pp;
  pp.motor.J_kgm2 = 1.0e-4;
  pp.inverter.t_dead_s = 0.5e-6;
  mcsim::PmsmPowerStage pmsm;
  ASSERT_EQ(pmsm.configure(pp), mcsim::Status::kOk);
  mcsim::StepperPowerStage stepper;
  ASSERT_EQ(stepper.configure(mcsim::StepperPowerStageParams{}), mcsim::Status::kOk);
  const long before = g_new_calls.load();
  for (int k = 0; k < 2000; ++k) {
    if (k == 1000) {
      ASSERT_EQ(pmsm.set_open_phase(1), mcsim::Status::kOk);
    }
    const bool on = (k % 500) < 250;
    ASSERT_EQ(pmsm.advance(Eigen::Vector3d(0.6, 0.4, 0.5), on), mcsim::Status::kOk);
    ASSERT_EQ(stepper.advance(Eigen::Vector2d(0.3, -0.2), on), mcsim::Status::kOk);
  }
  EXPECT_EQ(g_new_calls.load() - before, 0);  // exact: not a single heap allocation
  EXPECT_TRUE(std::isfinite(pmsm.rotor_frame_state().sum()));
  EXPECT_TRUE(std::isfinite(stepper.state().sum()));
}

TEST(SimAlloc, NewPlantModelsDoNotAllocate) {
  // Cogging and the thermal network in the PMSM stage, two stages on one DC
  // link, the stepper's common-leg bridge on and off, the Hall sensors and
  // the SPI encoders' frames (with noise and line errors).
  mcsim::PmsmPowerStageParams pp;
  pp.motor.J_kgm2 = 1.0e-4;
  pp.motor.cogging.slots = 12;
  pp.motor.cogging.amplitude_nm = 0.01;
  pp.thermal_enabled = true;
  mcsim::PmsmPowerStage ax[2];
  ASSERT_EQ(ax[0].configure(pp), mcsim::Status::kOk);
  ASSERT_EQ(ax[1].configure(pp), mcsim::Status::kOk);
  mcsim::DcLink link;
  ASSERT_EQ(link.configure(mcsim::DcLinkParams{}), mcsim::Status::kOk);
  mcsim::StepperCommonLegStage stepper;
  ASSERT_EQ(stepper.configure(mcsim::StepperCommonLegStageParams{}), mcsim::Status::kOk);
  mcsim::HallSensors hall;
  ASSERT_EQ(hall.configure(mcsim::HallParams{}), mcsim::Status::kOk);
  mcsim::As5047pParams ap;
  ap.noise_rms_rad = 1.0e-3;
  ap.line.miso_error_rate = 0.1;
  mcsim::As5047p as;
  ASSERT_EQ(as.configure(ap), mcsim::Status::kOk);
  mcsim::Ma732Params mp;
  mp.line.miso_error_rate = 0.1;
  mcsim::Ma732 ma;
  ASSERT_EQ(ma.configure(mp), mcsim::Status::kOk);
  double checksum = 0.0;
  const long before = g_new_calls.load();
  for (int k = 0; k < 2000; ++k) {
    const bool on = (k % 500) < 250;
    ASSERT_EQ(ax[0].advance(Eigen::Vector3d(0.6, 0.4, 0.5), true), mcsim::Status::kOk);
    ASSERT_EQ(ax[1].advance(Eigen::Vector3d(0.4, 0.6, 0.5), true), mcsim::Status::kOk);
    const double i_inv[2] = {1.0, -0.5};
    ASSERT_EQ(link.advance_loads(50.0e-6, 4, i_inv, 2, 0.0), mcsim::Status::kOk);
    ASSERT_EQ(stepper.advance(Eigen::Vector3d(0.7, 0.4, 0.2), on), mcsim::Status::kOk);
    const double t = k * 50.0e-6, th = ax[0].rotor_frame_state()(3);
    const double w = ax[0].rotor_frame_state()(2);
    ASSERT_EQ(as.observe(t, th, w), mcsim::Status::kOk);
    ASSERT_EQ(ma.observe(t, th, w), mcsim::Status::kOk);
    checksum += hall.sample(th) + as.transfer(0xFFFF, t) + ma.transfer(0x0000, t, 17);
  }
  EXPECT_EQ(g_new_calls.load() - before, 0);  // exact: not a single heap allocation
  EXPECT_TRUE(std::isfinite(checksum + ax[0].thermal()->winding_c() + link.v()));
}

TEST(SimAlloc, CounterSeesAllocations) {
  // Proves the counter works, so the test above can fail.
  const long before = g_new_calls.load();
  auto* p = new std::vector<int>(100);  // NOLINT: deliberate heap use
  delete p;
  EXPECT_GE(g_new_calls.load() - before, 2);
}

}  // namespace
