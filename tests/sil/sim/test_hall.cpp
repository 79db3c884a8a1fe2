// Hall sensors (mcsim/hall.hpp): the six states against the true
// electrical angle, the edges where their placement errors and the
// hysteresis put them in either direction, the 60-degree placement, the
// power-up state, and the illegal states only under a fault.
#include <cmath>
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "mcsim/hall.hpp"
#include "sim_test_util.hpp"

namespace {

using mcsim::HallFault;
using mcsim::HallParams;
using mcsim::HallSensors;
using mcsim::HallSpacing;
using mcsim::Status;
using mcsim_test::kPi;

double wrap(double x) {
  const double w = std::fmod(x, 2.0 * kPi);
  return w < 0.0 ? w + 2.0 * kPi : w;
}

// The state each 60-degree sector from phi_A holds, written out from the
// definition (sensor k high on [phi_k, phi_k + pi)), not from the model.
const std::uint8_t kStates120[6] = {5, 1, 3, 2, 6, 4};
const std::uint8_t kStates60[6] = {1, 3, 7, 6, 4, 0};

TEST(SimHall, IdealSensorsGiveTheTrueSectorAndNeverAnIllegalState) {
  for (const HallSpacing sp : {HallSpacing::k120, HallSpacing::k60}) {
    HallParams p;
    p.pole_pairs = 4;
    p.spacing = sp;
    p.offset_e_rad = 0.3;
    HallSensors h;
    ASSERT_EQ(h.configure(p), Status::kOk);
    const std::uint8_t* table = (sp == HallSpacing::k120) ? kStates120 : kStates60;
    const double step = 1.0e-4;  // rad mechanical: 4e-4 rad electrical
    int changes = 0;
    std::uint8_t prev = h.sample(0.0);
    for (int k = 1; k <= 40000; ++k) {  // 4 rad: 16 rad electrical
      const double th = k * step;
      const std::uint8_t s = h.sample(th);
      const double from_a = wrap(4.0 * th - 0.3);
      const int sector = static_cast<int>(from_a / (kPi / 3.0));
      // Away from the sector boundaries by more than a step the state is
      // the sector's.
      const double to_edge = std::fmod(from_a, kPi / 3.0);
      if (to_edge > 4.0 * step && kPi / 3.0 - to_edge > 4.0 * step) {
        ASSERT_EQ(s, table[sector]) << "th_e from A " << from_a;
      }
      if (sp == HallSpacing::k120) {
        ASSERT_TRUE(s != 0 && s != 7);
      } else {
        ASSERT_TRUE(s != 2 && s != 5);
      }
      if (s != prev) ++changes;
      prev = s;
    }
    // 16 rad electrical: 6 changes per 2 pi: 15 or 16 (by the start).
    EXPECT_GE(changes, 15);
    EXPECT_LE(changes, 16);
  }
}

// The electrical angles where sensor k changes over a sweep.
struct Edges {
  std::vector<double> rise[3], fall[3];
};
Edges sweep(HallSensors* h, double from_e, double to_e, int pp) {
  Edges e;
  const int n = 200000;
  std::uint8_t prev = 0;
  for (int j = 0; j <= n; ++j) {
    const double th_e = from_e + (to_e - from_e) * j / n;
    const std::uint8_t s = h->sample(th_e / pp);
    if (j > 0) {
      for (int k = 0; k < 3; ++k) {
        const bool a = ((prev >> k) & 1U) != 0U, b = ((s >> k) & 1U) != 0U;
        if (!a && b) e.rise[k].push_back(wrap(th_e));
        if (a && !b) e.fall[k].push_back(wrap(th_e));
      }
    }
    prev = s;
  }
  return e;
}

double ang_dist(double a, double b) {
  const double d = wrap(a - b);
  return std::min(d, 2.0 * kPi - d);
}

TEST(SimHall, EdgesSitWherePlacementErrorsAndHysteresisPutThem) {
  HallParams p;
  p.pole_pairs = 2;
  p.offset_e_rad = 0.1;
  const double errs[6] = {0.05, -0.03, -0.08, 0.02, 0.0, 0.06};
  for (int k = 0; k < 6; ++k) p.edge_error_e_rad[k] = errs[k];
  p.hysteresis_e_rad = 0.04;
  HallSensors h;
  ASSERT_EQ(h.configure(p), Status::kOk);
  const double step = 4.0 * kPi / 200000.0;  // the sweep's step (electrical)
  // Forward: a rising edge at phi_k + e_rise + h/2, a falling one at
  // phi_k + pi + e_fall + h/2 (within a step).
  h.reset(-0.5 / 2.0);
  const Edges fw = sweep(&h, -0.5, 4.0 * kPi - 0.5, 2);
  // Backward: each edge at its position - h/2; rising and falling swap
  // (moving backward the sensor turns on at its falling edge).
  const Edges bw = sweep(&h, 4.0 * kPi - 0.5, -0.5, 2);
  for (int k = 0; k < 3; ++k) {
    const double phi = 0.1 + k * 2.0 * kPi / 3.0;
    const double r = phi + errs[2 * k], f = phi + kPi + errs[2 * k + 1];
    EXPECT_NEAR(h.edge_e_rad(k, true), wrap(r), 1e-12);
    EXPECT_NEAR(h.edge_e_rad(k, false), wrap(f), 1e-12);
    ASSERT_EQ(fw.rise[k].size(), 2U) << k;
    ASSERT_EQ(fw.fall[k].size(), 2U) << k;
    ASSERT_EQ(bw.rise[k].size(), 2U) << k;
    ASSERT_EQ(bw.fall[k].size(), 2U) << k;
    for (int j = 0; j < 2; ++j) {
      EXPECT_LE(ang_dist(fw.rise[k][j], r + 0.02), step + 1e-12) << k;
      EXPECT_LE(ang_dist(fw.fall[k][j], f + 0.02), step + 1e-12) << k;
      EXPECT_LE(ang_dist(bw.fall[k][j], r - 0.02), step + 1e-12) << k;
      EXPECT_LE(ang_dist(bw.rise[k][j], f - 0.02), step + 1e-12) << k;
    }
  }
}

TEST(SimHall, PowerUpStateIsTheRegionsWithoutHysteresis) {
  HallParams p;
  p.pole_pairs = 5;
  p.hysteresis_e_rad = 0.2;
  HallSensors h;
  ASSERT_EQ(h.configure(p), Status::kOk);
  // 0.05 rad electrical past A's falling edge at pi: inside the band, a
  // sensor coming from above would still be high; at power-up it is low.
  const double th_e = kPi + 0.05;
  h.reset(th_e / 5.0);
  EXPECT_EQ(h.sample(th_e / 5.0), 2);  // sector 3 (180..240): B only
  // Moving back into the band from there keeps it (hysteresis), leaving
  // the band below the edge turns A on.
  EXPECT_EQ(h.sample((kPi - 0.05) / 5.0), 2);
  EXPECT_EQ(h.sample((kPi - 0.15) / 5.0), 3);
}

TEST(SimHall, IllegalStatesOnlyUnderAFault) {
  HallParams p;
  p.pole_pairs = 1;
  HallSensors h;
  ASSERT_EQ(h.configure(p), Status::kOk);
  std::vector<int> count(8, 0);
  auto turn = [&]() {
    std::fill(count.begin(), count.end(), 0);
    for (int k = 0; k < 3600; ++k) ++count[h.sample(2.0 * kPi * k / 3600.0)];
  };
  turn();
  EXPECT_EQ(count[0] + count[7], 0);
  ASSERT_EQ(h.set_fault(HallFault::kAllHigh), Status::kOk);  // connector off: pull-ups
  turn();
  EXPECT_EQ(count[7], 3600);
  ASSERT_EQ(h.set_fault(HallFault::kAllLow), Status::kOk);  // sensor supply lost
  turn();
  EXPECT_EQ(count[0], 3600);
  ASSERT_EQ(h.set_fault(HallFault::kStuckLow, 0), Status::kOk);  // A's wire broken, pulled low
  turn();
  // A stuck low: the sector where only A is high reads 000 (60 degrees),
  // and no state with A set appears.
  EXPECT_NEAR(count[0], 600, 2);
  EXPECT_EQ(count[1] + count[3] + count[5] + count[7], 0);
  ASSERT_EQ(h.set_fault(HallFault::kStuckHigh, 2), Status::kOk);
  turn();
  EXPECT_NEAR(count[7], 600, 2);  // C stuck high: A and B high together -> 111
  EXPECT_EQ(h.set_fault(HallFault::kStuckHigh, 3), Status::kBadSensor);
  EXPECT_EQ(h.fault(), HallFault::kStuckHigh);  // unchanged
  ASSERT_EQ(h.set_fault(HallFault::kNone), Status::kOk);
  turn();
  EXPECT_EQ(count[0] + count[7], 0);
}

TEST(SimHall, InvalidParametersAreRefused) {
  HallSensors h;
  HallParams p;
  p.edge_error_e_rad[3] = 0.6;  // > 30 degrees: edges could swap
  EXPECT_EQ(h.configure(p), Status::kBadSensor);
  p.edge_error_e_rad[3] = 0.4;
  p.hysteresis_e_rad = 0.3;  // 0.4 + 0.15 > 30 degrees
  EXPECT_EQ(h.configure(p), Status::kBadSensor);
  p.hysteresis_e_rad = -0.1;
  EXPECT_EQ(h.configure(p), Status::kBadSensor);
  p.hysteresis_e_rad = 0.0;
  p.pole_pairs = 0;
  EXPECT_EQ(h.configure(p), Status::kBadPolePairs);
  p.pole_pairs = 1;
  p.offset_e_rad = NAN;
  EXPECT_EQ(h.configure(p), Status::kNotFinite);
}

}  // namespace
