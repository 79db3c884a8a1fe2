// Motor and board files for `mcsim run SCENARIO --motor FILE --board FILE`.
//
// TOML (parsed with toml++, Debian's libtomlplusplus-dev), SI units with the
// unit in the key name. A motor file has a [motor] table, a board file a
// [board] table; one file may hold both. The library is in sim/motors/.
//
// [motor]  required: name, r_ohm, ld_h, lq_h, flux_wb (PM flux linkage, peak
//          phase value, amplitude-invariant dq: back-EMF constant p flux
//          V s/rad mech., torque 3/2 p flux iq), pole_pairs, j_kgm2 (rotor
//          plus what is coupled to it), b_nm_s_rad, i_max_a (peak phase
//          current limit), speed_max_rad_s (mechanical).
//          optional: i_rated_a (continuous peak phase current; default
//          i_max_a / 2), speed_rated_rad_s (default 0.8 speed_max_rad_s),
//          source (text: where the numbers come from).
//          Cogging (optional, mcsim::CoggingParams; default none): slots
//          (stator slots), cogging_nm (peak of the fundamental, order
//          lcm(slots, 2 pole_pairs) per turn), cogging_phase_rad, and the
//          harmonics of orders 2, 3, 4 times it: cogging_h2_nm,
//          cogging_h2_phase_rad, ... cogging_h4_phase_rad. A cogging
//          torque needs slots.
//          Ld may be below Lq (interior magnets, salient): the field-weakening
//          scenario uses MTPA for it; the sensorless and PI^2D laws refuse a
//          motor whose Ld and Lq differ by more than 5 % (they assume Ld = Lq).
// [board]  required: name, vbus_v, pwm_hz (one current-loop step per PWM
//          period), dead_time_s, current_sensors (2 or 3), i_sense_max_a
//          (current ADC full scale, +-A), adc_bits, encoder_cpr (counts per
//          mechanical revolution; 0 = no encoder).
//          optional: encoder (the position sensor: "abi", an A/B
//          incremental encoder without index, the default; "abi_index", one
//          with an index mark at encoder_index_rad, the mechanical angle of
//          the mark, default 0; "as5047p" (ams, 14 bits) or "ma732" (MPS,
//          16 bits), absolute on SPI: the image's driver (hal/spienc) reads
//          the plant's chip model, encoder_cpr is the chip's (a --set of
//          it refused), encoder_err_rate the line's MISO bit errors per
//          frame in [0, 1] (default 0), encoder_mount_rad the mechanical
//          angle the chip reads at the rotor's 0 (default 0); "hall" is
//          refused: not available in the simulator yet, issue 32 item 6;
//          --set board.encoder=abi_index takes the bare word),
//          delay_periods (computation delay, default 1),
//          source (text), i_adc_full_scale_a (the current converter's range,
//          +-A: the model's step is 2 i_adc_full_scale_a / 2^adc_bits;
//          default i_sense_max_a), vbus_sense_max_v (the bus sensor's range,
//          step vbus_sense_max_v / 2^adc_bits; default 2 vbus_v),
//          vbus_board_max_v (the board's highest bus, its rating: the
//          drive's parameter of that name, which bounds its over-voltage
//          trip; above vbus_v, at most vbus_sense_max_v; default the bus
//          sensor's range).
//          Or the board's description instead of values: a [board] table
//          with the one key description = "odrive36" (a board name, or a
//          path relative to the file) reads it as --board odrive36 does
//          (board_desc.hpp).
//          DC link (optional; without dc_link_c_f the bus is stiff at vbus_v):
//          dc_link_c_f (bus capacitance, F), source_r_ohm (supply internal
//          resistance, default 0.05), source_sink (bool: the supply can
//          sink current; default false, a bench supply behind its output
//          diode), brake_r_ohm (brake resistor on a chopper; 0 = none,
//          the default). See mcsim::DcLink.
//
// [stepper] a two-phase hybrid stepper (csmc-drive only; a file holds [motor]
//          or [stepper], never both). required: name, r_ohm (phase), l_h
//          (phase), i_rated_a (rated phase current, the datasheet's),
//          rotor_teeth (an integer: 50 for 1.8 deg per full step),
//          j_kgm2 (rotor), detent_nm (peak of the unpowered detent torque,
//          4 rotor_teeth periods per turn; 0 allowed), and the torque
//          constant: either km_nm_a (the model's Km: torque
//          Km (-i_a sin N phi + i_b cos N phi), sim/include/mcsim/
//          stepper_2ph.hpp) or holding_torque_nm with holding_excitation:
//          "two_phase_on" (both windings at i_rated_a, the usual datasheet
//          test: T_hold = sqrt(2) Km i_rated_a, the two windings' torques
//          summed at 45 deg) or "one_phase_on" (T_hold = Km i_rated_a).
//          optional: b_nm_s_rad (viscous, default 0), step_angle_deg
//          (checked against 90 / rotor_teeth), source (text).
//          --set motor.KEY=VALUE edits this table too.
//
// Any problem (unreadable or malformed file, a missing, unknown, mistyped
// or out-of-range key, a missing table) is a UsageError whose text is
// "<file>:<line>: <reason>" (line of the offending key, or of the table /
// line 1 when the key is missing).
//
// The keys the firmware's parameter table also holds (tools/config/
// params.toml: r_ohm ... speed_rated_rad_s, vbus_v ... encoder_cpr) are held
// to its ranges too, so a file mcsim runs is one the drive accepts (an
// encoder_cpr of 0, no encoder, is mcsim's own). When --board FILE is given,
// a [board] table in the motor file is refused, and so is a [motor] table in
// the board file (one of the two would be ignored), unless both name the
// same file.
#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace mcsim {

