// The drive application's binding to the simulated board as the SIL
// scenario can-telemetry makes it (sim/cli/scenarios/can_telemetry.cpp),
// written to a text file (MCSIM_APP_BINDING_OUT=FILE) so that the
// processor-in-the-loop twin (tests/target/pil/test_pil_can.cpp) builds the
// same plant and boots the image's application from the same defaults and
// gains, with nothing typed twice.
//
// Format: one "key value" per line; doubles and floats in C99 hex-float
// (%a: exact), parameters as "param <id> <raw u32>" (the parameter table's
// raw encoding, mc_param_get_raw). Lines starting with '#' are comments.
#pragma once

#include <string>

#include "foc_sil.hpp"
extern "C" {
#include "mc_app.h"
#include "mc_params.h"
}

namespace mcsim {

struct AppBinding {
  FocSilOptions plant;          // the simulated board and motor options
  mc_params_t defaults{};       // the board's defaults (mc_app_cfg_t.defaults)
  float tm_budget_frac = 0.0f;  // mc_app_cfg_t fields the rig sets
  uint16_t tm_ext_rate_hz[MC_TM_COUNT - MC_TM_OBSERVER] = {};
  uint32_t pwm_hz_fixed = 0;
  uint32_t slow_loop_div_fixed = 0;
  bool serve_params = false;   // the application initialised the drive from defaults
  bool position_law = false;   // a position law was plugged
  bool commissioning = false;  // commissioning over CAN was attached
};

// Throws std::runtime_error naming the file on an I/O error.
void write_app_binding(const std::string& path, const AppBinding& b);
// Throws std::runtime_error naming the file and line on a read or parse
// error, an unknown parameter id, or a missing key.
AppBinding read_app_binding(const std::string& path);

}  // namespace mcsim
