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

#include <cmath>
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
    p.angle_ref = angle_ref;
    p.encoder_cpr = encoder_cpr;
    ASSERT_EQ(MC_PARAMS_OK, mc_params_to_drive_cfg(&p, &cfg));
    InitDrive();
    GoodSample();  // the bus measured, as by the fast loop of a drive at rest
    (void)mc_drive_fast_step(&d);
    ASSERT_EQ(0, mc_param_srv_init(&srv, &p, &d, hal, nullptr, 0u));
    mc_can_cmd_cfg_t cc{};
    cc.node_id = 1u;
    cc.tick_hz = 2000u;
    cc.timeout_s = timeout_s;
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
    if (attach) {
      mc_can_cmd_attach_commission(&c, mc_comm_can_command, mc_comm_can_busy, mc_comm_can_host_lost,
                                   &m);
    }
  }
  mc_can_err_t Handle(uint32_t msg, const std::vector<float>& v) {
    mc_hal_can_frame_t f{};
    const float none = 0.0f;  // a message without signals still needs a pointer
    EXPECT_EQ(MC_CAN_ERR_NONE, mc_can_proto_pack(msg, 1u, v.empty() ? &none : v.data(),
                                                 static_cast<uint32_t>(v.size()), &f));
    return mc_can_cmd_handle(&c, &f, &fake.can_dev);
  }
  mc_can_err_t Comm(uint32_t action, float i_test = 0.0f, float v_test = 0.0f, float speed = 0.0f) {
    return Handle(MC_CAN_MSG_COMMISSION_CMD, {static_cast<float>(action), i_test, v_test, speed});
  }
  // n PWM periods with zero phase currents, the slow loop every kSlowDiv:
  // the command handler's step (timeout, reply limiter), the host's
  // HOST_HEARTBEAT every hb_every slow steps while `host`, and the
  // commissioning step with the handler's reply limiter; the bus takes the
  // frames sent at each slow step (the fake's queue holds 8, a bus
  // controller's mailboxes empty as fast).
  void Run(uint32_t n) {
    for (uint32_t k = 1; k <= n; ++k) {
      ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, 0.0f, 0.0f, 0.0f, kVbus, kMask3));
      (void)mc_drive_fast_step(&d);
      if (k % kSlowDiv == 0u) {
        if (host && (slow_n % hb_every == 0u)) {
          ASSERT_EQ(MC_CAN_ERR_NONE, Handle(MC_CAN_MSG_HOST_HEARTBEAT, {static_cast<float>(hb)}));
          hb = static_cast<uint8_t>(hb + 1u);
        }
        ++slow_n;
        mc_can_cmd_step(&c);
        mc_comm_can_step(&m, &fake.can_dev, &c.reply);
        Collect();
      }
    }
  }
  uint32_t angle_ref = MC_DRIVE_ANGLE_REF_STORED;        // the table's, at Boot
  uint32_t encoder_cpr = mc_params_default.encoder_cpr;  // 0: the table has no encoder
  bool host = true;                                      // the host sends its keep-alive ...
  uint32_t hb_every = 100u;                              // ... every this many slow steps
  float timeout_s = 0.5f;                                // the command timeout (1000 slow steps)
  uint8_t hb = 0;
  uint32_t slow_n = 0;
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

