// The commissioning sequence (firmware/app/commission) on the fake HAL: the
// refusals a board without a motor model can show (implausible offset, no
// motor, abort), the configuration checks, and mc_comm_apply. The fake's
// currents are whatever the test sets: nothing answers the voltage.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "app_test_fixture.h"
#include "comm_result_fixture.h"
extern "C" {
#include "commission/mc_commission.h"
}

namespace apptest {
namespace {

mc_comm_cfg_t GoodCommCfg() {
  mc_comm_cfg_t c{};
  c.dt_s = kDt;
  c.i_test_a = 4.0f;
  c.v_test_max_v = 10.0f;
  c.offset_max_a = 1.0f;
  c.dead_time_s = 0.0f;
  c.cur_bw_rad_s = 0.08f / kDt;
  c.speed_max_m_rad_s = 100.0f;
  c.bemf_frac = 0.5f;
  c.pole_pairs_max = 32u;
  c.three_shunts = false;
  return c;
}

class Commission : public AppDrive {
 protected:
  void Start() {
    InitDrive();
    ASSERT_EQ(MC_COMM_CFG_OK, mc_comm_init(&comm, &ccfg));
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, mc_comm_ops(&comm)));
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
  }
  // Fast steps with constant phase currents until the drive faults or n
  // periods pass; returns the periods run.
  uint32_t Run(uint32_t n, float ia = 0.0f, float ib = 0.0f) {
    uint32_t k = 0;
    for (; k < n && d.mode != MC_DRIVE_MODE_FAULT; ++k) {
      EXPECT_EQ(0, mc_hal_fake_adc_set_sample(&fake, ia, ib, -(ia + ib), kVbus, kMask3));
      (void)mc_drive_fast_step(&d);
    }
    return k;
  }
  void ExpectRefused(uint32_t bit) {
    EXPECT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
    EXPECT_NE(0u, d.faults & MC_DRIVE_FAULT_CONTROL);
    EXPECT_NE(0u, d.tm.ctrl_err & bit) << "ctrl_err " << d.tm.ctrl_err;
    EXPECT_EQ(MC_COMM_STEP_FAILED, comm.step);
    EXPECT_EQ(0u, comm.res.valid) << "nothing to store";
    EXPECT_FALSE(fake.pwm3.enabled);
  }
  mc_comm_cfg_t ccfg = GoodCommCfg();
  mc_comm_t comm{};
};

TEST(CommissionCfg, InitRefusesBadConfigurations) {
  mc_comm_t c{};
  const mc_comm_cfg_t good = GoodCommCfg();
  EXPECT_EQ(MC_COMM_CFG_OK, mc_comm_init(&c, &good));
  EXPECT_EQ(MC_COMM_STEP_IDLE, c.step);
  EXPECT_EQ(MC_COMM_CFG_ERR_NULL, mc_comm_init(nullptr, &good));
  EXPECT_EQ(MC_COMM_CFG_ERR_NULL, mc_comm_init(&c, nullptr));
  auto bad = [&](void (*edit)(mc_comm_cfg_t&)) {
    mc_comm_cfg_t x = good;
    edit(x);
    return mc_comm_init(&c, &x);
  };
  EXPECT_EQ(MC_COMM_CFG_ERR_VALUE, bad([](mc_comm_cfg_t& x) { x.dt_s = 0.0f; }));
  EXPECT_EQ(MC_COMM_CFG_ERR_VALUE, bad([](mc_comm_cfg_t& x) { x.i_test_a = -1.0f; }));
  EXPECT_EQ(MC_COMM_CFG_ERR_VALUE, bad([](mc_comm_cfg_t& x) { x.v_test_max_v = kNaN; }));
  EXPECT_EQ(MC_COMM_CFG_ERR_VALUE, bad([](mc_comm_cfg_t& x) { x.offset_max_a = kInf; }));
  EXPECT_EQ(MC_COMM_CFG_ERR_VALUE, bad([](mc_comm_cfg_t& x) { x.dead_time_s = 0.25f * kDt; }));
  EXPECT_EQ(MC_COMM_CFG_ERR_VALUE, bad([](mc_comm_cfg_t& x) { x.cur_bw_rad_s = 0.21f / kDt; }));
  EXPECT_EQ(MC_COMM_CFG_ERR_VALUE, bad([](mc_comm_cfg_t& x) { x.bemf_frac = 1.0f; }));
  EXPECT_EQ(MC_COMM_CFG_ERR_VALUE, bad([](mc_comm_cfg_t& x) { x.pole_pairs_max = 0u; }));
  EXPECT_EQ(MC_COMM_CFG_ERR_VALUE, bad([](mc_comm_cfg_t& x) { x.pole_pairs_max = 65u; }));
  EXPECT_EQ(MC_COMM_CFG_ERR_VALUE, bad([](mc_comm_cfg_t& x) { x.speed_max_m_rad_s = 0.0f; }));
  // without an encoder: the pole pairs given within pole_pairs_max, no Hall table
  EXPECT_EQ(MC_COMM_CFG_ERR_VALUE,
            bad([](mc_comm_cfg_t& x) { x.pole_pairs_given = x.pole_pairs_max + 1u; }));
  EXPECT_EQ(MC_COMM_CFG_OK, bad([](mc_comm_cfg_t& x) { x.pole_pairs_given = x.pole_pairs_max; }));
  static const mc_hal_hall_t kHall{};
  EXPECT_EQ(MC_COMM_CFG_ERR_VALUE, bad([](mc_comm_cfg_t& x) {
              x.pole_pairs_given = 7u;
              x.hall = &kHall;
            }));
}

