// The verdict machinery of mcsim (sim/cli/verdict.hpp, run.hpp): the Judge,
// the drive's fault names, the runner's outcome for each way a run ends,
// the step count and the JSON string escaping. The scenarios' own verdicts
// are exercised end to end by test_mcsim_cli.py and test_mcsim_motor_cli.py.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "run.hpp"
#include "scenario.hpp"
#include "verdict.hpp"
extern "C" {
#include "mc_drive.h"
}

namespace mcsim {
namespace {

TEST(Judge, PassListsEveryCheckAndItsBound) {
  Judge j;
  j.at_most("too slow", "time [s]", 1.0, 2.0, "the reason");
  j.within("off", "ratio", 1.0, 0.75, 1.25);
  const Verdict v = j.verdict();
  EXPECT_EQ(v.verdict, "pass");
  EXPECT_TRUE(v.pass());
  EXPECT_EQ(v.detail, "time [s] = 1 <= 2 (the reason); ratio = 1 in [0.75, 1.25]");
}

TEST(Judge, TheFirstFailedCheckNamesTheVerdictAndNaNFails) {
  Judge j;
  j.at_most("fine", "a", 1.0, 2.0);
  j.at_least("not reached", "b", std::nan(""), 1.0);  // never measured: a failure
  j.at_most("too slow", "c", 3.0, 2.0);
  const Verdict v = j.verdict();
  EXPECT_EQ(v.verdict, "not reached");
  EXPECT_FALSE(v.pass());
  EXPECT_EQ(v.detail, "b = nan >= 1 FAILED; c = 3 <= 2 FAILED");
}

TEST(FaultNames, EveryDriveFaultBitHasItsName) {
  const uint32_t all[] = {
      MC_DRIVE_FAULT_ADC,       MC_DRIVE_FAULT_MEAS_NAN,  MC_DRIVE_FAULT_OVERCURRENT,
      MC_DRIVE_FAULT_VBUS_LOW,  MC_DRIVE_FAULT_VBUS_HIGH, MC_DRIVE_FAULT_ENCODER,
      MC_DRIVE_FAULT_CONTROL,   MC_DRIVE_FAULT_PWM,       MC_DRIVE_FAULT_HW_INPUT,
      MC_DRIVE_FAULT_OVERSPEED, MC_DRIVE_FAULT_OVERTEMP,  MC_DRIVE_FAULT_OVERRUN,
      MC_DRIVE_FAULT_STALL,     MC_DRIVE_FAULT_EXTERNAL,  MC_DRIVE_FAULT_UNBALANCED,
      MC_DRIVE_FAULT_OPEN_PHASE};
  for (uint32_t f : all) {
    const std::string n = drive_fault_names(f);
    EXPECT_EQ(n.find("BIT"), std::string::npos) << f;
    EXPECT_EQ(n.find('|'), std::string::npos) << f;
  }
  // (the constants kept out of the assertions: tools/docs lists the tests
  // that assert a fault's behaviour by the constants they name)
  const uint32_t two = MC_DRIVE_FAULT_OVERCURRENT | MC_DRIVE_FAULT_VBUS_HIGH;
  const uint32_t bus = MC_DRIVE_FAULT_VBUS_HIGH;
  EXPECT_EQ(drive_fault_names(two), "OVERCURRENT|VBUS_HIGH");
  EXPECT_EQ(drive_fault_names(1u << 31), "BIT31");  // a bit the table lacks, still named
  EXPECT_EQ(faulted(bus).verdict, "faulted: VBUS_HIGH");
}

TEST(CurrentStep, RiseJudgedOnlyWhereTheDesignClaimsIt) {
  CurrentStepFigures f;
  f.iq_step_a = 10;
  f.id_step_a = -5;
  f.iq_rise_ratio = 1.3;  // 30 % slow
  f.id_rise_ratio = 1.0;
  f.iq_final_a = 10;
  f.id_final_a = -5;
  f.lsb_a = 0.01;
  f.t_id_step_s = 0.01;
  f.duration_s = 0.02;
  f.bw_t = 0.08;
  EXPECT_EQ(judge_current_step(f).verdict, "rise time off design");
  f.bw_t = 0.1;  // beyond the design's range: the rise is reported, not judged
  EXPECT_EQ(judge_current_step(f).verdict, "pass");
  f.iq_final_a = 10.3;  // 3 % off at the end
  EXPECT_EQ(judge_current_step(f).verdict, "not settled");
  f.iq_final_a = 10;
  f.duration_s = 0.005;  // the d step after the run's end
  EXPECT_EQ(judge_current_step(f).verdict, "target not reached");
}

TEST(Commission, AVerificationTheLawRefusesIsNotJudged) {
  CommissionFigures f;
  f.done = true;
  f.duration_s = 5;
  f.verify = true;
  f.verify_sensored_err_frac = 0.01;
  f.verify_sensorless_err_frac = 0.03;
  EXPECT_EQ(judge_commission(f).verdict, "pass");
  f.verify_sensored_err_frac = std::nan("");  // the speed step faulted
  EXPECT_EQ(judge_commission(f).verdict, "verification failed");
  f.sensored_refused = true;  // no safe gains for this pair: not run
  const Verdict v = judge_commission(f);
  EXPECT_EQ(v.verdict, "pass");
  EXPECT_NE(v.detail.find("no safe gains for the sensored law: not run"), std::string::npos);
  f.flux_frac = 0.04;  // identification still judged
  EXPECT_EQ(judge_commission(f).verdict, "identification inaccurate");
  f.done = false;
  f.error_names = "ROTOR_BLOCKED";
  EXPECT_EQ(judge_commission(f).verdict, "commissioning failed: ROTOR_BLOCKED");
  EXPECT_TRUE(judge_commission(f).stopped);
}

TEST(StepCount, RefusesACountThatDoesNotFit) {
  EXPECT_EQ(step_count(1.0, 5e-5), 20000);
  EXPECT_EQ(step_count(0.0, 5e-5), 0);
  EXPECT_THROW(step_count(1e300, 5e-5), UsageError);
  EXPECT_THROW(step_count(3600.0, 1e-6), UsageError);  // 3.6e9 > kMaxSteps
  EXPECT_THROW(step_count(-1.0, 5e-5), UsageError);
  EXPECT_THROW(step_count(std::nan(""), 5e-5), UsageError);
  EXPECT_THROW(step_count(1.0, 0.0), UsageError);
}

TEST(Json, EveryControlCharacterIsEscaped) {
  std::string all;
  for (int c = 0; c < 0x20; ++c) all += static_cast<char>(c);
  const std::string j = json_string(all);
  for (char c : j) EXPECT_GE(static_cast<unsigned char>(c), 0x20u) << static_cast<int>(c);
  EXPECT_EQ(j.substr(0, 8), "\"\\u0000\\");
  EXPECT_NE(j.find("\\b\\t\\n\\u000b\\f\\r"), std::string::npos) << j;
  EXPECT_EQ(json_string("a\"b\\c"), "\"a\\\"b\\\\c\"");
  // valid UTF-8 kept, invalid bytes as U+FFFD (an overlong NUL, a lone
  // continuation byte, a truncated sequence, a surrogate)
  EXPECT_EQ(json_string("\xc3\xa9\xe2\x82\xac"), "\"\xc3\xa9\xe2\x82\xac\"");
  EXPECT_EQ(json_string("\xc0\x80"), "\"\\ufffd\\ufffd\"");
  EXPECT_EQ(json_string("x\x80y"), "\"x\\ufffdy\"");
  EXPECT_EQ(json_string("\xe2\x82"), "\"\\ufffd\\ufffd\"");
  EXPECT_EQ(json_string("\xed\xa0\x80"), "\"\\ufffd\\ufffd\\ufffd\"");
}

// A scenario of this test only: its parameter says how the run ends.
void run_outcome(RunContext& ctx) {
  ctx.csv.columns({"t"});
  ctx.csv.row({0.0});
  switch (static_cast<int>(ctx.params.get("how"))) {
    case 0:
      return write_verdict(ctx.summary, Verdict{"pass", "fine"});
    case 1:
      return write_no_claim(ctx.summary, "nothing to check");
    case 2:
      return write_verdict(ctx.summary, Verdict{"not settled", "x = 3 <= 2 FAILED"});
    case 3:
      throw UsageError("refused inside");
    case 4:
      throw std::runtime_error("plant state diverged");
    case 5: {
      const uint32_t overspeed = MC_DRIVE_FAULT_OVERSPEED;
      return write_verdict(ctx.summary, faulted(overspeed));
    }
    default:
      return;  // no verdict: a programming error
  }
}
const Registrar reg_outcome({"test-outcome",
                             "a test scenario",
                             1.0,
                             {{"how", 0.0, "1", "how the run ends", 0.0, 6.0}},
                             run_outcome});

RunOutcome outcome(int how, Summary* s) {
  const PreparedRun r = prepare_run("test-outcome", "", "", {{"how", std::to_string(how)}});
  ColumnSink sink;
  Progress p(false);
  return execute_run(r, sink, *s, p);
}

TEST(Runner, EachWayARunEnds) {
  using K = RunOutcome::Kind;
  Summary s0, s1, s2, s3, s4, s5, s6;
  EXPECT_EQ(outcome(0, &s0).kind, K::kPass);
  EXPECT_EQ(outcome(1, &s1).kind, K::kPass);
  EXPECT_EQ(s1.texts().at("verdict"), "none");
  const RunOutcome f = outcome(2, &s2);
  EXPECT_EQ(f.kind, K::kFailed);
  EXPECT_FALSE(f.stopped);
  EXPECT_EQ(f.message, "run failed: not settled (x = 3 <= 2 FAILED)");
  const RunOutcome r = outcome(3, &s3);
  EXPECT_EQ(r.kind, K::kRefused);
  EXPECT_EQ(r.message, "refused inside");
  const RunOutcome x = outcome(4, &s4);
  EXPECT_EQ(x.kind, K::kFailed);
  EXPECT_TRUE(x.stopped);
  EXPECT_EQ(s4.texts().at("verdict"), "failed: plant state diverged");
  EXPECT_EQ(s4.numbers().at("rows"), 1.0);
  const RunOutcome ft = outcome(5, &s5);  // a fault ends the run: stopped
  EXPECT_EQ(ft.kind, K::kFailed);
  EXPECT_TRUE(ft.stopped);
  EXPECT_EQ(s5.numbers().at("stopped"), 1.0);
  EXPECT_EQ(s2.numbers().at("stopped"), 0.0);
  EXPECT_THROW(outcome(6, &s6), std::logic_error);
}

TEST(Runner, DurationsAreBounded) {
  EXPECT_NO_THROW(prepare_run("test-outcome", "", "", {}, "", kMaxDurationS));
  EXPECT_THROW(prepare_run("test-outcome", "", "", {}, "", 1.0001 * kMaxDurationS), UsageError);
  EXPECT_THROW(prepare_run("test-outcome", "", "", {}, "", 1e300), UsageError);
  EXPECT_THROW(prepare_run("test-outcome", "", "", {}, "", -1.0), UsageError);
  EXPECT_THROW(prepare_run("pi2d-certificate", "", "", {}, "", 1.0), UsageError);
  EXPECT_EQ(prepare_run("test-outcome", "", "", {}).duration_s, 1.0);  // the default
}

}  // namespace
}  // namespace mcsim
