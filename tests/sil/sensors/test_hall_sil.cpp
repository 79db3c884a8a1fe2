// The Hall kernel (firmware/kernels/hall, f32 and q31) on the plant's Hall
// model (mcsim::HallSensors: placement errors per edge, hysteresis, sensor
// faults), a model written independently of the kernel. The edge table is
// measured on the model as a commissioning would (a slow sweep each way:
// the edge is the middle of where it is seen going up and going down, the
// band their difference), then a rotor runs at constant and changing
// speeds; the kernel's angle is compared with the true electrical angle.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "hall/mc_hall.h"
#include "hall/mc_hall_q31.h"
#include "mcsim/hall.hpp"

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDt = 50e-6;
constexpr int kPolePairs = 7;  // a hub motor

double wrap_2pi(double x) {
  const double w = std::fmod(x, 2.0 * kPi);
  return (w < 0.0) ? w + 2.0 * kPi : w;
}

double wrap_pi(double x) {
  return wrap_2pi(x + kPi) - kPi;
}

mcsim::HallParams plant_params() {
  mcsim::HallParams p;
  p.pole_pairs = kPolePairs;
  p.offset_e_rad = 0.4;
  // each edge off by a few degrees (mounting, magnet asymmetry)
  const double e[6] = {0.06, -0.04, 0.03, 0.08, -0.07, 0.02};
  for (int k = 0; k < 6; ++k) {
    p.edge_error_e_rad[k] = e[k];
  }
  p.hysteresis_e_rad = 0.05;
  return p;
}

// Commissioning: sweep one electrical turn up, then down, in steps of
// kStep rad el.; at each state change note the angle. Sector k begins
// where the code changes into code k going up.
constexpr double kStep = 1e-5;  // rad el.: the table's resolution

struct Table {
  uint8_t code[6];
  double edge_up[6], edge_down[6];
};

Table measure(mcsim::HallSensors& h) {
  Table t{};
  h.reset(0.0);
  std::vector<std::pair<uint8_t, double>> up;
  uint8_t prev = h.sample(0.0);
  for (double th = 0.0; th <= 2.0 * kPi + 0.2; th += kStep) {
    const uint8_t s = h.sample(th / kPolePairs);
    if (s != prev) {
      up.emplace_back(s, th);
      prev = s;
    }
  }
  // the six codes in order, from the first full turn
  for (int k = 0; k < 6; ++k) {
    t.code[k] = up[static_cast<size_t>(k)].first;
    t.edge_up[k] = wrap_2pi(up[static_cast<size_t>(k)].second);
  }
  // going down, the change out of code k (into code k - 1) is sector k's start
  for (double th = 2.0 * kPi + 0.4; th >= -0.2; th -= kStep) {
    const uint8_t s = h.sample(th / kPolePairs);
    if (s != prev) {
      for (int k = 0; k < 6; ++k) {
        if (t.code[k] == prev) {
          t.edge_down[k] = wrap_2pi(th + kStep);
        }
      }
      prev = s;
    }
  }
  return t;
}

mc_hall_f32_cfg_t kernel_cfg(const Table& t, double* p_band) {
  mc_hall_f32_cfg_t c{};
  double band = 0.0;
  for (int k = 0; k < 6; ++k) {
    c.code_of_sector[k] = t.code[k];
    const double d = wrap_pi(t.edge_up[k] - t.edge_down[k]);
    c.edge_e_rad[k] = static_cast<float>(wrap_2pi(t.edge_down[k] + 0.5 * d));
    band += d / 6.0;
  }
  c.hysteresis_e_rad = static_cast<float>(band);
  c.dt_s = static_cast<float>(kDt);
  c.omega_min_e_rad_s = 30.0f;
  *p_band = band;
  return c;
}

}  // namespace