// With angle_ref index the offset is measured against the index: a START
// before the index has been seen after power-up is refused and energises
// nothing; once an encoder sample carries the index, it runs.
TEST_F(CommCan, IndexReferenceRefusedUntilTheIndexIsSeen) {
  angle_ref = MC_DRIVE_ANGLE_REF_INDEX;
  Boot();
  ASSERT_EQ(MC_DRIVE_ANGLE_NEED_INDEX, mc_drive_angle_state(&d));
  EXPECT_EQ(MC_CAN_ERR_REFUSED, Comm(MC_COMM_CAN_START));
  EXPECT_EQ(MC_DRIVE_MODE_IDLE, d.mode);
  EXPECT_FALSE(m.running);
  EXPECT_FALSE(fake.pwm3.enabled) << "nothing energised";
  ASSERT_EQ(
      0, mc_hal_fake_encoder_set(&fake, 0u, MC_HAL_ENCODER_FLAG_VALID | MC_HAL_ENCODER_FLAG_INDEX));
  GoodSample();
  (void)mc_drive_fast_step(&d);
  ASSERT_EQ(MC_DRIVE_ANGLE_KNOWN, mc_drive_angle_state(&d));
  EXPECT_EQ(MC_CAN_ERR_NONE, Comm(MC_COMM_CAN_START));
  EXPECT_TRUE(m.running);
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
      EXPECT_EQ(0.0f, r.v[MC_CAN_COMMISSION_STATUS_DETAIL]) << "a bit of its own: no detail";
      EXPECT_EQ(0.0f, r.v[MC_CAN_COMMISSION_STATUS_STAGED]);
    }
    EXPECT_NE(MC_CAN_MSG_COMMISSION_RESULT, r.msg) << "no results of a failed run";
  }
  EXPECT_TRUE(saw_failed);
  EXPECT_EQ(MC_CAN_ERR_REFUSED, Comm(MC_COMM_CAN_REPORT)) << "nothing to report";
  EXPECT_EQ(MC_CAN_ERR_REFUSED, Comm(MC_COMM_CAN_START)) << "the fault is latched";
}

// A refusal the status frame's 16-bit error field has no bit for (the flux
// step's checks, MC_COMM_ERR_WIDE_MASK): set in the running sequence as its
// coast end would, the drive faults on the next fast step, and the status
// frame says RANGE with the reason in its detail field; nothing staged.
TEST_F(CommCan, AWideRefusalTravelsAsRangeWithItsDetail) {
  Boot();
  ASSERT_EQ(MC_CAN_ERR_NONE, Comm(MC_COMM_CAN_START));
  Run(kSlowDiv * 10u);
  ASSERT_TRUE(m.running);
  comm.err |= MC_COMM_ERR_MECH_SPIN_COAST;
  Run(kSlowDiv * 10u);
  EXPECT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
  EXPECT_FALSE(m.running);
  EXPECT_EQ(MC_COMM_ERR_MECH_SPIN_COAST, m.err);
  EXPECT_FALSE(m.staged);
  bool saw_failed = false;
  for (const auto& r : Drain()) {
    if (r.msg == MC_CAN_MSG_COMMISSION_STATUS &&
        r.v[MC_CAN_COMMISSION_STATUS_STEP] == static_cast<float>(MC_COMM_STEP_FAILED)) {
      saw_failed = true;
      EXPECT_EQ(static_cast<float>(MC_COMM_ERR_RANGE), r.v[MC_CAN_COMMISSION_STATUS_ERROR]);
      EXPECT_EQ(static_cast<float>(MC_COMM_DETAIL_MECH_SPIN_COAST),
                r.v[MC_CAN_COMMISSION_STATUS_DETAIL]);
    }
  }
  EXPECT_TRUE(saw_failed);
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
  // 13 frames under the reply limiter: what is left of the bucket (the
  // progress statuses took it), then one token per 50 slow steps (40 per
  // second at 2 kHz)
  Run(1000u * kSlowDiv);
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
  // the end status, then the results in order, bit-exact
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
  Run(1000u * kSlowDiv);
  EXPECT_EQ(1u + MC_COMM_CAN_ITEM_COUNT, Drain().size());
}

