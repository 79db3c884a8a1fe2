// Processor-in-the-loop: the FOC current-step scenario (foc-current-step:
// iq 0 -> 2 A at 2 ms, id 0 -> -1 A at 15 ms, paper-002 test motor, 20 kHz)
// with the drive application running on the emulated STM32F405 (QEMU
// netduinoplus2, image mc_stm32f405_pil) and the plant on the host, against
// the software-in-the-loop run of the same scenario in this process.
//
// Expected: bit-identical trajectories. The drive's arithmetic is IEEE
// single precision with -ffp-contract=off and its own math (no libm), which
// tests/target shows to be bit-identical on x86-64 and the M4F; the link
// carries floats as bit patterns; the plant is the same host code in both
// runs. So every compared value must match to the bit (tolerance 0), and a
// one-ulp change of one gain on the target must be detected.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "foc_pil.hpp"
#include "pil_test_link.hpp"
#include "foc_sil.hpp"

namespace {

constexpr double kDuration_s = 0.03;  // the scenario's default duration

struct Sample {
  std::vector<double> plant;  // rotor-frame state after the period
  double duty[3];             // duties applied during the period
  float id_a, iq_a, vd_v, vq_v, theta_e_rad, omega_m_rad_s;
  uint32_t mode, faults;
};

mcsim::FocSilOptions scenario_options() {
  mcsim::FocSilOptions o;  // foc-current-step defaults
  o.bw_rad_s = 2.0 * 3.14159265358979323846 * 200.0;
  o.J_kgm2 = 0.1;
  return o;
}

// References of the scenario at time t.
void refs_at(double t, float* id, float* iq) {
  *id = (t >= 0.015) ? -1.0f : 0.0f;
  *iq = (t >= 0.002) ? 2.0f : 0.0f;
}

Sample capture(const hal_host::PmsmBoard& b) {
  Sample s{};
  const auto& x = b.rotor_frame_state();
  s.plant.assign(x.data(), x.data() + x.size());
  for (int k = 0; k < 3; ++k) s.duty[k] = b.duties_applied()(k);
  return s;
}

std::vector<Sample> run_sil(long n) {
  mcsim::FocSil sil(scenario_options());
  mc_drive_t& d = sil.drive();
  EXPECT_EQ(mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT), 0);
  std::vector<Sample> out;
  for (long k = 0; k < n; ++k) {
    float id, iq;
    refs_at(sil.board().t_s(), &id, &iq);
    EXPECT_EQ(mc_drive_set_current_ref(&d, id, iq), 0);
    sil.step();
    Sample s = capture(sil.board());
    s.id_a = d.tm.foc.id_a;
    s.iq_a = d.tm.foc.iq_a;
    s.vd_v = d.tm.foc.vd_v;
    s.vq_v = d.tm.foc.vq_v;
    s.theta_e_rad = d.tm.theta_e_rad;
    s.omega_m_rad_s = d.tm.omega_m_rad_s;
    s.mode = static_cast<uint32_t>(d.mode);
    s.faults = d.faults;
    out.push_back(s);
  }
  return out;
}

struct PilRun {
  std::vector<Sample> samples;
  std::vector<mc_pil_out_t> outs;
  mc_pil_ready_t ready{};
  int exit_status = -1;
};

PilRun run_pil(long n, const std::function<void(mc_drive_cfg_t&)>& tweak, const std::string& log) {
  PilRun r;
  mcsim::FocPil pil(scenario_options(), pil_test_link(log), tweak);
  r.ready = pil.ready();
  for (long k = 0; k < n; ++k) {
    mcsim::PilCommand c;
    c.set_mode = (k == 0);
    c.mode = MC_DRIVE_MODE_CURRENT;
    c.set_refs = true;
    refs_at(pil.board().t_s(), &c.id_ref_a, &c.iq_ref_a);
    const mc_pil_out_t& o = pil.step(c);
    Sample s = capture(pil.board());
    s.id_a = o.id_a;
    s.iq_a = o.iq_a;
    s.vd_v = o.vd_v;
    s.vq_v = o.vq_v;
    s.theta_e_rad = o.theta_e_rad;
    s.omega_m_rad_s = o.omega_m_rad_s;
    s.mode = o.mode;
    s.faults = o.faults;
    r.samples.push_back(s);
    r.outs.push_back(o);
  }
  r.exit_status = pil.finish();
  return r;
}

