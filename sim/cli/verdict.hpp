// Verdicts: every scenario judges itself against the figures it exists to
// show and writes the result in its summary (sim/README.md, "Verdicts"):
//
//   verdict         "pass", "none" (the scenario has no claim to check: a
//                   demonstration, a sweep that maps where something stops
//                   working), or the named reason it failed: "faulted:
//                   OVERCURRENT|VBUS_HIGH", "not settled", "target not
//                   reached", ... (the first check that failed, in the order
//                   the scenario's judge lists them)
//   verdict_detail  each check that failed (all of them for a pass) with its
//                   figure and the bound it was held to
//   stopped         1 when the run ended before its end: the drive faulted
//                   (and opened the bridge), a sequence stopped with its
//                   error, or the run threw; 0 when it ran to its end
//
// mcsim exits 1 when the verdict is neither "pass" nor "none" (run.hpp).
// The judges take the figures a scenario computed (plain numbers) and hold
// them to the thresholds stated, with their reasons, in verdict.cpp; the
// scenarios call one judge at the end of a run. Nothing here runs a plant.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "scenario.hpp"

namespace mcsim {

struct Verdict {
  std::string verdict;  ///< "pass", "none" or the failure's name
  std::string detail;
  bool stopped = false;  ///< the run ended before its end (a fault, a sequence stopped)
  bool pass() const { return verdict == "pass" || verdict == "none"; }
};

/// Collects checks; verdict() names the first that failed. A NaN figure
/// fails its check (a time never reached, a metric never measured).
class Judge {
 public:
  /// value <= bound.
  Judge& at_most(const std::string& reason, const std::string& what, double value, double bound,
                 const std::string& why = "");
  /// value >= bound.
  Judge& at_least(const std::string& reason, const std::string& what, double value, double bound,
                  const std::string& why = "");
  /// lo <= value <= hi.
  Judge& within(const std::string& reason, const std::string& what, double value, double lo,
                double hi, const std::string& why = "");
  /// A condition without a figure (text says what held or did not).
  Judge& require(const std::string& reason, bool ok, const std::string& text);
  /// A note in the detail that judges nothing (what was not checked, why).
  Judge& note(const std::string& text);
  Verdict verdict() const;

 private:
  struct Check {
    std::string reason, text;
    bool ok;
  };
  std::vector<Check> checks_;
  std::vector<std::string> notes_;
};

/// Writes verdict, verdict_detail and stopped.
void write_verdict(Summary& s, const Verdict& v);
/// A scenario with no claim to check: verdict "none", the reason as detail.
void write_no_claim(Summary& s, const std::string& why);

/// The drive's fault bits (MC_DRIVE_FAULT_*) by name, "|"-separated, in bit
/// order ("OVERCURRENT|VBUS_HIGH"); a bit without a name as "BIT<n>".
std::string drive_fault_names(uint32_t faults);
/// "faulted: <names>" (stopped); extra (e.g. the law's reason) in the detail.
Verdict faulted(uint32_t faults, const std::string& extra = "");

// ------------------------------------------------ scenarios for any motor
struct CurrentStepFigures {
  double iq_step_a = 0, id_step_a = 0;          // the steps asked
  double iq_rise_ratio = 0, id_rise_ratio = 0;  // 10-90 % rise / design
  double iq_final_a = 0, id_final_a = 0;        // true currents at the end
  double lsb_a = 0;                             // the ADC's current step
  double t_id_step_s = 0, duration_s = 0;       // the d step, the run's end
  double bw_t = 0;                              // the design bandwidth times the PWM period
  double rise_tol = 0.25;                       // the rise's allowed distance from the design
  double iq_overshoot = 0, id_overshoot = 0;    // past the step, fraction of it
  double overshoot_max = 0.10;                  // first-order-like (the verdict's reason)
};
Verdict judge_current_step(const CurrentStepFigures& f);

struct SpeedStepFigures {
  bool load_step = false;               // load-step (else speed-step)
  double target_rad_s = 0;              // speed_rad_s
  double speed_limit_rad_s = 0;         // the derived speed limit
  double werr_max_steady_rad_s = 0;     // max |omega - target| over the steady window
  double id_max_steady_frac_rated = 0;  // max |i_d| / rated in that window
  double t_steady_from_s = 0;           // the window: [t_steady_from_s, duration_s]
  double t_event_s = 0;                 // the step's end of slew, or the load step
  double duration_s = 0;
};
Verdict judge_speed_step(const SpeedStepFigures& f);

struct SensorlessFigures {
  double target_rad_s = 0;
  bool locked = false;
  double werr_max_end_rad_s = 0;  // over the last 10 % after the load step
  double angle_err_max_rad = 0;   // after the lock
  double t_load_step_s = 0, duration_s = 0;
};
Verdict judge_sensorless(const SensorlessFigures& f);

struct PositionFigures {
  bool stream = false;
  double final_err_counts = 0;
  double overshoot_rad = 0;
  double move_time_s = 0, move_time_pred_s = 0;  // last entry within 1 count; the trapezoid's
  double dv_ref_max_rad_s = 0;                   // largest velocity-reference step per period
  double a_max_rad_s2 = 0, d_max_rad_s2 = 0;     // the trajectory's limits
  double pos_kp_per_s = 0, enc_bw_rad_s = 0;     // position P gain, encoder tracking loop
  double period_s = 0, duration_s = 0;
  double track_err_max_rad = 0;  // stream
};
Verdict judge_position(const PositionFigures& f);

struct FieldWeakeningFigures {
  double mtpa_rel_err_max = 0;
  double omega_final_rad_s = 0, target_rad_s = 0;
  double i_peak_a = 0, i_limit_a = 0;
  double id_min_a = 0, id_demag_bound_a = 0;
  bool fault_part = false;  // part 3 ran (fault=1): reported, not judged
};
Verdict judge_field_weakening(const FieldWeakeningFigures& f);

struct RegenFigures {
  double stop_time_s = 0;  // NaN: never below 2 % of the start speed for good
  double vbus_peak_v = 0, vbus_trip_v = 0;
  double energy_balance_rel_err = 0;
};
Verdict judge_regen_stop(const RegenFigures& f);

struct CommissionFigures {
  bool done = false;
  std::string error_names;  // MC_COMM_ERR_* when not done
  double r_frac = 0, ld_frac = 0, lq_frac = 0, flux_frac = 0;
  double pole_pairs_diff = 0, encoder_offset_deg = 0, adc_offset_max_frac = 0;
  bool direction_right = true;
  bool sensorless = false;  // no encoder: no offset or direction to judge
  double duration_s = 0;
  double duration_max_s = 10.0;  // + the Hall table's step with Hall sensors
  bool verify = false;
  double verify_sensored_err_frac = 0, verify_sensorless_err_frac = 0;
  bool sensorless_refused = false;  // the law takes no such motor (a salient one)
  // the motor and board have no safe gains for the speed PI (the pair's
  // limit, e.g. PWM ripple above i_max_a, not the identification's)
  bool sensored_refused = false;
};
Verdict judge_commission(const CommissionFigures& f);

struct CanTelemetryFigures {
  double tm_frames_dropped = 0, rx_overflows = 0, flash_persist_errors = 0;
  uint32_t final_faults = 0;
};
Verdict judge_can_telemetry(const CanTelemetryFigures& f);

}  // namespace mcsim
