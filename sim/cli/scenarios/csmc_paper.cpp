// Scenarios of paper 001 (Seshagiri and Khalil, "Position control of a PMSM
// using conditional integrators"): the stepper position loop with
// continuous sliding-mode control and conditional integrators /
// servocompensators, state and output feedback, sampled data, and the ideal
// SMC baseline. The loop itself is in csmc_loop.hpp.
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "csmc_loop.hpp"
#include "q31_loops.hpp"
#include "scenario.hpp"

namespace mcsim {
namespace {

using csmc::Feedback;
using csmc::LoopOptions;
using csmc::LoopResult;
using csmc::RefKind;
using csmc::Sample;

constexpr double kPi = 3.14159265358979323846;

// Standard columns of one loop run (prefix p: "" or e.g. "smc_").
std::vector<std::string> loop_columns(const std::string& p, bool hgo) {
  std::vector<std::string> c = {p + "phi_d_rad", p + "e1_a",     p + "e2_rad",   p + "x1_a",
                                p + "x2_a",      p + "x3_rad_s", p + "x4_rad",   p + "u1_v",
                                p + "u2_v",      p + "s1_a",     p + "s2_rad_s2"};
  if (hgo) {
    c.push_back(p + "z1_rad");
    c.push_back(p + "z2_rad_s");
    c.push_back(p + "z3_rad_s2");
  }
  return c;
}

void append_sample(std::vector<double>* row, const Sample& s, bool hgo) {
  const double v[] = {s.phi_d, s.e1, s.e2, s.x1, s.x2, s.x3, s.x4, s.u1, s.u2, s.s1, s.s2};
  row->insert(row->end(), std::begin(v), std::end(v));
  if (hgo) {
    row->push_back(s.z1);
    row->push_back(s.z2);
    row->push_back(s.z3);
  }
}

// Writes runs side by side (same time grid): t, then each run's columns.
void write_runs(RunContext& ctx, const std::vector<const LoopResult*>& runs,
                const std::vector<std::string>& prefixes, const std::vector<bool>& hgo) {
  std::vector<std::string> cols = {"t"};
  for (size_t i = 0; i < runs.size(); ++i) {
    const auto c = loop_columns(prefixes[i], hgo[i]);
    cols.insert(cols.end(), c.begin(), c.end());
  }
  ctx.csv.columns(cols);
  const size_t n = runs[0]->trace.size();
  for (const auto* r : runs) {
    if (r->trace.size() != n) throw std::logic_error("runs on different time grids");
  }
  std::vector<double> row;
  for (size_t k = 0; k < n; ++k) {
    row.clear();
    row.push_back(runs[0]->trace[k].t);
    for (size_t i = 0; i < runs.size(); ++i) append_sample(&row, runs[i]->trace[k], hgo[i]);
    ctx.csv.row(row);
  }
}

size_t record_every(double duration_s, double dt_s) {
  const double n = duration_s / dt_s;
  return static_cast<size_t>(std::max(1.0, std::floor(n / 5000.0)));
}

// ------------------------------------------------ Fig. 2: state feedback
void run_state_feedback(RunContext& ctx) {
  LoopOptions o;
  o.duration_s = ctx.duration_s;
  o.dt_s = ctx.params.get("dt_s");
  o.plant.R_ohm = ctx.params.get("R_ohm");
  o.plant.L_h = ctx.params.get("L_h");
  o.step2_t_s = 0.5;
  const bool integ = ctx.params.get("integrators") != 0.0;
  const bool ideal = ctx.params.get("ideal") != 0.0;
  o.ctrl = csmc::paper_ctrl(true, integ, ideal);
  o.record_every = record_every(o.duration_s, o.dt_s);
  const bool q31 = ctx.params.get("kernels") != 0.0;
  ctx.summary.set_text("kernels", q31 ? "q31" : "f32");
  const LoopResult r = q31 ? q31loop::run_csmc_q31(o) : csmc::run_loop(o);
  write_runs(ctx, {&r}, {""}, {false});
  const double a = csmc::kPaperStepRad;
  const auto m1 = csmc::step_metrics(r.trace, 0.0, std::min(0.5, o.duration_s), a, a);
  ctx.summary.set("step1_overshoot_pct", 100.0 * m1.overshoot_frac);
  ctx.summary.set("step1_settling_2pct_s", m1.settling_s);
  if (o.duration_s > 0.5) {
    const auto m2 = csmc::step_metrics(r.trace, 0.5, o.duration_s, 2.0 * a, a);
    ctx.summary.set("step2_overshoot_pct", 100.0 * m2.overshoot_frac);
    ctx.summary.set("step2_settling_2pct_s", m2.settling_s);
  }
  ctx.summary.set("e2_final_rad", r.e2_end);
  ctx.summary.set("e1_final_a", r.trace.back().e1);
}

const Registrar reg_sf(
    {"csmc-state-feedback",
     "Paper 001 Fig. 2: stepper position steps phi_d = 0.03142 (u(t) + u(t-0.5)) under "
     "state-feedback CSMC (5) with conditional integrators; R, L mismatched (nominal 20 ohm, "
     "35 mH)",
     1.0,
     {{"dt_s", 1.0e-5, "s", "control period (small: close to the paper's continuous loop)", 1.0e-6,
       1.0e-3},
      {"R_ohm", 19.0, "ohm", "actual winding resistance", 1.0, 100.0},
      {"L_h", 0.040, "H", "actual winding inductance", 1.0e-3, 1.0},
      {"integrators", 1.0, "-", "1: conditional integrators k0 = (20, 100); 0: none", 0.0, 1.0},
      q31loop::kernels_param(),
      {"ideal", 0.0, "-", "1: ideal SMC (sgn instead of sat)", 0.0, 1.0}},
     run_state_feedback});

// ------------------------------------------ Fig. 3(a): output feedback
LoopOptions of_options(RunContext& ctx) {
  LoopOptions o;
  o.duration_s = ctx.duration_s;
  o.dt_s = ctx.params.get("dt_s");
  o.plant.R_ohm = 19.5;
  o.plant.L_h = 0.030;
  o.step2_t_s = -1.0;
  o.ctrl = csmc::paper_ctrl(false, true, false);
  o.record_every = record_every(o.duration_s, o.dt_s);
  return o;
}

void run_output_feedback(RunContext& ctx) {
  LoopOptions o = of_options(ctx);
  o.fb = Feedback::kHgo;
  o.hgo = csmc::paper_hgo(ctx.params.get("eps_s"));
  const LoopResult of = csmc::run_loop(o);
  o.fb = Feedback::kState;
  const LoopResult sf = csmc::run_loop(o);
  write_runs(ctx, {&of, &sf}, {"", "sf_"}, {true, false});
  const double a = csmc::kPaperStepRad;
  const auto mo = csmc::step_metrics(of.trace, 0.0, o.duration_s, a, a);
  const auto ms = csmc::step_metrics(sf.trace, 0.0, o.duration_s, a, a);
  double dmax = 0.0;
  for (size_t k = 0; k < of.trace.size(); ++k) {
    dmax = std::max(dmax, std::abs(of.trace[k].e2 - sf.trace[k].e2));
  }
  ctx.summary.set("of_overshoot_pct", 100.0 * mo.overshoot_frac);
  ctx.summary.set("of_settling_2pct_s", mo.settling_s);
  ctx.summary.set("sf_overshoot_pct", 100.0 * ms.overshoot_frac);
  ctx.summary.set("sf_settling_2pct_s", ms.settling_s);
  ctx.summary.set("max_abs_e2_of_minus_sf_rad", dmax);
  ctx.summary.set("of_e2_final_rad", of.e2_end);
  ctx.summary.set("sf_e2_final_rad", sf.e2_end);
}

const Registrar reg_of(
    {"csmc-output-feedback",
     "Paper 001 Fig. 3(a): phi_d = 0.03142 step, output feedback u = -M sat(s^/mu) with the "
     "high-gain observer (6) (columns z1..z3) against partial state feedback (sf_ columns); "
     "R = 19.5 ohm, L = 30 mH, M = 50 V",
     0.5,
     {{"dt_s", 1.0e-5, "s", "control period", 1.0e-6, 1.0e-3},
      {"eps_s", 1.0e-4, "s", "high-gain observer eps", 1.0e-6, 1.0e-2}},
     run_output_feedback});

// ----------------------------------------- Fig. 3(b): the eps sweep
const double kEpsSweep[] = {4.0e-4, 2.0e-4, 1.0e-4, 5.0e-5, 2.5e-5};

void run_eps_sweep(RunContext& ctx) {
  LoopOptions o = of_options(ctx);
  o.fb = Feedback::kState;
  const LoopResult sf = csmc::run_loop(o);
  std::vector<LoopResult> runs;
  for (double eps : kEpsSweep) {
    o.fb = Feedback::kHgo;
    o.hgo = csmc::paper_hgo(eps);
    runs.push_back(csmc::run_loop(o));
  }
  std::vector<std::string> cols = {"t", "sf_e2_rad"};
  for (double eps : kEpsSweep) {
    char b[64];
    std::snprintf(b, sizeof b, "e2_eps_%g_rad", eps);
    cols.emplace_back(b);
  }
  ctx.csv.columns(cols);
  std::vector<double> row;
  for (size_t k = 0; k < sf.trace.size(); ++k) {
    row.assign({sf.trace[k].t, sf.trace[k].e2});
    for (const auto& r : runs) row.push_back(r.trace[k].e2);
    ctx.csv.row(row);
  }
  for (size_t i = 0; i < runs.size(); ++i) {
    double dmax = 0.0;
    for (size_t k = 0; k < sf.trace.size(); ++k) {
      dmax = std::max(dmax, std::abs(runs[i].trace[k].e2 - sf.trace[k].e2));
    }
    char b[80];
    std::snprintf(b, sizeof b, "max_abs_e2_of_minus_sf_rad.eps_%g", kEpsSweep[i]);
    ctx.summary.set(b, dmax);
  }
}

const Registrar reg_eps(
    {"csmc-output-feedback-eps",
     "Paper 001 Fig. 3(b): e2 under output feedback for eps = 4e-4 .. 2.5e-5 against partial "
     "state feedback (sf_e2_rad); the difference shrinks as eps -> 0",
     0.5,
     {{"dt_s", 1.0e-5, "s", "control period", 1.0e-6, 1.0e-3}},
     run_eps_sweep});

// ---------------------------------------- Fig. 4: sampled data, CSMC vs SMC
void run_sampled(RunContext& ctx) {
  LoopOptions o;
  o.duration_s = ctx.duration_s;
  o.dt_s = ctx.params.get("T_s");
  o.substeps = static_cast<int>(ctx.params.get("substeps"));
  o.plant.R_ohm = 19.5;
  o.plant.L_h = 0.030;
  o.step2_t_s = -1.0;
  o.record_every = 1;
  const bool model = ctx.params.get("model_law") != 0.0;
  o.ctrl = csmc::paper_ctrl(model, true, false);
  const LoopResult cs = csmc::run_loop(o);
  o.ctrl = csmc::paper_ctrl(model, false, true);
  const LoopResult sm = csmc::run_loop(o);
  write_runs(ctx, {&cs, &sm}, {"", "smc_"}, {false, false});
  const double t1 = o.duration_s, t0 = t1 - ctx.params.get("window_s");
  const auto e_cs = csmc::window_stats(cs.trace, &Sample::e2, t0, t1);
  const auto e_sm = csmc::window_stats(sm.trace, &Sample::e2, t0, t1);
  const auto v_cs = csmc::window_stats(cs.trace, &Sample::u2, t0, t1);
  const auto v_sm = csmc::window_stats(sm.trace, &Sample::u2, t0, t1);
  ctx.summary.set("csmc_e2_ss_max_abs_rad", e_cs.max_abs);
  ctx.summary.set("csmc_e2_ss_mean_rad", e_cs.mean);
  ctx.summary.set("csmc_vq_sign_changes_per_s", v_cs.sign_changes_per_s);
  ctx.summary.set("csmc_vq_peak_to_peak_v", v_cs.peak_to_peak);
  ctx.summary.set("smc_e2_ss_max_abs_rad", e_sm.max_abs);
  ctx.summary.set("smc_e2_ss_mean_rad", e_sm.mean);
  ctx.summary.set("smc_vq_sign_changes_per_s", v_sm.sign_changes_per_s);
  ctx.summary.set("smc_vq_peak_to_peak_v", v_sm.peak_to_peak);
}

const Registrar reg_sampled(
    {"csmc-sampled",
     "Paper 001 Fig. 4: sampled-data loop (ZOH, T = 0.1 ms), CSMC with conditional "
     "integrators (columns without prefix) vs ideal SMC u = -M sgn(s) (smc_ columns); "
     "steady-state error and v_q chattering in the summary",
     0.5,
     {{"T_s", 1.0e-4, "s", "sampling period", 1.0e-6, 1.0e-3},
      {"substeps", 4.0, "-", "RK4 sub-steps per period", 1.0, 100.0},
      {"model_law", 0.0, "-", "1: law (5) with beta functions instead of -M sat/sgn", 0.0, 1.0},
      {"window_s", 0.1, "s", "steady-state window at the end of the run", 1.0e-3, 10.0}},
     run_sampled});

// -------------------------------------- Fig. 5: sinusoidal references
void run_sinusoid(RunContext& ctx) {
  LoopOptions o;
  o.duration_s = ctx.duration_s;
  o.dt_s = ctx.params.get("dt_s");
  o.plant.R_ohm = 19.5;
  o.plant.L_h = 0.030;
  o.ref = RefKind::kCos;
  o.r0_rad = ctx.params.get("r0_rad");
  o.w0_rad_s = ctx.params.get("w0_rad_s");
  o.fb = ctx.params.get("state_feedback") != 0.0 ? Feedback::kState : Feedback::kHgo;
  o.hgo = csmc::paper_hgo(ctx.params.get("eps_s"));
  o.record_every = record_every(o.duration_s, o.dt_s);
  o.ctrl = csmc::paper_ctrl(false, false, false);
  csmc::paper_servo(o.w0_rad_s, &o.ctrl);
  const LoopResult sv = csmc::run_loop(o);
  o.ctrl = csmc::paper_ctrl(false, false, false);  // no servocompensator
  const LoopResult ns = csmc::run_loop(o);
  const bool hgo = o.fb == Feedback::kHgo;
  write_runs(ctx, {&sv, &ns}, {"", "nosvc_"}, {hgo, hgo});
  // steady state: the last reference period
  const double per = 2.0 * kPi / o.w0_rad_s;
  const double t1 = o.duration_s, t0 = std::max(0.0, t1 - per);
  const auto a = csmc::window_stats(sv.trace, &Sample::e2, t0, t1);
  const auto b = csmc::window_stats(ns.trace, &Sample::e2, t0, t1);
  ctx.summary.set("svc_e2_ss_max_abs_rad", a.max_abs);
  ctx.summary.set("nosvc_e2_ss_max_abs_rad", b.max_abs);
  ctx.summary.set("ratio_nosvc_over_svc", b.max_abs / a.max_abs);
}

const Registrar reg_sin(
    {"csmc-sinusoid",
     "Paper 001 Fig. 5: phi_d = r0 cos(w0 t), output feedback with conditional "
     "servocompensators (K0 placing {-1,-2+-j,-3+-j} and {-1,-2+-j}) against the same CSMC "
     "without them (nosvc_ columns)",
     10.0,
     {{"dt_s", 1.0e-5, "s", "control period", 1.0e-6, 1.0e-3},
      {"r0_rad", kPi / 2.0, "rad", "reference amplitude (paper: pi/2 or pi/10)", 0.0, 10.0},
      {"w0_rad_s", 2.0, "rad/s", "reference frequency (paper: 2 or 5)", 0.1, 50.0},
      {"eps_s", 1.0e-4, "s", "high-gain observer eps", 1.0e-6, 1.0e-2},
      {"state_feedback", 0.0, "-", "1: e2', e2'' from the states instead of the HGO", 0.0, 1.0}},
     run_sinusoid});

}  // namespace
}  // namespace mcsim