// encoder_cpr 0 in force: START runs the sequence without an encoder (the
// plug-in does not ask for one; the pole pairs are the table's); when done
// the motor's values are staged, the encoder's offset and direction (not
// measured) stay as they are, and the status's valid carries SENSORLESS.
TEST_F(CommCan, WithoutAnEncoderRunsOnThePolePairsInForceAndStagesNoEncoderValues) {
  encoder_cpr = 0u;
  Boot();
  ASSERT_EQ(0u, p.encoder_cpr);
  ASSERT_EQ(MC_CAN_ERR_NONE, Comm(MC_COMM_CAN_START));
  EXPECT_EQ(MC_DRIVE_MODE_CTRL, d.mode);
  EXPECT_EQ(p.pole_pairs, comm.cfg.pole_pairs_given);
  EXPECT_FALSE(mc_comm_ops(&comm)->needs_encoder);
  Run(10u * kSlowDiv);
  (void)Drain();
  mc_comm_result_t r = FullResult();
  r.valid = (r.valid & ~MC_COMM_HAVE_ENCODER) | MC_COMM_SENSORLESS;
  r.encoder_offset_rad = 0.0f;
  r.encoder_direction = 0;
  r.pole_pairs = p.pole_pairs;
  comm.res = r;
  comm.step = MC_COMM_STEP_DONE;
  Run(1000u * kSlowDiv);
  ASSERT_TRUE(m.staged);
  const mc_params_t& s = srv.staged;
  EXPECT_EQ(0.02f, s.flux_wb);
  EXPECT_EQ(0.2f, s.r_ohm);
  EXPECT_EQ(p.encoder_offset_rad, s.encoder_offset_rad);
  EXPECT_EQ(p.encoder_reversed, s.encoder_reversed);
  EXPECT_EQ(p.j_kgm2, s.j_kgm2);  // no mechanics measured
  const auto rx = Drain();
  ASSERT_FALSE(rx.empty());
  EXPECT_EQ(MC_CAN_MSG_COMMISSION_STATUS, rx[0].msg);
  EXPECT_EQ(static_cast<float>(r.valid), rx[0].v[MC_CAN_COMMISSION_STATUS_VALID]);
}

