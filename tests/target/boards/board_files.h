// The boards' source files read by the tests themselves, independently of
// tools/boards/mc_boards.py: pins.csv (a small CSV reader) and board.toml
// (toml++), plus the STM32F405 facts the tests compare against, typed here
// from the reference manual RM0090 (§8.4 GPIO register encodings) and the
// datasheet DS8626 (ADC channel of each pin).
#ifndef BOARD_FILES_H
#define BOARD_FILES_H

#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <toml++/toml.h>

namespace boards
{

struct Pin {
    std::string signal;
    std::string name; // "PA8"
    int port = -1;    // 0 = A
    int pin = -1;
    std::string mode, pull, otype, speed;
    int af = 0;
    int init = -1; // outputs: 0 or 1
};

// Hall inputs: alternates of the encoder's pins in pins.csv.
inline bool is_hall(const std::string &signal)
{
    return signal == "hall_a" || signal == "hall_b" || signal == "hall_c";
}

inline std::string dir(const std::string &board)
{
    return std::string(MC_BOARDS_DIR) + "/" + board;
}

// The folder whose pins.csv applies: the board's, or its base's for a
// variant without one (board.toml base = "<folder>", mc_boards.py).
inline std::string pins_dir(const std::string &board)
{
    if (std::ifstream(dir(board) + "/pins.csv")) {
        return dir(board);
    }
    const auto base = toml::parse_file(dir(board) + "/board.toml")["base"].value<std::string>();
    return base ? dir(*base) : dir(board);
}

inline std::vector<Pin> read_pins(const std::string &board)
{
    std::ifstream f(pins_dir(board) + "/pins.csv");
    if (!f) {
        throw std::runtime_error("no pins.csv for " + board);
    }
    std::vector<Pin> out;
    std::string line;
    bool header = true;
    while (std::getline(f, line)) {
        if (line.empty() || line[0] == '#') {
            continue;
        }
        std::vector<std::string> c;
        std::stringstream ss(line);
        std::string field;
        while (std::getline(ss, field, ',')) {
            c.push_back(field);
        }
        if (!line.empty() && line.back() == ',') {
            c.push_back("");
        }
        if (header) {
            header = false;
            continue;
        }
        if (c.size() != 8) {
            throw std::runtime_error(board + ": bad row " + line);
        }
        Pin p;
        p.signal = c[0];
        p.name = c[1];
        p.port = c[1][1] - 'A';
        p.pin = std::stoi(c[1].substr(2));
        p.mode = c[2];
        p.af = c[3].empty() ? 0 : std::stoi(c[3]);
        p.pull = c[4];
        p.otype = c[5].empty() ? "pp" : c[5];
        p.speed = c[6].empty() ? "low" : c[6];
        p.init = c[7].empty() ? -1 : std::stoi(c[7]);
        out.push_back(p);
    }
    return out;
}

inline const Pin *find(const std::vector<Pin> &pins, const std::string &signal)
{
    for (const Pin &p : pins) {
        if (p.signal == signal) {
            return &p;
        }
    }
    return nullptr;
}

// RM0090 §8.4.1 MODER: 00 input, 01 output, 10 alternate function, 11 analog.
inline unsigned moder_code(const std::string &mode)
{
    static const std::map<std::string, unsigned> m = {
        {"input", 0u}, {"output", 1u}, {"af", 2u}, {"analog", 3u}};
    return m.at(mode);
}
// §8.4.4 PUPDR: 00 none, 01 pull-up, 10 pull-down.
inline unsigned pupdr_code(const std::string &pull)
{
    static const std::map<std::string, unsigned> m = {{"none", 0u}, {"up", 1u}, {"down", 2u}};
    return m.at(pull);
}
// §8.4.3 OSPEEDR: 00 low, 01 medium, 10 high, 11 very high.
inline unsigned ospeedr_code(const std::string &speed)
{
    static const std::map<std::string, unsigned> m = {
        {"low", 0u}, {"medium", 1u}, {"high", 2u}, {"veryhigh", 3u}};
    return m.at(speed);
}
// §8.4.2 OTYPER: 0 push-pull, 1 open drain.
inline unsigned otyper_code(const std::string &otype)
{
    return otype == "od" ? 1u : 0u;
}

// DS8626 pinout: ADC123_IN0..7 = PA0..PA7, IN8/IN9 = PB0/PB1, IN10..15 =
// PC0..PC5.
inline std::optional<unsigned> adc_channel(const std::string &name)
{
    static const std::map<std::string, unsigned> m = {
        {"PA0", 0u},  {"PA1", 1u},  {"PA2", 2u},  {"PA3", 3u}, {"PA4", 4u},  {"PA5", 5u},
        {"PA6", 6u},  {"PA7", 7u},  {"PB0", 8u},  {"PB1", 9u}, {"PC0", 10u}, {"PC1", 11u},
        {"PC2", 12u}, {"PC3", 13u}, {"PC4", 14u}, {"PC5", 15u}};
    auto it = m.find(name);
    if (it == m.end()) {
        return std::nullopt;
    }
    return it->second;
}

// board.toml, a variant's merged over its base's table by table, key by
// key (mc_boards.py merge()).
inline void merge_over(toml::table &base, const toml::table &over)
{
    for (const auto &kv : over) {
        toml::table *b = base[kv.first].as_table();
        if (kv.second.is_table() && b != nullptr) {
            merge_over(*b, *kv.second.as_table());
        } else {
            base.insert_or_assign(kv.first, kv.second);
        }
    }
}

inline toml::table read_toml(const std::string &board)
{
    toml::table t = toml::parse_file(dir(board) + "/board.toml");
    const auto base = t["base"].value<std::string>();
    if (!base) {
        return t;
    }
    toml::table merged = toml::parse_file(dir(*base) + "/board.toml");
    t.erase("base");
    merge_over(merged, t);
    return merged;
}

inline double num(const toml::table &t, const std::string &path)
{
    auto v = t.at_path(path).value<double>();
    if (!v) {
        throw std::runtime_error("board.toml: no number at " + path);
    }
    return *v;
}

} // namespace boards

#endif
