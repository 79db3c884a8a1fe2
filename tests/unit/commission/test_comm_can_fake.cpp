// Commissioning over CAN (firmware/app/commission/mc_comm_can) on the fake
// HAL, behind the real command handler and parameter service: COMMISSION_CMD
// refusals (not attached, enabled, faulted, running), the commands refused
// while it runs, progress and end reports, a failed or aborted run stages
// nothing, a finished run stages every result through the service's WRITE
// checks (all or nothing) and APPLY puts them into the drive with the
// current-loop gains re-derived. The fake's currents are whatever the test
// sets, so a finished run is simulated by writing the plug-in's result (the
// measurements themselves are tested on the plant: tests/sil/commission).
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "app_test_fixture.h"
#include "comm_result_fixture.h"
extern "C" {
#include "can/mc_can_cmd.h"
#include "commission/mc_comm_can.h"
#include "config/mc_gains.h"
#include "config/mc_param_srv.h"
#include "config/mc_params.h"
}

namespace apptest {
namespace {

struct Rx {
  uint32_t msg;
  float v[MC_CAN_NSIG_MAX];
  uint32_t raw_hi;  // data[4..7] little-endian (COMMISSION_RESULT.value)
};

class CommCan : public AppDrive {
 protected:
  void Boot(bool attach = true) {
    p = mc_params_default;
    ASSERT_EQ(MC_PARAMS_OK, mc_params_to_drive_cfg(&p, &cfg));
    InitDrive();
    ASSERT_EQ(0, mc_param_srv_init(&srv, &p, &d, hal, nullptr, 0u));
    mc_can_cmd_cfg_t cc{};
    cc.node_id = 1u;
    cc.tick_hz = 2000u;
    cc.timeout_s = 0.5f;
    cc.stop_ramp_a_per_s = 20.0f;
    cc.stop_decel_rad_s2 = 100.0f;
    cc.speed_max_rad_s = 100.0f;
    ASSERT_EQ(MC_CAN_CMD_CFG_OK, mc_can_cmd_init(&c, &cc, &d, nullptr));
    mc_can_cmd_attach_params(&c, &srv);
    mc_comm_can_cfg_t k{};
    k.base.dt_s = cfg.foc.dt_s;
    k.base.i_test_a = 4.0f;
    k.base.v_test_max_v = 10.0f;
    k.base.offset_max_a = 1.0f;
    k.base.dead_time_s = 0.0f;
    k.base.cur_bw_rad_s = 0.08f / cfg.foc.dt_s;
    k.base.speed_max_m_rad_s = 100.0f;
    k.base.bemf_frac = 0.5f;
    k.base.pole_pairs_max = 32u;
    k.base.three_shunts = false;
    k.node_id = 1u;
    k.status_div = 200u;  // 10 Hz at the 2 kHz slow loop
    k.enc_pll_bw_rad_s = 1000.0f;
    ASSERT_EQ(MC_COMM_CAN_CFG_OK, mc_comm_can_init(&m, &k, &comm, &d, &srv));
    if (attach) mc_can_cmd_attach_commission(&c, mc_comm_can_command, mc_comm_can_busy, &m);
  }
  mc_can_err_t Handle(uint32_t msg, const std::vector<float>& v) {
    mc_hal_can_frame_t f{};
    const float none = 0.0f;  // a message without signals still needs a pointer
    EXPECT_EQ(MC_CAN_ERR_NONE, mc_can_proto_pack(msg, 1u, v.empty() ? &none : v.data(),
                                                 static_cast<uint32_t>(v.size()), &f));
    return mc_can_cmd_handle(&c, &f, &fake.can_dev);
  }
  mc_can_err_t Comm(uint32_t action, float i_test = 0.0f) {
    return Handle(MC_CAN_MSG_COMMISSION_CMD, {static_cast<float>(action), i_test, 0.0f, 0.0f});
  }
  // n PWM periods with zero phase currents, the slow loop every kSlowDiv;
  // the bus takes the frames sent at each slow step (the fake's queue
  // holds 8, a bus controller's mailboxes empty as fast).
  void Run(uint32_t n) {
    for (uint32_t k = 1; k <= n; ++k) {
      ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, 0.0f, 0.0f, 0.0f, kVbus, kMask3));
      (void)mc_drive_fast_step(&d);
      if (k % kSlowDiv == 0u) {
        mc_comm_can_step(&m, &fake.can_dev);
        Collect();
      }
    }
  }
  void Collect() {
    mc_hal_can_frame_t f;
    while (mc_hal_fake_can_tx_pop(&fake, &f) == 0) {
      Rx r{};
      EXPECT_EQ(MC_CAN_ERR_NONE, mc_can_proto_unpack(&f, &r.msg, r.v, MC_CAN_NSIG_MAX));
      for (uint32_t i = 0; i < 4u; ++i) r.raw_hi |= static_cast<uint32_t>(f.data[4 + i]) << (8 * i);
      bus.push_back(r);
    }
  }
  std::vector<Rx> Drain() {
    Collect();
    std::vector<Rx> out;
    out.swap(bus);
    return out;
  }
  std::vector<Rx> bus;
  // the complete result plus the mechanics
  static mc_comm_result_t FullResultWithMech() {
    mc_comm_result_t r = FullResult();
    r.j_kgm2 = 2e-4f;
    r.b_nm_s_rad = 1e-5f;
    r.valid = MC_COMM_HAVE_ALL;
    return r;
  }
  mc_params_t p{};
  mc_param_srv_t srv{};
  mc_can_cmd_t c{};
  mc_comm_t comm{};
  mc_comm_can_t m{};
};

