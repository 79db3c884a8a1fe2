// Commissioning's Hall table (firmware/app/commission/mc_comm_hall.h)
// against its closed form: changes synthesised from a known table, the
// sensors' band h and the rotor's lag L (up at edge + h/2 + L, down at
// edge - h/2 - L) give back the edges exactly and the band h + 2 L; each
// refusal by name with the output untouched.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "commission/mc_comm_hall.h"

namespace {

constexpr double kTwoPi = 6.283185307179586;
constexpr double kDeg = kTwoPi / 360.0;

struct Truth {
  uint8_t code[6];  // code of sector k, positive order
  double edge[6];   // where sector k begins [rad el.]
};

// The 120-degree placement's order from 5 (the parameters' default), edges
// uneven by a few degrees (placement errors), starting at 0.7 rad.
Truth uneven() {
  Truth t{{5, 1, 3, 2, 6, 4}, {}};
  const double err_deg[6] = {2.0, -3.0, 1.5, 4.0, -2.5, 0.5};
  for (int k = 0; k < 6; ++k) t.edge[k] = 0.7 + (60.0 * k + err_deg[k]) * kDeg;
  return t;
}

double wrap2pi(double x) {
  x = std::fmod(x, kTwoPi);
  return x < 0.0 ? x + kTwoPi : x;
}

// A turn and two sectors up from sector s0, then back: the changes the
// commissioning's sweep records.
mc_comm_hall_rec_t sweep(const Truth& t, double h, double lag, int s0 = 0) {
  mc_comm_hall_rec_t r{};
  for (int j = 1; j <= 8; ++j) {
    const int k = (s0 + j) % 6;
    const int prev = (k + 5) % 6;
    mc_comm_hall_record(&r, 1, t.code[prev], t.code[k],
                        static_cast<float>(wrap2pi(t.edge[k] + 0.5 * h + lag)));
  }
  for (int j = 8; j >= 1; --j) {
    const int k = (s0 + j) % 6;
    const int prev = (k + 5) % 6;
    mc_comm_hall_record(&r, -1, t.code[k], t.code[prev],
                        static_cast<float>(wrap2pi(t.edge[k] - 0.5 * h - lag)));
  }
  return r;
}

mc_comm_hall_table_t sentinel() {
  mc_comm_hall_table_t s{};
  for (int k = 0; k < 6; ++k) {
    s.code_of_sector[k] = 9;
    s.edge_e_rad[k] = -1.0f;
  }
  s.hysteresis_e_rad = -1.0f;
  return s;
}

void expect_untouched(const mc_comm_hall_table_t& o) {
  for (int k = 0; k < 6; ++k) {
    EXPECT_EQ(o.code_of_sector[k], 9);
    EXPECT_EQ(o.edge_e_rad[k], -1.0f);
  }
  EXPECT_EQ(o.hysteresis_e_rad, -1.0f);
}

}  // namespace

// Edges from the middle of up and down: the lag and the band cancel; the
// band read is h + 2 lag. Tolerance 2e-6 rad: float angles near 2 pi
// (spacing 4.8e-7) through one sin/cos and atan2 each (a few ulp).
TEST(CommHallTable, EdgesAreTheMiddleOfUpAndDownWhateverTheLag) {
  const Truth t = uneven();
  for (const double lag : {0.0, 0.02, 0.1}) {
    for (const int s0 : {0, 3}) {
      const double h = 0.05;
      const mc_comm_hall_rec_t r = sweep(t, h, lag, s0);
      mc_comm_hall_table_t o = sentinel();
      ASSERT_EQ(mc_comm_hall_table_f32(&r, &o), MC_COMM_HALL_ERR_NONE);
      // sector 0 is the one whose edge is smallest in [0, 2 pi): here the
      // truth's sector 0 (0.7 + 2 deg)
      for (int k = 0; k < 6; ++k) {
        EXPECT_EQ(o.code_of_sector[k], t.code[k]) << k;
        EXPECT_NEAR(o.edge_e_rad[k], t.edge[k], 2e-6) << "lag " << lag << " k " << k;
      }
      EXPECT_NEAR(o.hysteresis_e_rad, h + 2.0 * lag, 2e-6) << lag;
    }
  }
}

