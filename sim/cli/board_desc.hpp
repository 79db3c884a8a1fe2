// The simulator's board from the image's board description:
// `mcsim run SCENARIO --motor M --board NAME` (a folder of
// firmware/targets/stm32f405/boards/) or `--board PATH/board.toml`.
//
// The description (board.toml, a variant over its base with
// `base = "<folder>"`, and the pins.csv that applies) is the one source of
// the board's values; tools/boards/mc_boards.py generates the image's
// mc_board_<name>_desc from the same files. What the simulator takes from it:
//   vbus_v          = [supply] nominal_v
//   pwm_hz          = [pwm] frequency_hz
//   dead_time_s     = [pwm] deadtime_ns * 1e-9
//   current_sensors = the adc_ia/adc_ib/adc_ic rows of pins.csv
//   i_sense_max_a   = (min(offset, vref - offset) - margin * vref / 4096) / (|gain| shunt)
//                     (the linear range inside the rail margin: the image's
//                     i_sense_max_a)
//   i_adc_full_scale_a = vref / (2 |gain| shunt): the converter's range, so
//                     the model's step 2 full_scale / 4096 is the board's
//                     vref / 4096 / (|gain| shunt)
//   adc_bits        = 12 (the STM32F405's ADC)
//   vbus_sense_max_v = vref * divider (step vref * divider / 4096)
//   encoder_cpr     = [encoder] counts_per_rev
//   encoder         = [encoder] type ("abi"; motor_file.cpp refuses the SPI
//                     and Hall sensors by name until the simulator runs them)
//   brake_r_ohm     = [brake] r_ohm when present, else 0 (no chopper)
// These formulas are mc_boards.py's (load_board); tests/sil/boards checks the
// two agree on every board. The rest of the description (pins, thermistors,
// gate driver) is the image's alone; mc_boards.py validates all of it.
//
// Errors: UsageError "<file>:<line>: [table] key: reason" (the line of the
// key, or of its table when missing); an unknown name lists the boards.
#pragma once

#include <string>
#include <vector>
#include <toml++/toml.h>

#include "motor_file.hpp"

namespace mcsim {

/// A TOML file parsed with toml++ (motor_file.cpp); an unreadable or
/// malformed file is a UsageError "<file>:<line>: ...".
toml::table parse_toml_file(const std::string& path);

/// The folder holding the boards (firmware/targets/stm32f405/boards of the
/// source tree mcsim was built from).
std::string boards_dir();

/// The board names (folders with a board.toml), sorted.
std::vector<std::string> board_names();

/// True when arg names a board description: a board name (no '/', no
/// ".toml") or a path whose file name is board.toml.
bool is_board_description(const std::string& arg);

/// The path of the board.toml that arg names; unknown names are refused.
std::string board_desc_path(const std::string& arg);

/// A description as the simulator's [board] table (the keys of
/// motor_file.hpp) and, per key, the "FILE:LINE" of the description's
/// value it comes from.
struct BoardDescTable {
  std::string path;  // the board.toml
  toml::table board;
  KeySources at;
};
BoardDescTable board_desc_table(const std::string& arg);

/// Read a board description into the simulator's board; --set board.KEY
/// overrides apply to the result (checked by the [board] rules of
/// motor_file.cpp, which defines it).
BoardSpec load_board_desc(const std::string& arg, const Overrides& overrides = {});

}  // namespace mcsim