TEST_F(CommCan, UnsupportedWithoutTheFrontEnd) {
  Boot(false);
  EXPECT_EQ(MC_CAN_ERR_UNSUPPORTED, Comm(MC_COMM_CAN_START));
  EXPECT_EQ(MC_DRIVE_MODE_IDLE, d.mode);
}

TEST_F(CommCan, RefusedWhileEnabled) {
  Boot();
  ASSERT_EQ(MC_CAN_ERR_NONE, Handle(MC_CAN_MSG_SET_CONTROL_MODE, {1.0f}));
  ASSERT_EQ(MC_CAN_ERR_NONE, Handle(MC_CAN_MSG_SET_ENABLE, {1.0f}));
  EXPECT_EQ(MC_CAN_ERR_MODE, Comm(MC_COMM_CAN_START));
  EXPECT_EQ(MC_DRIVE_MODE_CURRENT, d.mode) << "the run goes on";
  EXPECT_FALSE(m.running);
}

TEST_F(CommCan, AnOptionReplacesTheDefaultZeroKeepsIt) {
  Boot();
  EXPECT_EQ(MC_CAN_ERR_NONE, Comm(MC_COMM_CAN_START, 2.0f));
  EXPECT_EQ(2.0f, comm.cfg.i_test_a) << "the option replaces the default";
  EXPECT_EQ(10.0f, comm.cfg.v_test_max_v) << "0: the board's default";
  EXPECT_EQ(MC_CAN_ERR_NONE, Comm(MC_COMM_CAN_ABORT));
  EXPECT_EQ(MC_DRIVE_MODE_IDLE, d.mode);
}

TEST_F(CommCan, RunningRefusesEnableModeAndClearAndReportsProgress) {
  Boot();
  ASSERT_EQ(MC_CAN_ERR_NONE, Comm(MC_COMM_CAN_START));
  EXPECT_EQ(MC_DRIVE_MODE_CTRL, d.mode);
  EXPECT_TRUE(mc_comm_can_busy(&m));
  EXPECT_EQ(MC_CAN_ERR_MODE, Comm(MC_COMM_CAN_START)) << "already running";
  EXPECT_EQ(MC_CAN_ERR_MODE, Handle(MC_CAN_MSG_SET_CONTROL_MODE, {1.0f}));
  EXPECT_EQ(MC_CAN_ERR_MODE, Handle(MC_CAN_MSG_SET_ENABLE, {1.0f}));
  EXPECT_EQ(MC_CAN_ERR_MODE, Handle(MC_CAN_MSG_CLEAR_FAULTS, {}));
  (void)Drain();  // the CMD_ERROR replies
  Run(10u * kSlowDiv);
  const auto rx = Drain();
  ASSERT_FALSE(rx.empty());
  EXPECT_EQ(MC_CAN_MSG_COMMISSION_STATUS, rx[0].msg);
  EXPECT_EQ(static_cast<float>(MC_COMM_STEP_OFFSETS), rx[0].v[MC_CAN_COMMISSION_STATUS_STEP]);
  EXPECT_EQ(0.0f, rx[0].v[MC_CAN_COMMISSION_STATUS_ERROR]);
  // the next status at the configured 10 Hz: 200 slow steps
  Run(200u * kSlowDiv);
  const auto rx2 = Drain();
  ASSERT_EQ(1u, rx2.size());
  EXPECT_EQ(MC_CAN_MSG_COMMISSION_STATUS, rx2[0].msg);
  EXPECT_EQ(1.0f, rx2[0].v[MC_CAN_COMMISSION_STATUS_SEQ]);
}