// The measured table finds the model's edges and band to its sweep step.
TEST(HallSil, CommissioningTableMatchesThePlacement) {
  mcsim::HallSensors h;
  const mcsim::HallParams p = plant_params();
  ASSERT_EQ(h.configure(p), mcsim::Status::kOk);
  const Table t = measure(h);
  double band = 0.0;
  const mc_hall_f32_cfg_t c = kernel_cfg(t, &band);
  mc_hall_f32_t st{};
  ASSERT_EQ(mc_hall_f32_init(&st, &c), MC_HALL_ERR_NONE);
  // the band: each edge seen h/2 late both ways, found to one step each way
  EXPECT_NEAR(band, p.hysteresis_e_rad, 2.0 * kStep);
  // the edges against the model's (sector starts: A rise, C fall, B rise,
  // A fall, C rise, B fall with 120-degree spacing)
  const int sensor[6] = {0, 2, 1, 0, 2, 1};
  const bool rising[6] = {true, false, true, false, true, false};
  for (int k = 0; k < 6; ++k) {
    const double model = h.edge_e_rad(sensor[k], rising[k]);
    // which of the measured sectors starts there
    double best = 10.0;
    for (int j = 0; j < 6; ++j) {
      best = std::fmin(best, std::fabs(wrap_pi(c.edge_e_rad[j] - model)));
    }
    EXPECT_LE(best, 2.0 * kStep) << k;  // sweep step, float of 2 pi
  }
}

// A rotor at constant speeds and through an acceleration: with the
// measured table the angle error stays within the speed's sampling error
// over a sector plus one sample of travel (|omega| dt); with the ideal
// table (60-degree sectors, no band) the placement errors show up in full.
TEST(HallSil, InterpolatedAngleOnThePlant) {
  mcsim::HallSensors h;
  ASSERT_EQ(h.configure(plant_params()), mcsim::Status::kOk);
  double band = 0.0;
  const mc_hall_f32_cfg_t measured = kernel_cfg(measure(h), &band);
  mc_hall_f32_cfg_t ideal = measured;
  for (int k = 0; k < 6; ++k) {
    ideal.edge_e_rad[k] = static_cast<float>(wrap_2pi(0.4 + k * kPi / 3.0));
  }
  // the ideal table's code order from A's rise: the same as measured,
  // rotated to start where the measured one starts
  ideal.hysteresis_e_rad = 0.0f;
  for (const double w_e : {300.0, -300.0, 1500.0}) {  // rad/s el.
    double err[2] = {0.0, 0.0};
    for (int which = 0; which < 2; ++which) {
      mc_hall_f32_cfg_t c = (which == 0) ? measured : ideal;
      if (which == 1) {
        // rotate the ideal edges to the measured sector numbering
        int k0 = 0;
        for (int k = 0; k < 6; ++k) {
          if (std::fabs(wrap_pi(measured.edge_e_rad[k] - 0.4)) < 0.3) {
            k0 = k;
          }
        }
        for (int k = 0; k < 6; ++k) {
          c.edge_e_rad[(k0 + k) % 6] = static_cast<float>(wrap_2pi(0.4 + k * kPi / 3.0));
        }
      }
      mc_hall_f32_t st{};
      ASSERT_EQ(mc_hall_f32_init(&st, &c), MC_HALL_ERR_NONE);
      h.reset(0.2);
      int edges = 0;
      for (int n = 0; n < 40000; ++n) {
        const double th_e = 0.2 * kPolePairs + w_e * n * kDt;
        mc_hall_f32_out_t o{};
        ASSERT_EQ(mc_hall_f32_step(&st, h.sample(th_e / kPolePairs), &o), MC_HALL_ERR_NONE);
        edges += o.edge ? 1 : 0;
        if (edges > 2 && o.interpolating) {
          err[which] = std::fmax(err[which], std::fabs(wrap_pi(o.theta_e_rad - th_e)));
        }
      }
    }
    const double per_sector = (kPi / 3.0) / (std::fabs(w_e) * kDt);
    // one sample of edge timing at each end of the interval (speed
    // error 2 / per_sector over at most 70 degrees of sector), plus
    // one sample of travel, plus the table's 2 sweep steps
    const double bound =
        (70.0 * kPi / 180.0) * 2.0 / per_sector + std::fabs(w_e) * kDt + 2.0 * kStep + 1e-5;
    EXPECT_LE(err[0], bound) << w_e;
    // the ideal table errs by the placement (up to 0.08 rad) and band
    EXPECT_GT(err[1], 0.05) << w_e;
  }
}