// With an encoder the plug-in asks for it (and measures the pole pairs).
TEST_F(CommCan, WithAnEncoderThePolePairsAreMeasured) {
  Boot();
  ASSERT_NE(0u, p.encoder_cpr);
  ASSERT_EQ(MC_CAN_ERR_NONE, Comm(MC_COMM_CAN_START));
  EXPECT_EQ(0u, comm.cfg.pole_pairs_given);
  EXPECT_TRUE(mc_comm_ops(&comm)->needs_encoder);
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

// Issue 28: commissioning energised the motor from one frame and ran on
// with no host alive. Now it needs the keep-alive as an enabled drive. On
// the fake (no current flows) the sequence fails NO_MOTOR after about
// 0.2 s, so the timeout here is 0.05 s (100 slow steps) and the host's
// heartbeats come every 40 steps. The host falls silent after its
// heartbeat at slow step 40; at step 140 the bridge is open, the run
// FAILED with HOST_LOST, the HEARTBEAT's stop reason CMD_TIMEOUT. Exact:
// the step counts are integers.
TEST_F(CommCan, RunWithoutTheHostsKeepAliveIsAbortedAtTheTimeout) {
  timeout_s = 0.05f;
  hb_every = 40u;
  Boot();
  ASSERT_EQ(MC_CAN_ERR_NONE, Comm(MC_COMM_CAN_START));
  ASSERT_TRUE(fake.pwm3.enabled);
  Run(60u * kSlowDiv);  // heartbeats at slow steps 0 and 40
  host = false;         // silence from here
  uint32_t steps = 0;
  while (m.running && steps < 4000u) {
    Run(kSlowDiv);
    ++steps;
  }
  EXPECT_EQ(140u, 60u + steps) << "the timeout (100 steps) after the last heartbeat (step 40)";
  EXPECT_FALSE(m.running);
  EXPECT_FALSE(fake.pwm3.enabled) << "bridge open";
  EXPECT_EQ(MC_DRIVE_MODE_IDLE, d.mode);
  EXPECT_EQ(MC_COMM_ERR_ABORTED | MC_COMM_ERR_HOST_LOST, m.err);
  EXPECT_EQ(static_cast<uint8_t>(MC_COMM_STEP_FAILED), m.step);
  EXPECT_EQ(MC_CAN_STOP_CMD_TIMEOUT, c.stop_reason);
  Run(100u * kSlowDiv);  // the end status under the reply limiter
  bool said = false;
  for (const auto& r : Drain()) {
    if (r.msg == MC_CAN_MSG_COMMISSION_STATUS &&
        r.v[MC_CAN_COMMISSION_STATUS_STEP] == static_cast<float>(MC_COMM_STEP_FAILED)) {
      said = r.v[MC_CAN_COMMISSION_STATUS_ERROR] ==
             static_cast<float>(MC_COMM_ERR_ABORTED | MC_COMM_ERR_HOST_LOST);
    }
  }
  EXPECT_TRUE(said) << "COMMISSION_STATUS FAILED with ABORTED | HOST_LOST";
}

// With the host alive the same run goes on past the timeout (three of
// them): only a fresh HOST_HEARTBEAT keeps it, a repeated counter does not.
TEST_F(CommCan, AdvancingHeartbeatsKeepItRepeatsDoNot) {
  timeout_s = 0.05f;
  hb_every = 40u;
  Boot();
  ASSERT_EQ(MC_CAN_ERR_NONE, Comm(MC_COMM_CAN_START));
  Run(300u * kSlowDiv);  // heartbeats at 0, 40, ..., 280
  EXPECT_TRUE(m.running) << "err 0x" << std::hex << m.err;
  host = false;
  uint32_t steps = 0;
  for (; steps < 400u && m.running; ++steps) {
    if (steps % 20u == 0u) {  // the last counter again
      EXPECT_EQ(MC_CAN_ERR_STALE, Handle(MC_CAN_MSG_HOST_HEARTBEAT,
                                         {static_cast<float>(static_cast<uint8_t>(hb - 1u))}));
    }
    Run(kSlowDiv);
  }
  EXPECT_EQ(80u, steps) << "timeout 100 steps after the last fresh one (step 280)";
  EXPECT_FALSE(m.running);
  EXPECT_EQ(MC_COMM_ERR_ABORTED | MC_COMM_ERR_HOST_LOST, m.err);
}

// Issue 28: i_test 65 A on a 20 A sensor and v_test_max 600 V on a 200 V
// bus were accepted. The test values in force are checked against the
// drive's limits: an option beyond them refused RANGE, nothing energised,
// nothing changed; a zero option bounded by them.
TEST_F(CommCan, TestValuesBeyondTheDrivesLimitsAreRefusedNothingEnergised) {
  Boot();
  const float v_max = kVbus / std::sqrt(3.0f);  // the vector the bus can make
  struct Case {
    float i, v, w;
    const char* what;
  } cases[] = {
      {p.i_max_a + 0.01f, 0.0f, 0.0f, "i_test above i_max_a"},
      {65.0f, 0.0f, 0.0f, "the issue's 65 A"},
      {0.0f, v_max + 0.01f, 0.0f, "v_test_max above v_bus / sqrt 3"},
      {0.0f, 600.0f, 0.0f, "the issue's 600 V"},
      {0.0f, 0.0f, p.speed_max_rad_s + 0.1f, "speed above speed_max_rad_s"},
  };
  for (const auto& k : cases) {
    const mc_drive_t d0 = d;
    EXPECT_EQ(MC_CAN_ERR_RANGE, Comm(MC_COMM_CAN_START, k.i, k.v, k.w)) << k.what;
    EXPECT_FALSE(m.running) << k.what;
    EXPECT_FALSE(fake.pwm3.enabled) << k.what;
    EXPECT_EQ(0, std::memcmp(&d0, &d, sizeof d)) << k.what << ": the drive changed";
  }
  // a bus not measured (the fast loop has not sampled it): refused
  d.tm.vbus_v = 0.0f;
  EXPECT_EQ(MC_CAN_ERR_RANGE, Comm(MC_COMM_CAN_START)) << "no bus measured";
  EXPECT_FALSE(fake.pwm3.enabled);
  // A zero option takes the board's default bounded by the drive's limits
  // (the images' boards default to a quarter of their sense range, above a
  // small motor's i_max_a): the bus sagging to 15 V bounds the 10 V
  // default to 15 V / sqrt 3, i_max_a 3 A the 4 A, speed_max_rad_s 50 the
  // 100 rad/s (each exact: min of two floats).
  auto sample = [&](float vbus) {  // one conversion, one fast step
    ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, 0.0f, 0.0f, 0.0f, vbus, kMask3));
    (void)mc_drive_fast_step(&d);
  };
  auto apply = [&](float i_max, float w_max) {  // the runtime limits, by the service
    uint32_t raw = 0;
    std::memcpy(&raw, &i_max, sizeof raw);
    ASSERT_EQ(MC_PARAM_OK,
              mc_param_srv_request(&srv, MC_PARAM_OP_WRITE, MC_PARAM_ID_I_MAX_A, &raw));
    std::memcpy(&raw, &w_max, sizeof raw);
    ASSERT_EQ(MC_PARAM_OK,
              mc_param_srv_request(&srv, MC_PARAM_OP_WRITE, MC_PARAM_ID_SPEED_MAX_RAD_S, &raw));
    raw = 0;
    ASSERT_EQ(MC_PARAM_OK, mc_param_srv_request(&srv, MC_PARAM_OP_APPLY, 0u, &raw));
  };
  {
    // the under-voltage trip at 12 V (derived it is half of vbus_v, 24 V:
    // a 15 V bus would be a fault, not a sag)
    uint32_t raw = 0;
    const float v_min = 12.0f;
    std::memcpy(&raw, &v_min, sizeof raw);
    ASSERT_EQ(MC_PARAM_OK,
              mc_param_srv_request(&srv, MC_PARAM_OP_WRITE, MC_PARAM_ID_VBUS_MIN_V, &raw));
  }
  apply(3.0f, 50.0f);
  sample(15.0f);
  ASSERT_EQ(15.0f, d.tm.vbus_v);
  ASSERT_EQ(MC_CAN_ERR_NONE, Comm(MC_COMM_CAN_START));
  EXPECT_EQ(15.0f * 0.57735026918962576f, comm.cfg.v_test_max_v);
  EXPECT_EQ(3.0f, comm.cfg.i_test_a);
  EXPECT_EQ(50.0f, comm.cfg.speed_max_m_rad_s);
  ASSERT_EQ(MC_CAN_ERR_NONE, Comm(MC_COMM_CAN_ABORT));
  // an option above them is still refused
  EXPECT_EQ(MC_CAN_ERR_RANGE, Comm(MC_COMM_CAN_START, 3.5f));
  apply(p.i_max_a, p.speed_max_rad_s);
  sample(kVbus);
  // without the parameter set the over-speed trip bounds it
  m.params = nullptr;
  EXPECT_EQ(MC_CAN_ERR_RANGE, Comm(MC_COMM_CAN_START, 0.0f, 0.0f, d.cfg.omega_max_rad_s));
  // at the limits themselves: accepted (the DBC's steps: 1 mA, 10 mV, 0.1 rad/s)
  // (10 rad/s below the trip: 440 of the derived 1.5 speed_max_rad_s)
  EXPECT_EQ(MC_CAN_ERR_NONE,
            Comm(MC_COMM_CAN_START, p.i_max_a, 13.85f, d.cfg.omega_max_rad_s - 10.0f));
  EXPECT_TRUE(m.running);
}

}  // namespace
}  // namespace apptest
