#include "mcsim/status.hpp"

namespace mcsim {

const char* status_name(Status s) {
  switch (s) {
    case Status::kOk:
      return "ok";
    case Status::kNotFinite:
      return "not_finite";
    case Status::kNonPositiveResistance:
      return "non_positive_resistance";
    case Status::kNonPositiveInductance:
      return "non_positive_inductance";
    case Status::kNegativeFlux:
      return "negative_flux";
    case Status::kBadPolePairs:
      return "bad_pole_pairs";
    case Status::kNonPositiveInertia:
      return "non_positive_inertia";
    case Status::kNegativeFriction:
      return "negative_friction";
    case Status::kBadLoad:
      return "bad_load";
    case Status::kBadTeeth:
      return "bad_teeth";
    case Status::kNonPositiveTorqueConstant:
      return "non_positive_torque_constant";
    case Status::kBadPwmPeriod:
      return "bad_pwm_period";
    case Status::kBadDeadTime:
      return "bad_dead_time";
    case Status::kBadDeadBand:
      return "bad_dead_band";
    case Status::kBadBits:
      return "bad_bits";
    case Status::kBadFullScale:
      return "bad_full_scale";
    case Status::kBadGain:
      return "bad_gain";
    case Status::kNegativeNoise:
      return "negative_noise";
    case Status::kBadCounts:
      return "bad_counts";
    case Status::kBadStepCount:
      return "bad_step_count";
    case Status::kBadPeriod:
      return "bad_period";
    case Status::kDelayTooLong:
      return "delay_too_long";
    case Status::kNonSalientRequired:
      return "non_salient_required";
    case Status::kBadBase:
      return "bad_base";
    case Status::kBadPhase:
      return "bad_phase";
    case Status::kBadCogging:
      return "bad_cogging";
    case Status::kBadThermal:
      return "bad_thermal";
    case Status::kBadSensor:
      return "bad_sensor";
    case Status::kBadLoadCount:
      return "bad_load_count";
  }
  return "unknown";
}

}  // namespace mcsim