template <class T>
bool same_bits(T a, T b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

// Index of the first period whose samples differ in any bit, or -1.
long first_difference(const std::vector<Sample>& a, const std::vector<Sample>& b) {
  for (size_t k = 0; k < a.size() && k < b.size(); ++k) {
    const Sample& x = a[k];
    const Sample& y = b[k];
    bool same = x.plant.size() == y.plant.size() && x.mode == y.mode && x.faults == y.faults &&
                same_bits(x.id_a, y.id_a) && same_bits(x.iq_a, y.iq_a) &&
                same_bits(x.vd_v, y.vd_v) && same_bits(x.vq_v, y.vq_v) &&
                same_bits(x.theta_e_rad, y.theta_e_rad) &&
                same_bits(x.omega_m_rad_s, y.omega_m_rad_s);
    for (size_t j = 0; same && j < x.plant.size(); ++j) same = same_bits(x.plant[j], y.plant[j]);
    for (int j = 0; same && j < 3; ++j) same = same_bits(x.duty[j], y.duty[j]);
    if (!same) return static_cast<long>(k);
  }
  return (a.size() == b.size()) ? -1 : static_cast<long>(std::min(a.size(), b.size()));
}

long periods() {
  return std::lround(kDuration_s * scenario_options().pwm_hz);
}

TEST(PilFocCurrentStep, TrajectoryIsBitIdenticalToSil) {
  const long n = periods();
  const std::vector<Sample> sil = run_sil(n);
  const PilRun pil = run_pil(n, nullptr, "pil_foc.log");

  ASSERT_EQ(pil.exit_status, 0) << "target did not exit cleanly on END";
  // The clock set-up found no RCC (QEMU) and reported it instead of hanging.
  EXPECT_EQ(pil.ready.sysclk_hz, 0u);
  ASSERT_EQ(pil.samples.size(), sil.size());
  EXPECT_EQ(first_difference(sil, pil.samples), -1) << "first differing period";

  // The run did something: the q current followed its 2 A step (within 2 %,
  // far wider than the loop's steady-state ripple, far tighter than a loop
  // that is not running) and nothing faulted.
  EXPECT_EQ(pil.samples.back().faults, 0u);
  EXPECT_EQ(pil.samples.back().mode, static_cast<uint32_t>(MC_DRIVE_MODE_CURRENT));
  EXPECT_NEAR(pil.samples.back().iq_a, 2.0f, 0.04f);
  EXPECT_NEAR(pil.samples.back().id_a, -1.0f, 0.04f);

  // Where the code ran on the target: every fast step in the ADC interrupt
  // (exception 16 + 18), the slow step in PendSV (14) every 20th period, as
  // slow_loop_div = 20 schedules it in the SIL run.
  for (size_t k = 0; k < pil.outs.size(); ++k) {
    const mc_pil_out_t& o = pil.outs[k];
    ASSERT_EQ(o.ipsr_fast, 16u + 18u) << "period " << k;
    const bool slow_due = ((k + 1) % 20) == 0;
    ASSERT_EQ(o.slow_ran, slow_due ? 1u : 0u) << "period " << k;
    if (slow_due) {
      ASSERT_EQ(o.ipsr_slow, 14u) << "period " << k;
    }
    ASSERT_EQ(o.cmd_rc, 0) << "period " << k;
  }
}

TEST(PilFocCurrentStep, OneUlpGainChangeOnTheTargetIsDetected) {
  // The comparison must be able to fail: raise the q-axis proportional gain
  // on the target by one unit in the last place and expect a difference soon
  // after the iq step (2 ms = period 40), yet a small one (the change is
  // 1e-7 relative): no more than 1 mA in iq by 10 ms.
  const long n = 200;
  const std::vector<Sample> sil = run_sil(n);
  const PilRun pil = run_pil(
      n, [](mc_drive_cfg_t& c) { c.foc.kp_q_v_per_a = std::nextafter(c.foc.kp_q_v_per_a, 1e9f); },
      "pil_foc_ulp.log");
  ASSERT_EQ(pil.exit_status, 0);
  const long k = first_difference(sil, pil.samples);
  EXPECT_GE(k, 40);
  EXPECT_LT(k, n);
  EXPECT_NEAR(pil.samples.back().iq_a, sil.back().iq_a, 1e-3f);
}

}  // namespace
