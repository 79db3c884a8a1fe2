// mcsim/status.hpp: error codes returned by every configure()/validate() of
// the plant simulator. A failed configure() leaves the object unchanged.
#ifndef MCSIM_STATUS_HPP
#define MCSIM_STATUS_HPP

namespace mcsim {

enum class Status : int {
  kOk = 0,
  kNotFinite,                  // a parameter is NaN or infinite
  kNonPositiveResistance,      // R_ohm <= 0
  kNonPositiveInductance,      // an inductance <= 0
  kNegativeFlux,               // flux_wb < 0
  kBadPolePairs,               // pole_pairs < 1
  kNonPositiveInertia,         // J_kgm2 <= 0
  kNegativeFriction,           // B_nms_rad < 0 or Coulomb friction < 0
  kBadLoad,                    // load model inconsistent (kind, band, missing fn)
  kBadTeeth,                   // rotor_teeth < 1
  kNonPositiveTorqueConstant,  // K_m <= 0
  kBadPwmPeriod,               // t_pwm_s <= 0
  kBadDeadTime,                // t_dead_s < 0 or >= t_pwm_s / 2
  kBadDeadBand,                // dead-time linear band i_dead_band_a <= 0
  kBadBits,                    // ADC resolution outside [1, 30]
  kBadFullScale,               // ADC full scale <= 0
  kBadGain,                    // gain (1 + gain_error) <= 0
  kNegativeNoise,              // noise rms < 0
  kBadCounts,                  // encoder counts per revolution < 1
  kBadStepCount,               // integrator sub-step count < 1
  kBadPeriod,                  // integration period <= 0
  kDelayTooLong,               // delay longer than the ring-buffer capacity
  kNonSalientRequired,         // normalisation needs Ld == Lq and B == 0
  kBadBase,                    // a normalisation base value <= 0
  kBadPhase,                   // phase index outside 0..2
  kBadCogging,                 // cogging: slots < 0 or > 1000, an amplitude < 0
  kBadThermal,                 // thermal network: a resistance or capacity <= 0, ...
  kBadSensor,                  // Hall / SPI encoder parameter out of range
  kBadLoadCount,               // DC link: number of loads outside 1..kMaxLoads
};

// Short stable name of a status code (for test and log messages).
const char* status_name(Status s);

}  // namespace mcsim

#endif  // MCSIM_STATUS_HPP