/// Where each key's value came from: "FILE:LINE" or the "--set KEY=VALUE"
/// that replaced it (refusals after the files are read name it).
using KeySources = std::map<std::string, std::string>;

struct MotorSpec {
  std::string name, source, file;
  KeySources at;
  double r_ohm = 0, ld_h = 0, lq_h = 0, flux_wb = 0;
  int pole_pairs = 0;
  double j_kgm2 = 0, b_nm_s_rad = 0, i_max_a = 0, speed_max_rad_s = 0;
  double i_rated_a = 0, speed_rated_rad_s = 0;
  int slots = 0;  // 0: no cogging
  double cogging_nm = 0, cogging_phase_rad = 0;
  double cogging_h_nm[3] = {0, 0, 0}, cogging_h_phase_rad[3] = {0, 0, 0};  // orders 2N..4N
};

struct BoardSpec {
  std::string name, source, file;
  KeySources at;
  double vbus_v = 0, pwm_hz = 0, dead_time_s = 0;
  int current_sensors = 2;
  double i_sense_max_a = 0;
  double i_adc_full_scale_a = 0;  // the converter's range (quantisation); 0: i_sense_max_a
  int adc_bits = 12;
  double vbus_sense_max_v = 0;  // the bus sensor's range; 0: 2 vbus_v
  double vbus_board_max_v = 0;  // the board's bus limit (rating); 0: the bus sensor's range
  long encoder_cpr = 0;
  std::string encoder = "abi";   // kEncoderAbi, kEncoderAbiIndex, kEncoderAs5047p, kEncoderMa732
  double encoder_index_rad = 0;  // abi_index: mechanical angle of the index mark
  double encoder_err_rate = 0;   // as5047p, ma732: MISO bit errors per frame
  double encoder_mount_rad = 0;  // as5047p, ma732: the magnet's angle on the shaft
  // hall (board_hall.hpp): sensor A's electrical angle, the full hysteresis
  // band, the edges' placement error (rising +e, falling -e) [rad el.]
  double hall_offset_e_rad = 0;
  double hall_hysteresis_e_rad = 0;
  double hall_edge_error_e_rad = 0;
  std::string hall_fault = "none";  // none, all_low, all_high
  double hall_fault_at_s = 0;       // from this time of the run on
  int delay_periods = 1;
  double dc_link_c_f = 0;  // 0: stiff bus
  double source_r_ohm = 0.05;
  bool source_sink = false;
  double brake_r_ohm = 0;
  // The sensor models' ranges (a BoardSpec built in code leaves them 0).
  double adc_full_scale_a() const {
    return i_adc_full_scale_a > 0 ? i_adc_full_scale_a : i_sense_max_a;
  }
  double vbus_full_scale_v() const {
    return vbus_sense_max_v > 0 ? vbus_sense_max_v : 2.0 * vbus_v;
  }
  // The drive's vbus_board_max_v parameter: the board's rating, or what its
  // bus sensor reads (the trip and the braking thresholds stay below it).
  double bus_limit_v() const {
    return vbus_board_max_v > 0 ? vbus_board_max_v : vbus_full_scale_v();
  }
};

/// A two-phase hybrid stepper ([stepper] table).
struct StepperSpec {
  std::string name, source, file;
  KeySources at;
  double r_ohm = 0, l_h = 0, km_nm_a = 0, i_rated_a = 0;
  double holding_torque_nm = 0;    // as given (0: km_nm_a was given)
  std::string holding_excitation;  // "two_phase_on", "one_phase_on" or empty
  int rotor_teeth = 0;
  double j_kgm2 = 0, detent_nm = 0, b_nm_s_rad = 0;
  // The torque at the rated current in the model (quadrature currents of
  // amplitude i_rated_a): Km i_rated_a.
  double rated_torque_nm() const { return km_nm_a * i_rated_a; }
};

/// The board's encoder types the simulator runs (BoardSpec::encoder).
inline constexpr const char* kEncoderAbi = "abi";
inline constexpr const char* kEncoderAbiIndex = "abi_index";
inline constexpr const char* kEncoderAs5047p = "as5047p";  // absolute, SPI, 14 bits
inline constexpr const char* kEncoderMa732 = "ma732";      // absolute, SPI, 16 bits
inline constexpr const char* kEncoderHall = "hall";

/// The files given on the command line, parsed and validated.
struct MotorFiles {
  MotorSpec motor;  ///< a [motor] file (is_stepper false)
  BoardSpec board;
  bool is_stepper = false;  ///< a [stepper] file: stepper holds it, motor is empty
  StepperSpec stepper;
};

/// Parse --motor FILE and --board FILE (board_path may be empty when the
/// motor file also holds [board]; a board name or a board.toml path reads
/// the image's board description, board_desc.hpp). Throws UsageError("<file>:<line>: ...").
/// --set motor.KEY=VALUE / board.KEY=VALUE pairs: they replace the files'
/// values before the tables are read (the same checks; a refusal names the
/// --set).
using Overrides = std::vector<std::pair<std::string, std::string>>;
MotorFiles load_motor_files(const std::string& motor_path, const std::string& board_path,
                            const Overrides& overrides = {});

}  // namespace mcsim
