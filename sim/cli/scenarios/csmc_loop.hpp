// The CSMC position loop of paper 001 (Seshagiri and Khalil) closed around
// the simulator's two-phase stepper (mcsim::Stepper2Ph, phase a/b model),
// with the drive's CSMC plug-in (firmware/app/ctrl/mc_ctrl_csmc, the one
// composition of the loop) as the controller, its step called on the
// plant's measurements (no drive, no encoder, no bridge):
//
//   every control period T (sampled data, zero-order hold):
//     measure i_a, i_b, w, phi at t_k (exact, no quantisation); e2 in double
//     mc_ctrl_csmc_step: dq transform at N_r phi, e from the state (state
//       feedback) or from the HGO (output feedback), CSMC / ideal SMC law,
//       inverse transform
//     (v_a, v_b) held over [t_k, t_k + T]
//     RK4 with n_sub sub-steps over the period
//
// The paper's figures 2, 3, 5 are continuous-time; a small T (default
// 10 us) makes the loop close to that. Fig. 4 is the sampled-data case
// (T = 0.1 ms). Used by the csmc-* scenarios and by tests/sil/csmc.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "csmc/mc_csmc.h"
#include "observer/mc_hgo.h"

namespace mcsim {
namespace csmc {

constexpr double kPaperStepRad = 0.03142;  // phi_d step of the paper [rad]

struct PlantOptions {
  double R_ohm = 19.0;  // actual resistance (Fig. 2; Fig. 3-5: 19.5)
  double L_h = 0.040;   // actual inductance (Fig. 2; Fig. 3-5: 0.030)
  double Km_nm_a = 0.1349;
  double J_kgm2 = 4.1295e-4;
  double B_nms_rad = 0.0013;
  int rotor_teeth = 50;
  double tau_load_nm = 0.2;
};

enum class RefKind { kSteps, kCos };
enum class Feedback { kState, kHgo };

struct LoopOptions {
  PlantOptions plant{};
  double dt_s = 1.0e-5;  // control period T
  int substeps = 1;      // RK4 sub-steps per period
  double duration_s = 1.0;
  RefKind ref = RefKind::kSteps;
  double step_rad = kPaperStepRad;  // kSteps: phi_d = step (u(t) + u(t - t2))
  double step2_t_s = 0.5;           //   second step time; < 0: none
  double r0_rad = 0.0;              // kCos: phi_d = r0 cos(w0 t)
  double w0_rad_s = 0.0;
  Feedback fb = Feedback::kState;
  mc_csmc_f32_cfg_t ctrl{};  // dt_s is overwritten with dt_s above
  mc_hgo_f32_cfg_t hgo{};    // used with kHgo; dt_s overwritten
  size_t record_every = 1;   // keep every n-th sample in the trace
};

// One recorded sample.
struct Sample {
  double t, e1, e2, x1, x2, x3, x4, u1, u2, z1, z2, z3, s1, s2, phi_d;
};

struct LoopResult {
  std::vector<Sample> trace;  ///< run_loop(o) only; empty when streamed
  double t_end = 0.0;
  double e2_end = 0.0;
  Sample last{};  ///< the last recorded sample
};

/// Called with every recorded sample (every record_every-th period and the
/// last), in order.
using SampleFn = std::function<void(const Sample&)>;

// The paper's controller settings (Sec. III and IV).
//   model_law: eq. (5) with beta functions (Fig. 2), else -M sat (Fig. 3-5)
//   integrators: conditional integrators k0 = (20, 100), else none
//   ideal: sgn instead of sat (ideal SMC; normally without integrators)
mc_csmc_f32_cfg_t paper_ctrl(bool model_law, bool integrators, bool ideal);
// The paper's HGO: alpha = (17, 80, 100), the given eps.
mc_hgo_f32_cfg_t paper_hgo(double eps_s);
// Servocompensators of Sec. V for w0, K0 placing {-1, -2+-j, -3+-j} (d) and
// {-1, -2+-j} (q). Throws std::runtime_error if the kernels refuse.
void paper_servo(double w0_rad_s, mc_csmc_f32_cfg_t* cfg);

// Runs the loop; throws std::runtime_error if a kernel init fails. The
// first form keeps the recorded samples in trace (tests); the second hands
// each to on_sample and keeps none (the scenarios: constant memory).
LoopResult run_loop(const LoopOptions& o);
LoopResult run_loop(const LoopOptions& o, const SampleFn& on_sample);

// Step-response figures of the trace between t_from and t_to for a step of
// size step_rad whose final value is phi_final_rad:
//   overshoot = max over the window of (phi - phi_final)/step (sign of step),
//   settling  = last time |phi - phi_final| > 2 % step, minus t_from.
struct StepMetrics {
  double overshoot_frac = 0.0;
  double settling_s = 0.0;
};
StepMetrics step_metrics(const std::vector<Sample>& tr, double t_from, double t_to,
                         double phi_final_rad, double step_rad);
/// step_metrics fed one sample at a time (the same figures, in constant memory).
class StepAcc {
 public:
  StepAcc(double t_from, double t_to, double phi_final_rad, double step_rad);
  void add(const Sample& s);
  StepMetrics result() const;

 private:
  double t_from_, t_to_, phi_final_, step_, sgn_, band_, over_ = 0.0, last_out_;
};

// Statistics of a signal over [t_from, t_to].
struct WindowStats {
  double max_abs = 0.0, mean = 0.0, rms = 0.0, peak_to_peak = 0.0;
  double sign_changes_per_s = 0.0;
};
WindowStats window_stats(const std::vector<Sample>& tr, double Sample::*field, double t_from,
                         double t_to);
/// window_stats fed one sample at a time.
class WindowAcc {
 public:
  WindowAcc(double Sample::*field, double t_from, double t_to)
      : field_(field), t_from_(t_from), t_to_(t_to) {}
  void add(const Sample& s);
  WindowStats result() const;

 private:
  double Sample::*field_;
  double t_from_, t_to_;
  WindowStats w_{};
  double sum_ = 0.0, sum2_ = 0.0, lo_ = 0.0, hi_ = 0.0, t0_ = 0.0, t1_ = 0.0, prev_ = 0.0;
  long n_ = 0, changes_ = 0;
};

}  // namespace csmc
}  // namespace mcsim