// Faults of the model: all low (supply lost) and all high (connector off:
// the pull-ups) are illegal at the first sample; a stuck sensor shows an
// illegal state within one electrical turn.
TEST(HallSil, SensorFaultsAreNamedErrors) {
  mcsim::HallSensors h;
  double band = 0.0;
  ASSERT_EQ(h.configure(plant_params()), mcsim::Status::kOk);
  const mc_hall_f32_cfg_t c = kernel_cfg(measure(h), &band);
  struct Case {
    mcsim::HallFault f;
    int sensor;
    double max_turns_e;  // electrical turns until the error
  };
  const Case cases[] = {{mcsim::HallFault::kAllLow, 0, 0.0},
                        {mcsim::HallFault::kAllHigh, 0, 0.0},
                        {mcsim::HallFault::kStuckLow, 1, 1.0},
                        {mcsim::HallFault::kStuckHigh, 2, 1.0}};
  for (const Case& cs : cases) {
    mc_hall_f32_t st{};
    ASSERT_EQ(mc_hall_f32_init(&st, &c), MC_HALL_ERR_NONE);
    h.reset(0.0);
    const double w_e = 400.0;
    mc_hall_f32_out_t o{};
    int n = 0;
    for (; n < 200; ++n) {  // healthy first
      ASSERT_EQ(mc_hall_f32_step(&st, h.sample(w_e * n * kDt / kPolePairs), &o), MC_HALL_ERR_NONE);
    }
    ASSERT_EQ(h.set_fault(cs.f, cs.sensor), mcsim::Status::kOk);
    const int n0 = n;
    uint32_t err = 0u;
    for (; n < n0 + 2000 && err == 0u; ++n) {
      err = mc_hall_f32_step(&st, h.sample(w_e * n * kDt / kPolePairs), &o);
    }
    EXPECT_EQ(err, MC_HALL_ERR_ILLEGAL) << static_cast<int>(cs.f);
    const double turns = w_e * (n - 1 - n0) * kDt / (2.0 * kPi);
    EXPECT_LE(turns, cs.max_turns_e + 1e-9) << static_cast<int>(cs.f);
  }
}

// The q31 twin on the same plant run gives the same sectors, edges and
// errors, and its angle within the twins' bound (tests/unit/q31).
TEST(HallSil, Q31TwinOnThePlant) {
  mcsim::HallSensors h;
  double band = 0.0;
  ASSERT_EQ(h.configure(plant_params()), mcsim::Status::kOk);
  mc_hall_q31_cfg_t c{};
  c.f = kernel_cfg(measure(h), &band);
  c.omega_base_rad_s = 5000.0f;
  mc_hall_f32_t f{};
  mc_hall_q31_t q{};
  ASSERT_EQ(mc_hall_f32_init(&f, &c.f), MC_HALL_ERR_NONE);
  ASSERT_EQ(mc_hall_q31_init(&q, &c), MC_HALL_ERR_NONE);
  h.reset(0.0);
  double dmax = 0.0;
  for (int n = 0; n < 20000; ++n) {
    const double th_e = 700.0 * n * kDt + 0.5 * 3000.0 * (n * kDt) * (n * kDt);
    const uint8_t code = h.sample(th_e / kPolePairs);
    mc_hall_f32_out_t of{};
    mc_hall_q31_out_t oq{};
    ASSERT_EQ(mc_hall_f32_step(&f, code, &of), mc_hall_q31_step(&q, code, &oq));
    ASSERT_EQ(of.sector, oq.sector);
    if (of.interpolating == oq.interpolating) {
      dmax =
          std::fmax(dmax, std::fabs(wrap_pi(mc_q31_angle_to_rad_f32(oq.theta_e) - of.theta_e_rad)));
    }
  }
  EXPECT_LE(dmax, 2e-6);  // the bound of tests/unit/q31/test_hall_q31.cpp
}