// An edge table across 0: sector 0 is the one beginning just above 0 and
// the codes rotate with it.
TEST(CommHallTable, SectorZeroBeginsAtTheSmallestAngle) {
  Truth t = uneven();
  for (double& e : t.edge) e = wrap2pi(e + 3.0);  // sector 4 now starts lowest
  double lo = 10.0;
  int k_lo = 0;
  for (int k = 0; k < 6; ++k) {
    if (t.edge[k] < lo) {
      lo = t.edge[k];
      k_lo = k;
    }
  }
  const mc_comm_hall_rec_t r = sweep(t, 0.03, 0.01, 2);
  mc_comm_hall_table_t o = sentinel();
  ASSERT_EQ(mc_comm_hall_table_f32(&r, &o), MC_COMM_HALL_ERR_NONE);
  for (int k = 0; k < 6; ++k) {
    const int j = (k_lo + k) % 6;
    EXPECT_EQ(o.code_of_sector[k], t.code[j]);
    EXPECT_NEAR(o.edge_e_rad[k], t.edge[j], 2e-6);  // as above
  }
  mc_hall_f32_cfg_t c{};
  for (int k = 0; k < 6; ++k) {
    c.code_of_sector[k] = o.code_of_sector[k];
    c.edge_e_rad[k] = o.edge_e_rad[k];
  }
  c.hysteresis_e_rad = o.hysteresis_e_rad;
  c.dt_s = 1e-4f;
  c.omega_min_e_rad_s = 50.0f;
  uint8_t map[8];
  EXPECT_EQ(mc_hall_f32_validate(&c, map, nullptr), MC_HALL_ERR_NONE);  // the decoder takes it
}

// A swing back at an edge going up (the rotor over-shooting and coming
// back) is the reverse of a change already known: accepted, and the edge
// the circular mean of its up changes.
TEST(CommHallTable, ASwingBackAtAnEdgeIsAccepted) {
  const Truth t = uneven();
  mc_comm_hall_rec_t r = sweep(t, 0.0, 0.0);
  mc_comm_hall_rec_t s{};
  // up: 5->1 at e1+0.01, back 1->5, 5->1 again at e1+0.03, then the rest
  mc_comm_hall_record(&s, 1, 5, 1, static_cast<float>(t.edge[1] + 0.01));
  mc_comm_hall_record(&s, 1, 1, 5, static_cast<float>(t.edge[1] + 0.015));
  mc_comm_hall_record(&s, 1, 5, 1, static_cast<float>(t.edge[1] + 0.03));
  for (uint32_t k = 1; k < r.n_up; ++k) {
    mc_comm_hall_record(&s, 1, r.up[k].from, r.up[k].to, r.up[k].theta_rad);
  }
  for (uint32_t k = 0; k < r.n_down; ++k) {
    mc_comm_hall_record(&s, -1, r.down[k].from, r.down[k].to, r.down[k].theta_rad);
  }
  mc_comm_hall_table_t o = sentinel();
  ASSERT_EQ(mc_comm_hall_table_f32(&s, &o), MC_COMM_HALL_ERR_NONE);
  // up at e1 + 0.04 / 3 (the mean of 0.01, 0.03 and the sweep's second
  // pass at 0 over the turn and two sectors), down at e1 (both passes): the
  // middle e1 + 0.02 / 3; 1e-5: the circular mean of angles 0.03 apart
  // differs from the arithmetic one by under 1e-6, plus float
  EXPECT_NEAR(o.edge_e_rad[1], t.edge[1] + 0.02 / 3.0, 1e-5);
}

TEST(CommHallTable, IllegalCodeOrMissingCodeIsRefusedByName) {
  const Truth t = uneven();
  {
    mc_comm_hall_rec_t r = sweep(t, 0.0, 0.0);
    r.seen_mask |= 1u << 0;  // 000 read once
    mc_comm_hall_table_t o = sentinel();
    EXPECT_EQ(mc_comm_hall_table_f32(&r, &o), MC_COMM_HALL_ERR_CODES);
    expect_untouched(o);
  }
  {
    mc_comm_hall_rec_t r = sweep(t, 0.0, 0.0);
    r.seen_mask |= 1u << 7;  // 111
    mc_comm_hall_table_t o = sentinel();
    EXPECT_EQ(mc_comm_hall_table_f32(&r, &o), MC_COMM_HALL_ERR_CODES);
    expect_untouched(o);
  }
  {
    // sensor A stuck high: 5,1,3 stay; 2->3, 6->7, 4->5: only 1, 3, 5, 7
    Truth s = t;
    for (uint8_t& c : s.code) c |= 1u;
    mc_comm_hall_rec_t r{};
    for (int k = 1; k < 6; ++k) {
      if (s.code[k] != s.code[k - 1]) mc_comm_hall_record(&r, 1, s.code[k - 1], s.code[k], 1.0f);
    }
    mc_comm_hall_table_t o = sentinel();
    EXPECT_EQ(mc_comm_hall_table_f32(&r, &o), MC_COMM_HALL_ERR_CODES);
    expect_untouched(o);
  }
  {
    // no 000/111 but five codes only (the seen mask as a 60-degree-placement
    // sensor set with one code never read would show)
    mc_comm_hall_rec_t r = sweep(t, 0.0, 0.0);
    r.seen_mask &= ~(1u << 6);
    mc_comm_hall_table_t o = sentinel();
    EXPECT_EQ(mc_comm_hall_table_f32(&r, &o), MC_COMM_HALL_ERR_CODES);
    expect_untouched(o);
  }
}