TEST_F(CommCan, FailedRunStagesNothingAndLeavesTheFault) {
  Boot();
  const mc_params_t staged_before = srv.staged;
  ASSERT_EQ(MC_CAN_ERR_NONE, Comm(MC_COMM_CAN_START));
  Run(static_cast<uint32_t>(2.0f / cfg.foc.dt_s));  // nothing conducts: NO_MOTOR
  EXPECT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
  EXPECT_FALSE(fake.pwm3.enabled);
  EXPECT_FALSE(m.running);
  EXPECT_EQ(static_cast<uint8_t>(MC_COMM_STEP_FAILED), m.step);
  EXPECT_NE(0u, m.err & MC_COMM_ERR_NO_MOTOR);
  EXPECT_FALSE(m.staged);
  EXPECT_EQ(0, std::memcmp(&staged_before, &srv.staged, sizeof staged_before));
  EXPECT_FALSE(srv.pending);
  EXPECT_EQ(nullptr, d.ctrl) << "the application's plug-in (none) is back";
  bool saw_failed = false;
  for (const auto& r : Drain()) {
    if (r.msg == MC_CAN_MSG_COMMISSION_STATUS &&
        r.v[MC_CAN_COMMISSION_STATUS_STEP] == static_cast<float>(MC_COMM_STEP_FAILED)) {
      saw_failed = true;
      EXPECT_EQ(static_cast<float>(MC_COMM_ERR_NO_MOTOR), r.v[MC_CAN_COMMISSION_STATUS_ERROR]);
      EXPECT_EQ(0.0f, r.v[MC_CAN_COMMISSION_STATUS_STAGED]);
    }
    EXPECT_NE(MC_CAN_MSG_COMMISSION_RESULT, r.msg) << "no results of a failed run";
  }
  EXPECT_TRUE(saw_failed);
  EXPECT_EQ(MC_CAN_ERR_REFUSED, Comm(MC_COMM_CAN_REPORT)) << "nothing to report";
  EXPECT_EQ(MC_CAN_ERR_REFUSED, Comm(MC_COMM_CAN_START)) << "the fault is latched";
}

TEST_F(CommCan, AbortOpensTheBridgeWithoutAFault) {
  Boot();
  ASSERT_EQ(MC_CAN_ERR_NONE, Comm(MC_COMM_CAN_START));
  Run(100u);
  ASSERT_TRUE(fake.pwm3.enabled);
  ASSERT_EQ(MC_CAN_ERR_NONE, Comm(MC_COMM_CAN_ABORT));
  EXPECT_FALSE(fake.pwm3.enabled);
  EXPECT_EQ(MC_DRIVE_MODE_IDLE, d.mode);
  EXPECT_NE(0u, m.err & MC_COMM_ERR_ABORTED);
  EXPECT_FALSE(m.staged);
  // SET_ENABLE 0 during a run ends it the same way
  ASSERT_EQ(MC_CAN_ERR_NONE, Comm(MC_COMM_CAN_START));
  Run(10u * kSlowDiv);
  ASSERT_EQ(MC_CAN_ERR_NONE, Handle(MC_CAN_MSG_SET_ENABLE, {0.0f}));
  Run(kSlowDiv);
  EXPECT_FALSE(m.running);
  EXPECT_EQ(MC_COMM_ERR_ABORTED, m.err);
}