// A sensor reading 2 A with the bridge at zero voltage (no current can flow):
// refused after the offset average, bridge off, nothing stored.
TEST_F(Commission, RefusesAnImplausibleOffset) {
  Start();
  Run(20000u, 2.0f, 0.0f);
  ExpectRefused(MC_COMM_ERR_OFFSET);
}

// Offsets within bounds are measured at zero voltage (equal duties: the
// average of what the ADC reads) and the sequence moves on to the square
// wave; two shunts: phase c's offset is not measured.
TEST_F(Commission, MeasuresOffsetsAtZeroVoltageThenMovesOn) {
  Start();
  Run(100u, 0.3f, -0.2f);
  EXPECT_EQ(MC_COMM_STEP_OFFSETS, comm.step);
  EXPECT_EQ(fake.pwm3.duty_a, fake.pwm3.duty_b);
  EXPECT_EQ(fake.pwm3.duty_b, fake.pwm3.duty_c);
  Run(static_cast<uint32_t>(0.2f / kDt), 0.3f, -0.2f);
  ASSERT_EQ(MC_DRIVE_MODE_CTRL, d.mode);
  EXPECT_EQ(MC_COMM_STEP_L_ROUGH, comm.step);
  EXPECT_NE(0u, comm.res.valid & MC_COMM_HAVE_OFFSETS);
  EXPECT_NEAR(0.3f, comm.res.adc_offset_a[0], 1e-5f);
  EXPECT_NEAR(-0.2f, comm.res.adc_offset_a[1], 1e-5f);
  EXPECT_EQ(0.0f, comm.res.adc_offset_a[2]);
}

// Nothing conducts whatever the square wave's amplitude: NO_MOTOR.
TEST_F(Commission, RefusesWithoutAMotor) {
  Start();
  Run(static_cast<uint32_t>(2.0f / kDt));
  ExpectRefused(MC_COMM_ERR_NO_MOTOR);
}

TEST_F(Commission, AbortStopsTheBridge) {
  Start();
  Run(100u);
  ASSERT_EQ(MC_DRIVE_MODE_CTRL, d.mode);
  EXPECT_EQ(MC_COMM_STEP_OFFSETS, comm.step);
  mc_comm_abort(&comm);
  Run(2u);
  ExpectRefused(MC_COMM_ERR_ABORTED);
}

