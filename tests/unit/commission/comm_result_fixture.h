// A complete, plausible commissioning result (no mechanics) for the tests
// of mc_comm_apply and of the CAN front end (mc_comm_can).
#ifndef COMM_RESULT_FIXTURE_H
#define COMM_RESULT_FIXTURE_H

extern "C" {
#include "commission/mc_commission.h"
}

namespace apptest {

inline mc_comm_result_t FullResult() {
  mc_comm_result_t r{};
  r.adc_offset_a[0] = 0.1f;
  r.adc_offset_a[1] = -0.05f;
  r.adc_offset_a[2] = 0.0f;
  r.r_ohm = 0.2f;
  r.ld_h = 1e-4f;
  r.lq_h = 1.5e-4f;
  r.flux_wb = 0.02f;
  r.pole_pairs = 7u;
  r.encoder_offset_rad = 1.25f;
  r.encoder_direction = -1;
  r.valid = MC_COMM_HAVE_OFFSETS | MC_COMM_HAVE_R | MC_COMM_HAVE_L | MC_COMM_HAVE_ENCODER |
            MC_COMM_HAVE_FLUX;
  return r;
}

}  // namespace apptest

#endif  // COMM_RESULT_FIXTURE_H