TEST_F(CommCan, DoneStagesEveryResultThenApplyPutsThemInEffect) {
  Boot();
  ASSERT_EQ(MC_CAN_ERR_NONE, Comm(MC_COMM_CAN_START));
  Run(10u * kSlowDiv);
  (void)Drain();
  const mc_params_t active_before = srv.active;
  comm.res = FullResultWithMech();
  comm.step = MC_COMM_STEP_DONE;  // as the plug-in leaves it
  Run(20u * kSlowDiv);
  EXPECT_EQ(MC_DRIVE_MODE_IDLE, d.mode);
  EXPECT_FALSE(fake.pwm3.enabled);
  ASSERT_TRUE(m.staged);
  EXPECT_TRUE(srv.pending);
  EXPECT_EQ(0, std::memcmp(&active_before, &srv.active, sizeof active_before)) << "not applied";
  const mc_params_t& s = srv.staged;
  EXPECT_EQ(0.2f, s.r_ohm);
  EXPECT_EQ(1e-4f, s.ld_h);
  EXPECT_EQ(1.5e-4f, s.lq_h);
  EXPECT_EQ(0.02f, s.flux_wb);
  EXPECT_EQ(7u, s.pole_pairs);
  EXPECT_EQ(1.25f, s.encoder_offset_rad);
  EXPECT_EQ(1u, s.encoder_reversed);
  EXPECT_EQ(p.i_offset_a_a + 0.1f, s.i_offset_a_a);
  EXPECT_EQ(p.i_offset_b_a - 0.05f, s.i_offset_b_a);
  EXPECT_EQ(2e-4f, s.j_kgm2);
  EXPECT_EQ(1e-5f, s.b_nm_s_rad);
  // the speed gains are staged as derived (0), and derive from the new J
  EXPECT_EQ(0.0f, s.speed_kp_a_s_rad);
  EXPECT_EQ(0.0f, s.speed_ki_a_rad);
  mc_params_eff_t e;
  mc_params_resolve(&s, &e);
  float kp = 0, ki = 0;
  ASSERT_EQ(MC_GAINS_OK, mc_gains_speed_pi(static_cast<double>(2e-4f),
                                           mc_gains_kt_nm_a(7.0, static_cast<double>(0.02f)),
                                           e.g.speed_wc_rad_s, &kp, &ki));
  EXPECT_EQ(kp, e.p.speed_kp_a_s_rad);
  EXPECT_EQ(ki, e.p.speed_ki_a_rad);
  // the end status, then one result per slow step, bit-exact
  const auto rx = Drain();
  ASSERT_EQ(1u + MC_COMM_CAN_ITEM_COUNT, rx.size());
  EXPECT_EQ(MC_CAN_MSG_COMMISSION_STATUS, rx[0].msg);
  EXPECT_EQ(static_cast<float>(MC_COMM_STEP_DONE), rx[0].v[MC_CAN_COMMISSION_STATUS_STEP]);
  EXPECT_EQ(100.0f, rx[0].v[MC_CAN_COMMISSION_STATUS_PROGRESS_PCT]);
  EXPECT_EQ(1.0f, rx[0].v[MC_CAN_COMMISSION_STATUS_STAGED]);
  const float want[MC_COMM_CAN_ITEM_COUNT] = {
      0.2f,  1e-4f,          1.5e-4f,        0.02f,          7.0f,  1.25f,
      -1.0f, s.i_offset_a_a, s.i_offset_b_a, s.i_offset_c_a, 2e-4f, 1e-5f};
  for (uint32_t i = 0; i < MC_COMM_CAN_ITEM_COUNT; ++i) {
    EXPECT_EQ(MC_CAN_MSG_COMMISSION_RESULT, rx[1 + i].msg);
    EXPECT_EQ(static_cast<float>(i), rx[1 + i].v[MC_CAN_COMMISSION_RESULT_ITEM]);
    float got;
    std::memcpy(&got, &rx[1 + i].raw_hi, sizeof got);
    EXPECT_EQ(want[i], got) << "item " << i;
  }
  // APPLY through the service: the whole-set check, then in effect with the
  // current loop re-derived (kp = L bw, ki = R bw)
  uint32_t v = 0;
  ASSERT_EQ(MC_PARAM_OK, mc_param_srv_request(&srv, MC_PARAM_OP_APPLY, 0u, &v));
  EXPECT_EQ(0.2f, d.cfg.foc.r_ohm);
  EXPECT_EQ(7u, d.cfg.pole_pairs);
  EXPECT_TRUE(d.cfg.encoder_reversed);
  EXPECT_EQ(s.i_offset_a_a, d.cfg.i_offset_a[0]);
  float kpd = 0, kid = 0;
  // (the bandwidth the set derives: the table's current_bw_rad_s is 0)
  ASSERT_EQ(0u, mc_foc_f32_gains_from_bandwidth(0.2f, 1e-4f, e.p.current_bw_rad_s, &kpd, &kid));
  EXPECT_EQ(kpd, d.cfg.foc.kp_d_v_per_a);
  EXPECT_EQ(kid, d.cfg.foc.ki_d_v_per_as);
  // REPORT sends them again
  ASSERT_EQ(MC_CAN_ERR_NONE, Comm(MC_COMM_CAN_REPORT));
  Run(20u * kSlowDiv);
  EXPECT_EQ(1u + MC_COMM_CAN_ITEM_COUNT, Drain().size());
}

TEST_F(CommCan, AResultTheTableRefusesStagesNothing) {
  Boot();
  const mc_params_t staged_before = srv.staged;
  ASSERT_EQ(MC_CAN_ERR_NONE, Comm(MC_COMM_CAN_START));
  Run(10u * kSlowDiv);
  comm.res = FullResultWithMech();
  comm.res.lq_h = 2.0f;  // above the table's 1 H: the 4th write is refused
  comm.step = MC_COMM_STEP_DONE;
  Run(20u * kSlowDiv);
  EXPECT_FALSE(m.staged);
  EXPECT_EQ(MC_COMM_ERR_RANGE, m.err);
  EXPECT_EQ(static_cast<uint8_t>(MC_COMM_STEP_FAILED), m.step);
  EXPECT_EQ(0, std::memcmp(&staged_before, &srv.staged, sizeof staged_before))
      << "the writes before the refused one are undone";
  EXPECT_FALSE(srv.pending);
  for (const auto& r : Drain()) EXPECT_NE(MC_CAN_MSG_COMMISSION_RESULT, r.msg);
}

}  // namespace
}  // namespace apptest
