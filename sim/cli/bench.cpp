#include "bench.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include "foc_sil.hpp"
#include "scenario.hpp"

namespace mcsim {

int cmd_bench(const std::vector<std::string>& args) {
  double sim_s = 2.0;
  for (size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--duration" && i + 1 < args.size()) {
      char* end = nullptr;
      sim_s = std::strtod(args[++i].c_str(), &end);
      if (*end != '\0' || !(sim_s > 0.0) || !std::isfinite(sim_s)) {
        throw UsageError("bench: malformed --duration '" + args[i] + "'");
      }
    } else {
      throw UsageError("bench: unknown option '" + args[i] + "'");
    }
  }
  FocSilOptions o;  // 20 kHz PWM, 4 RK4 sub-steps, one-period delay
  FocSil sil(o);
  mc_drive_t& d = sil.drive();
  if (mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT) != 0) throw std::runtime_error("mode refused");
  const long n = std::lround(sim_s * o.pwm_hz);
  // A load that keeps the loop busy: a symmetric square-wave q current
  // (+-2 A, 50 ms half-periods) swings the rotor between about +-66 rad/s,
  // so decoupling and the speed-dependent paths run, inside the drive's
  // over-speed limit.
  const auto t0 = std::chrono::steady_clock::now();
  for (long k = 0; k < n; ++k) {
    const float iq = ((k / 1000) % 2 == 0) ? 2.0f : -2.0f;
    (void)mc_drive_set_current_ref(&d, -0.5f, iq);
    sil.step();
  }
  const auto t1 = std::chrono::steady_clock::now();
  const double wall = std::chrono::duration<double>(t1 - t0).count();
  if (d.faults != 0u) throw std::runtime_error("drive faulted during the benchmark");
  std::printf(
      "{\"benchmark\": \"sil_foc_rtf\", \"pwm_hz\": %.0f, \"substeps\": %d, "
      "\"delay_periods\": %d, \"sim_s\": %.6g, \"wall_s\": %.6g, \"steps\": %ld, "
      "\"ns_per_step\": %.1f, \"rtf\": %.1f}\n",
      o.pwm_hz, o.substeps, o.delay_periods, sim_s, wall, n, 1e9 * wall / static_cast<double>(n),
      sim_s / wall);
  return 0;
}

}  // namespace mcsim
