// mc_fw_f32 (firmware/kernels/fw/mc_fw.h): validation, the MTPA closed form
// against a brute-force optimum, the non-salient pass-through, the
// field-weakening integrator's direction and bounds.
#include <gtest/gtest.h>

#include <cmath>

extern "C" {
#include "fw/mc_fw.h"
}

namespace {

mc_fw_f32_cfg_t ipm() {
  mc_fw_f32_cfg_t c{};
  c.ld_h = 0.2e-3f;
  c.lq_h = 0.4e-3f;
  c.flux_wb = 0.02f;
  c.i_max_a = 80.0f;
  c.v_margin = 0.9f;
  c.ki_fw_a_per_vs = 100.0f;
  c.k_demag = 0.9f;
  c.dt_s = 5e-5f;
  return c;
}

TEST(Fw, RejectsBadConfig) {
  mc_fw_f32_t st{};
  mc_fw_f32_cfg_t c = ipm();
  c.ld_h = -1.0f;
  EXPECT_NE(mc_fw_f32_init(&st, &c) & MC_FW_ERR_MOTOR, 0u);
  c = ipm();
  c.k_demag = 1.5f;
  EXPECT_NE(mc_fw_f32_init(&st, &c) & MC_FW_ERR_LIMIT, 0u);
  c = ipm();
  c.ki_fw_a_per_vs = NAN;
  EXPECT_NE(mc_fw_f32_init(&st, &c) & MC_FW_ERR_GAIN, 0u);
  EXPECT_EQ(mc_fw_f32_init(nullptr, &c), MC_FW_ERR_NULL);
}

// The closed form maximises torque per ampere: no beta does better.
TEST(Fw, MtpaIsTheOptimum) {
  mc_fw_f32_t st{};
  const mc_fw_f32_cfg_t c = ipm();
  ASSERT_EQ(mc_fw_f32_init(&st, &c), 0u);
  for (double I : {5.0, 20.0, 40.0, 80.0}) {
    const double id = mc_fw_f32_mtpa_id(&st, static_cast<float>(I));
    auto t = [&](double d) {
      const double q = std::sqrt(I * I - d * d);
      return q * (c.flux_wb + (c.ld_h - c.lq_h) * d);
    };
    double best = -1, best_d = 0;
    for (int k = 0; k <= 200000; ++k) {
      const double d = -I * k / 200000.0;
      if (t(d) > best) best = t(d), best_d = d;
    }
    EXPECT_NEAR(id, best_d, 1e-3 * I + 1e-4) << I;
    EXPECT_LT(t(id), best * (1 + 1e-9));
    EXPECT_GT(t(id), best * (1 - 1e-6));
  }
}

// Non-salient: (0, i_cmd) exactly while the voltage is below v_max.
TEST(Fw, NonSalientPassThrough) {
  mc_fw_f32_t st{};
  mc_fw_f32_cfg_t c = ipm();
  c.lq_h = c.ld_h;
  ASSERT_EQ(mc_fw_f32_init(&st, &c), 0u);
  for (float i : {-30.0f, -1.25f, 0.0f, 3.3f, 79.0f}) {
    const mc_fw_f32_in_t in{i, 1.0f, 2.0f, 48.0f};
    mc_fw_f32_out_t o{};
    ASSERT_EQ(mc_fw_f32_step(&st, &in, &o), 0u);
    EXPECT_EQ(o.id_ref_a, 0.0f);
    EXPECT_EQ(o.iq_ref_a, i);
  }
}

// Above v_max the d current goes negative, never below the demagnetisation
// bound, the current stays in the circle, and comes back when the voltage
// drops.
TEST(Fw, WeakensWithinBounds) {
  mc_fw_f32_t st{};
  const mc_fw_f32_cfg_t c = ipm();
  ASSERT_EQ(mc_fw_f32_init(&st, &c), 0u);
  const float bound = -c.k_demag * c.flux_wb / c.ld_h;
  const float id_min = bound > -c.i_max_a ? bound : -c.i_max_a;
  mc_fw_f32_out_t o{};
  for (int k = 0; k < 200000; ++k) {
    const mc_fw_f32_in_t in{80.0f, 0.0f, 40.0f, 48.0f};  // 40 V > 0.9 * 48 / sqrt 3
    ASSERT_EQ(mc_fw_f32_step(&st, &in, &o), 0u);
    EXPECT_GE(o.id_ref_a, id_min);
    EXPECT_LE(std::hypot(o.id_ref_a, o.iq_ref_a), c.i_max_a * (1 + 1e-6f));
  }
  EXPECT_FLOAT_EQ(o.id_ref_a, id_min);
  for (int k = 0; k < 200000; ++k) {
    const mc_fw_f32_in_t in{10.0f, 0.0f, 1.0f, 48.0f};
    ASSERT_EQ(mc_fw_f32_step(&st, &in, &o), 0u);
  }
  EXPECT_FLOAT_EQ(o.id_ref_a, o.id_mtpa_a);
  const mc_fw_f32_in_t bad{NAN, 0.0f, 0.0f, 48.0f};
  EXPECT_EQ(mc_fw_f32_step(&st, &bad, &o), MC_FW_ERR_INPUT);
}

}  // namespace