// Codes of two sectors exchanged (two sensors' wires swapped on a board
// that reads them in another order): a change of three sensors at once; a
// down change of two; chatter beyond the record.
TEST(CommHallTable, OrderNotOneSensorAtATimeIsRefusedByName) {
  {
    Truth t = uneven();
    std::swap(t.code[1], t.code[3]);  // 5,2,3,1,6,4: 5->2 changes two sensors
    const mc_comm_hall_rec_t r = sweep(t, 0.0, 0.0);
    mc_comm_hall_table_t o = sentinel();
    EXPECT_EQ(mc_comm_hall_table_f32(&r, &o), MC_COMM_HALL_ERR_ORDER);
    expect_untouched(o);
  }
  {
    const Truth t = uneven();
    mc_comm_hall_rec_t r = sweep(t, 0.0, 0.0);
    // going down 1 -> 2: two sensors at once (between legal codes every
    // one-sensor change is a neighbour in the cycle, so this is the only
    // way a down change can fail to reverse an up one)
    r.down[2].from = 1;
    r.down[2].to = 2;
    mc_comm_hall_table_t o = sentinel();
    EXPECT_EQ(mc_comm_hall_table_f32(&r, &o), MC_COMM_HALL_ERR_ORDER);
    expect_untouched(o);
  }
  {
    const Truth t = uneven();
    mc_comm_hall_rec_t r = sweep(t, 0.0, 0.0);
    r.overflow = 1u;
    mc_comm_hall_table_t o = sentinel();
    EXPECT_EQ(mc_comm_hall_table_f32(&r, &o), MC_COMM_HALL_ERR_ORDER);
    expect_untouched(o);
  }
}

// Widths: 30 and 90 degrees pass, 29 and 91 do not; a band of half the
// narrowest sector is refused (the decoder's rule).
TEST(CommHallTable, SectorWidthOutsideThirtyToNinetyDegreesIsRefused) {
  auto with_width = [](double w0_deg) {
    Truth t{{5, 1, 3, 2, 6, 4}, {}};
    const double rest = (360.0 - w0_deg) / 5.0;
    t.edge[0] = 0.1;
    t.edge[1] = 0.1 + w0_deg * kDeg;
    for (int k = 2; k < 6; ++k) t.edge[k] = t.edge[1] + rest * (k - 1) * kDeg;
    return t;
  };
  for (const double ok : {30.5, 89.5}) {  // 0.5 deg inside: float rounding of the bounds
    const mc_comm_hall_rec_t r = sweep(with_width(ok), 0.0, 0.0);
    mc_comm_hall_table_t o = sentinel();
    EXPECT_EQ(mc_comm_hall_table_f32(&r, &o), MC_COMM_HALL_ERR_NONE) << ok;
  }
  for (const double bad : {29.0, 91.0}) {
    const mc_comm_hall_rec_t r = sweep(with_width(bad), 0.0, 0.0);
    mc_comm_hall_table_t o = sentinel();
    EXPECT_EQ(mc_comm_hall_table_f32(&r, &o), MC_COMM_HALL_ERR_WIDTH) << bad;
    expect_untouched(o);
  }
  {
    // narrowest 50 deg: a band of 26 deg (h + 2 lag) is refused, 24 passes
    const Truth t = with_width(50.0);
    mc_comm_hall_table_t o = sentinel();
    mc_comm_hall_rec_t r = sweep(t, 24.0 * kDeg, 0.0);
    EXPECT_EQ(mc_comm_hall_table_f32(&r, &o), MC_COMM_HALL_ERR_NONE);
    o = sentinel();
    r = sweep(t, 26.0 * kDeg, 0.0);
    EXPECT_EQ(mc_comm_hall_table_f32(&r, &o), MC_COMM_HALL_ERR_WIDTH);
    expect_untouched(o);
  }
}

TEST(CommHallTable, NoChangeOrAnEdgeSeenOneWayOnlyIsNoMotion) {
  const Truth t = uneven();
  {
    mc_comm_hall_rec_t r{};
    r.seen_mask = 0x7Eu;  // every legal code read (the rotor moved before), no change recorded
    mc_comm_hall_table_t o = sentinel();
    EXPECT_EQ(mc_comm_hall_table_f32(&r, &o), MC_COMM_HALL_ERR_MOTION);
    expect_untouched(o);
  }
  {
    mc_comm_hall_rec_t r = sweep(t, 0.0, 0.0);
    r.n_down = 3u;  // the rotor stopped following on the way down
    mc_comm_hall_table_t o = sentinel();
    EXPECT_EQ(mc_comm_hall_table_f32(&r, &o), MC_COMM_HALL_ERR_MOTION);
    expect_untouched(o);
  }
  mc_comm_hall_table_t o = sentinel();
  EXPECT_EQ(mc_comm_hall_table_f32(nullptr, &o), MC_COMM_HALL_ERR_NULL);
}