// ----------------------------------------------------------- apply
TEST(CommissionApply, WritesTheMotorAndRederivesTheCurrentLoop) {
  mc_drive_cfg_t dc = GoodCfg();
  dc.i_offset_a[0] = 0.5f;
  const mc_comm_result_t r = FullResult();
  const float bw = 2000.0f;
  ASSERT_EQ(0u, mc_comm_apply(&r, bw, &dc));
  EXPECT_EQ(0.2f, dc.foc.r_ohm);
  EXPECT_EQ(1e-4f, dc.foc.ld_h);
  EXPECT_EQ(1.5e-4f, dc.foc.lq_h);
  EXPECT_EQ(0.02f, dc.foc.flux_wb);
  EXPECT_FLOAT_EQ(1e-4f * bw, dc.foc.kp_d_v_per_a);  // kp = L bw
  EXPECT_FLOAT_EQ(0.2f * bw, dc.foc.ki_d_v_per_as);  // ki = R bw
  EXPECT_FLOAT_EQ(1.5e-4f * bw, dc.foc.kp_q_v_per_a);
  EXPECT_EQ(7u, dc.pole_pairs);
  EXPECT_EQ(1.25f, dc.encoder_offset_rad);
  EXPECT_TRUE(dc.encoder_reversed);
  EXPECT_FLOAT_EQ(0.6f, dc.i_offset_a[0]);  // relative offsets add
  EXPECT_FLOAT_EQ(-0.05f, dc.i_offset_a[1]);
  mc_drive_t drive{};
  mc_hal_fake_config_t fc{};
  mc_hal_fake_t fake{};
  ASSERT_EQ(0, mc_hal_fake_config_default(&fc));
  ASSERT_EQ(0, mc_hal_fake_init(&fake, &fc));
  EXPECT_EQ(MC_DRIVE_CFG_OK, mc_drive_init(&drive, &dc, &fake.board));
}

TEST(CommissionApply, RefusesAnIncompleteOrImplausibleResult) {
  const mc_drive_cfg_t before = GoodCfg();
  auto refused = [&](void (*edit)(mc_comm_result_t&)) {
    mc_comm_result_t r = FullResult();
    edit(r);
    mc_drive_cfg_t dc = before;
    const uint32_t e = mc_comm_apply(&r, 2000.0f, &dc);
    EXPECT_EQ(0, std::memcmp(&dc, &before, sizeof dc)) << "changed on refusal";
    return e;
  };
  EXPECT_EQ(MC_COMM_ERR_RANGE, refused([](mc_comm_result_t& r) { r.valid &= ~MC_COMM_HAVE_FLUX; }));
  EXPECT_EQ(MC_COMM_ERR_RANGE, refused([](mc_comm_result_t& r) { r.r_ohm = 0.0f; }));
  EXPECT_EQ(MC_COMM_ERR_RANGE, refused([](mc_comm_result_t& r) { r.ld_h = kNaN; }));
  EXPECT_EQ(MC_COMM_ERR_RANGE, refused([](mc_comm_result_t& r) { r.pole_pairs = 0u; }));
  EXPECT_EQ(MC_COMM_ERR_RANGE, refused([](mc_comm_result_t& r) { r.encoder_direction = 0; }));
  EXPECT_EQ(MC_COMM_ERR_RANGE, refused([](mc_comm_result_t& r) { r.encoder_offset_rad = kInf; }));
  // an encoder result without the encoder's values is incomplete
  EXPECT_EQ(MC_COMM_ERR_RANGE,
            refused([](mc_comm_result_t& r) { r.valid &= ~MC_COMM_HAVE_ENCODER; }));
}

// Without an encoder (MC_COMM_SENSORLESS): the motor's values and the pole
// pairs are written, the encoder's offset and direction stay as they were.
TEST(CommissionApply, WithoutAnEncoderKeepsTheEncoderValues) {
  mc_drive_cfg_t dc = GoodCfg();
  dc.encoder_offset_rad = 0.5f;
  dc.encoder_reversed = false;
  mc_comm_result_t r = FullResult();
  r.valid = (r.valid & ~MC_COMM_HAVE_ENCODER) | MC_COMM_SENSORLESS;
  r.encoder_offset_rad = 0.0f;
  r.encoder_direction = 0;  // not measured: not looked at
  ASSERT_EQ(0u, mc_comm_apply(&r, 2000.0f, &dc));
  EXPECT_EQ(0.02f, dc.foc.flux_wb);
  EXPECT_EQ(7u, dc.pole_pairs);
  EXPECT_EQ(0.5f, dc.encoder_offset_rad);
  EXPECT_FALSE(dc.encoder_reversed);
}

}  // namespace
}  // namespace apptest
