// Closed loops with the q31 kernels (issue 10): the same plants, timing and
// references as the f32 scenarios, with the fixed-point twin of each control
// kernel in the loop (conversions to and from per unit at the kernel
// boundary, as an ADC/PWM driver would do them):
//   pi2d-paper-q31          paper 000 Section V, mc_pi2d_q31      (vs pi2d-paper)
//   pi2d-motor-q31          test motor through the drive, the q31
//                           PI2D plug-in (firmware/app/ctrl/
//                           mc_ctrl_pi2d_q31)                     (vs pi2d-motor)
//   csmc-state-feedback-q31 paper 001 Fig. 2, the q31 CSMC plug-in
//                           (firmware/app/ctrl/mc_ctrl_csmc_q31)  (vs csmc-state-feedback)
// Each scenario runs the f32 and the q31 loop and writes both trajectories
// and their difference; tests/sil/q31 bounds the difference.
#pragma once

#include <functional>

#include "scenarios/csmc_loop.hpp"
#include "scenarios/pi2d_sil.hpp"

extern "C" {
#include "csmc/mc_csmc_q31.h"
#include "pi2d/mc_pi2d_q31.h"
}

#include "scenario.hpp"

namespace mcsim {
namespace q31loop {

// `--set kernels=q31` on pi2d-paper, pi2d-motor and csmc-state-feedback runs
// the control law with its q31 twin (tests/sil/q31 bounds the difference).
inline ParamSpec kernels_param() {
  return {"kernels",
          0.0,
          "-",
          "control kernels: f32 or q31 (per-unit fixed-point twins)",
          0.0,
          1.0,
          {{"f32", 0.0}, {"q31", 1.0}}};
}

// Bases of the paper-000 loop (normalised units; from the f32 run's ranges:
// |x2*| <= 15.2, |u2| <= 922, positions in [0, 2 pi + e4), |nu| <= 0.03).
mc_pi2d_q31_bases_t paper_pi2d_bases();
// pi2d::run_paper with mc_pi2d_q31 in place of mc_pi2d_f32.
long run_paper_q31(const pi2d::PaperOptions& o,
                   const std::function<void(const pi2d::PaperSample&)>& row);

// Bases of the motor loop (SI: 20 A sensor range, 400 V, ...).
mc_pi2d_q31_bases_t motor_pi2d_bases(const pi2d::MotorOptions& o);
// pi2d::run_motor(o, true, ...) with the q31 PI2D plug-in (mc_ctrl_pi2d_q31).
pi2d::MotorMetrics run_motor_q31(const pi2d::MotorOptions& o, double duration_s,
                                 const std::function<void(const pi2d::MotorSample&)>& row);

// Bases of the paper-001 loop.
mc_csmc_q31_bases_t paper_csmc_bases();
// csmc::run_loop with the q31 plug-in mc_ctrl_csmc_q31 (state feedback only):
// the trace kept (tests), or each recorded sample handed on (scenarios).
csmc::LoopResult run_csmc_q31(const csmc::LoopOptions& o);
csmc::LoopResult run_csmc_q31(const csmc::LoopOptions& o, const csmc::SampleFn& on_sample);

}  // namespace q31loop
}  // namespace mcsim
