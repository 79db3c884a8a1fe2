// See app_binding.hpp.
#include "app_binding.hpp"

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace mcsim {

namespace {

std::string hexf(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%a", v);
  return buf;
}

}  // namespace

void write_app_binding(const std::string& path, const AppBinding& b) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write the application binding '" + path + "'");
  const FocSilOptions& o = b.plant;
  f << "# the drive application's binding of mcsim can-telemetry (sim/cli/app_binding.hpp)\n";
  f << "plant.pwm_hz " << hexf(o.pwm_hz) << "\n";
  f << "plant.substeps " << o.substeps << "\n";
  f << "plant.delay_periods " << o.delay_periods << "\n";
  f << "plant.bw_rad_s " << hexf(o.bw_rad_s) << "\n";
  f << "plant.vbus_v " << hexf(o.vbus_v) << "\n";
  f << "plant.J_kgm2 " << hexf(o.J_kgm2) << "\n";
  f << "plant.load_nm " << hexf(o.load_nm) << "\n";
  f << "plant.noise_rms_a " << hexf(o.noise_rms_a) << "\n";
  f << "plant.speed_pll_bw_rad_s " << hexf(o.speed_pll_bw_rad_s) << "\n";
  f << "plant.slow_loop_div " << o.slow_loop_div << "\n";
  f << "plant.three_shunts " << (o.three_shunts ? 1 : 0) << "\n";
  f << "plant.omega_m0_rad_s " << hexf(o.omega_m0_rad_s) << "\n";
  f << "plant.theta_m0_rad " << hexf(o.theta_m0_rad) << "\n";
  f << "app.tm_budget_frac " << hexf(b.tm_budget_frac) << "\n";
  for (int i = 0; i < MC_TM_COUNT - MC_TM_OBSERVER; ++i) {
    f << "app.tm_ext_rate_hz." << i << " " << b.tm_ext_rate_hz[i] << "\n";
  }
  f << "app.pwm_hz_fixed " << b.pwm_hz_fixed << "\n";
  f << "app.slow_loop_div_fixed " << b.slow_loop_div_fixed << "\n";
  f << "app.serve_params " << (b.serve_params ? 1 : 0) << "\n";
  f << "app.position_law " << (b.position_law ? 1 : 0) << "\n";
  f << "app.commissioning " << (b.commissioning ? 1 : 0) << "\n";
  for (const mc_param_info_t& info : mc_param_table) {
    if (info.offset == MC_PARAM_NO_FIELD) continue;
    f << "param " << info.id << " " << mc_param_get_raw(&b.defaults, &info) << "\n";
  }
  f.flush();
  if (!f) throw std::runtime_error("write error on the application binding '" + path + "'");
}

AppBinding read_app_binding(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw std::runtime_error("cannot read the application binding '" + path + "'");
  std::map<std::string, std::string> kv;
  AppBinding b;
  b.defaults = mc_params_default;
  std::string line;
  int n = 0;
  auto fail = [&](const std::string& why) {
    return std::runtime_error(path + ":" + std::to_string(n) + ": " + why);
  };
  while (std::getline(f, line)) {
    ++n;
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    std::string key, value;
    if (!(ls >> key >> value)) throw fail("expected 'key value'");
    if (key == "param") {
      std::string raw;
      if (!(ls >> raw)) throw fail("expected 'param id raw'");
      const mc_param_info_t* info =
          mc_param_find(static_cast<uint32_t>(std::stoul(value)), nullptr);
      if (info == nullptr) throw fail("unknown parameter id " + value);
      mc_param_set_raw(&b.defaults, info, static_cast<uint32_t>(std::stoul(raw)));
      continue;
    }
    kv[key] = value;
  }
  auto get = [&](const std::string& k) {
    const auto it = kv.find(k);
    if (it == kv.end()) throw std::runtime_error(path + ": no '" + k + "'");
    return it->second;
  };
  auto d = [&](const std::string& k) { return std::strtod(get(k).c_str(), nullptr); };
  auto u = [&](const std::string& k) {
    return static_cast<uint32_t>(std::strtoul(get(k).c_str(), nullptr, 10));
  };
  FocSilOptions& o = b.plant;
  o.pwm_hz = d("plant.pwm_hz");
  o.substeps = static_cast<int>(u("plant.substeps"));
  o.delay_periods = static_cast<int>(u("plant.delay_periods"));
  o.bw_rad_s = d("plant.bw_rad_s");
  o.vbus_v = d("plant.vbus_v");
  o.J_kgm2 = d("plant.J_kgm2");
  o.load_nm = d("plant.load_nm");
  o.noise_rms_a = d("plant.noise_rms_a");
  o.speed_pll_bw_rad_s = d("plant.speed_pll_bw_rad_s");
  o.slow_loop_div = u("plant.slow_loop_div");
  o.three_shunts = u("plant.three_shunts") != 0;
  o.omega_m0_rad_s = d("plant.omega_m0_rad_s");
  o.theta_m0_rad = d("plant.theta_m0_rad");
  b.tm_budget_frac = static_cast<float>(d("app.tm_budget_frac"));
  for (int i = 0; i < MC_TM_COUNT - MC_TM_OBSERVER; ++i) {
    b.tm_ext_rate_hz[i] = static_cast<uint16_t>(u("app.tm_ext_rate_hz." + std::to_string(i)));
  }
  b.pwm_hz_fixed = u("app.pwm_hz_fixed");
  b.slow_loop_div_fixed = u("app.slow_loop_div_fixed");
  b.serve_params = u("app.serve_params") != 0;
  b.position_law = u("app.position_law") != 0;
  b.commissioning = u("app.commissioning") != 0;
  return b;
}

}  // namespace mcsim
