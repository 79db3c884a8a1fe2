// observer-error-phase: phase portraits of the flux observer's error
// system (17) of paper 002 (Figs. 2-3), integrated here with RK4 in double
// from a grid of initial conditions, for Omega0 = 0, 0.4, 0.5, 0.9 (and
// one more chosen with --set). The kernel itself is checked against (17)
// in tests/unit/observer.
#include <cmath>
#include <vector>

#include "scenario.hpp"
#include "verdict.hpp"

namespace mcsim {
namespace {

struct V2 {
  double a, b;
};

V2 f17(V2 c, double W) {
  const double s = c.a * c.a + c.b * c.b - 2.0 * c.a;
  return {-s * (c.a - 1.0) - W * c.b, -s * c.b + W * c.a};
}

V2 rk4(V2 c, double W, double h) {
  const V2 k1 = f17(c, W);
  const V2 k2 = f17({c.a + h / 2 * k1.a, c.b + h / 2 * k1.b}, W);
  const V2 k3 = f17({c.a + h / 2 * k2.a, c.b + h / 2 * k2.b}, W);
  const V2 k4 = f17({c.a + h * k3.a, c.b + h * k3.b}, W);
  return {c.a + h / 6 * (k1.a + 2 * k2.a + 2 * k3.a + k4.a),
          c.b + h / 6 * (k1.b + 2 * k2.b + 2 * k3.b + k4.b)};
}

void run_phase(RunContext& ctx) {
  const double h = ctx.params.get("h");
  const int n_grid = static_cast<int>(ctx.params.get("grid"));
  const double s_end = ctx.duration_s;  // "duration" is in units of s here
  std::vector<double> omegas = {0.0, 0.4, 0.5, 0.9};
  const double extra = ctx.params.get("extra_omega0");
  if (extra >= 0.0) omegas.push_back(extra);
  ctx.csv.columns({"omega0_1", "traj_1", "t", "chi1_1", "chi2_1", "angle_err_rad"});
  const long steps = step_count(s_end, h);
  const long every = std::max(1L, steps / 300);
  int traj = 0;
  for (double W : omegas) {
    for (int i = 0; i < n_grid; ++i) {
      for (int j = 0; j < n_grid; ++j) {
        // grid over [-1.5, 2.5] x [-2, 2], i.e. the disk |chi| <= 2 and beyond
        V2 c{-1.5 + 4.0 * i / (n_grid - 1), -2.0 + 4.0 * j / (n_grid - 1)};
        for (long k = 0; k <= steps; ++k) {
          if (k % every == 0 || k == steps) {
            ctx.csv.row({W, static_cast<double>(traj), static_cast<double>(k) * h, c.a, c.b,
                         std::atan2(-c.b, 1.0 - c.a)});
          }
          c = rk4(c, W, h);
        }
        ++traj;
      }
    }
    ctx.progress.update(W, 1.0);
  }
  // Prop. 4 equilibria (Omega0 >= 0) in the summary, for the plot.
  for (double W : omegas) {
    const std::string k = "omega0_" + std::to_string(W).substr(0, 4);
    if (W > 0 && W <= 0.5) {
      const double d = 0.5 * std::sqrt(1 - 4 * W * W);
      ctx.summary.set(k + "_focus_chi1", 0.5 + d);
      ctx.summary.set(k + "_saddle_chi1", 0.5 - d);
      ctx.summary.set(k + "_chi2", -W);
    }
  }
  ctx.summary.set("trajectories", traj);
  write_no_claim(ctx.summary,
                 "phase portraits of the observer's error system (paper 002 Figs. 2-3): the "
                 "trajectories are the result; the equilibria of Prop. 4 are in the summary");
}

const Registrar reg_phase({"observer-error-phase",
                           "Paper 002 Figs. 2-3: phase portraits of the flux observer's error "
                           "system (17) for Omega0 = 0, 0.4, 0.5, 0.9 from a grid of initial "
                           "conditions (duration = time s in units of 2/(gamma flux^2))",
                           12.0,
                           {{"h", 0.01, "1", "RK4 step in s", 1e-4, 0.1},
                            {"grid", 9.0, "1", "grid points per axis", 2.0, 40.0},
                            {"extra_omega0", -1.0, "1", "one more Omega0 (>= 0), -1: none", -1.0,
                             10.0}},
                           run_phase});

}  // namespace
}  // namespace mcsim
