#include "hal_host/candump_log.hpp"

#include <cerrno>
#include <cinttypes>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "hal_host/can_ops.hpp"

namespace hal_host {
namespace {

int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

}  // namespace

std::string candump_format(double t_s, const std::string& iface, const mc_hal_can_frame_t& f) {
  char buf[64];
  const long long us = std::llround(t_s * 1e6);
  const long long sec = us / 1000000, frac = us % 1000000;
  std::string s;
  (void)std::snprintf(buf, sizeof buf, "(%010lld.%06lld) ", sec, frac);
  s += buf;
  s += iface;
  if (f.flags & MC_HAL_CAN_FLAG_EXT) {
    (void)std::snprintf(buf, sizeof buf, " %08" PRIX32, f.id & MC_HAL_CAN_EXT_ID_MAX);
  } else {
    (void)std::snprintf(buf, sizeof buf, " %03" PRIX32, f.id & MC_HAL_CAN_STD_ID_MAX);
  }
  s += buf;
  if (f.flags & MC_HAL_CAN_FLAG_RTR) {
    s += "#R";
    if (f.len > 0) s += std::to_string(f.len);
    return s;
  }
  if (f.flags & MC_HAL_CAN_FLAG_FD) {
    (void)std::snprintf(buf, sizeof buf, "##%X", (f.flags & MC_HAL_CAN_FLAG_BRS) ? 1u : 0u);
    s += buf;
  } else {
    s += "#";
  }
  for (unsigned i = 0; i < f.len && i < MC_HAL_CAN_FD_MAX_LEN; ++i) {
    (void)std::snprintf(buf, sizeof buf, "%02X", f.data[i]);
    s += buf;
  }
  return s;
}

bool candump_parse(const std::string& line, double* t_s, mc_hal_can_frame_t* f) {
  // (SECONDS) IFACE ID#DATA | ID#R[len] | ID##F DATA
  size_t p = 0;
  if (line.empty() || line[0] != '(') return false;
  const size_t close = line.find(')');
  if (close == std::string::npos) return false;
  const std::string ts = line.substr(1, close - 1);
  char* end = nullptr;
  const double t = std::strtod(ts.c_str(), &end);
  if (ts.empty() || *end != '\0' || !std::isfinite(t)) return false;
  p = close + 1;
  while (p < line.size() && line[p] == ' ') ++p;
  const size_t sp = line.find(' ', p);
  if (sp == std::string::npos) return false;
  p = sp + 1;
  const size_t hash = line.find('#', p);
  if (hash == std::string::npos) return false;
  const std::string id_txt = line.substr(p, hash - p);
  if (id_txt.size() != 3 && id_txt.size() != 8) return false;
  uint32_t id = 0;
  for (char c : id_txt) {
    const int d = hex_digit(c);
    if (d < 0) return false;
    id = (id << 4) | static_cast<uint32_t>(d);
  }
  mc_hal_can_frame_t fr{};
  if (id_txt.size() == 8) {
    if (id & 0x20000000u) return false;  // error frame
    fr.flags |= MC_HAL_CAN_FLAG_EXT;
    id &= MC_HAL_CAN_EXT_ID_MAX;
  }
  fr.id = id;
  size_t q = hash + 1;
  if (q < line.size() && (line[q] == 'R' || line[q] == 'r')) {
    fr.flags |= MC_HAL_CAN_FLAG_RTR;
    if (q + 1 < line.size()) {
      const int d = hex_digit(line[q + 1]);
      if (d < 0 || d > 8 || q + 2 != line.size()) return false;
      fr.len = static_cast<uint8_t>(d);
    }
    *t_s = t;
    *f = fr;
    return true;
  }
  if (q < line.size() && line[q] == '#') {
    if (q + 1 >= line.size()) return false;
    const int fl = hex_digit(line[q + 1]);
    if (fl < 0) return false;
    fr.flags |= MC_HAL_CAN_FLAG_FD;
    if (fl & 1) fr.flags |= MC_HAL_CAN_FLAG_BRS;
    q += 2;
  }
  unsigned n = 0;
  while (q < line.size()) {
    if (line[q] == '.') {
      ++q;
      continue;
    }
    if (q + 1 >= line.size()) return false;
    const int hi = hex_digit(line[q]), lo = hex_digit(line[q + 1]);
    if (hi < 0 || lo < 0 || n >= MC_HAL_CAN_FD_MAX_LEN) return false;
    fr.data[n++] = static_cast<uint8_t>((hi << 4) | lo);
    q += 2;
  }
  fr.len = static_cast<uint8_t>(n);
  *t_s = t;
  *f = fr;
  return true;
}

CandumpScript::CandumpScript(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read CAN command script '" + path + "'");
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos || line[0] == '#') continue;
    Timed tf{};
    if (!candump_parse(line, &tf.t_s, &tf.f)) {
      throw std::runtime_error(path + ":" + std::to_string(n) + ": not a candump -L line");
    }
    if (!frames_.empty() && tf.t_s < frames_.back().t_s) {
      throw std::runtime_error(path + ":" + std::to_string(n) + ": time goes backwards");
    }
    frames_.push_back(tf);
  }
}

bool CandumpScript::next_due(double now_s, mc_hal_can_frame_t* f) {
  if (next_ >= frames_.size() || frames_[next_].t_s > now_s) return false;
  *f = frames_[next_++].f;
  return true;
}

CandumpLogCan::CandumpLogCan(const std::string& out_path, const std::string& iface,
                             std::function<double()> now_s, const std::string& rx_path,
                             std::function<uint32_t()> now_ticks, std::function<double()> rx_now_s)
    : iface_(iface),
      now_s_(std::move(now_s)),
      rx_now_s_(std::move(rx_now_s)),
      now_ticks_(std::move(now_ticks)) {
  if (!now_s_) throw std::invalid_argument("CandumpLogCan: a clock is required");
  if (!rx_now_s_) rx_now_s_ = now_s_;
  if (!rx_path.empty()) script_ = std::make_unique<CandumpScript>(rx_path);
  if (!out_path.empty()) {
    out_ = std::fopen(out_path.c_str(), "w");
    if (out_ == nullptr) {
      throw std::runtime_error("cannot write CAN log '" + out_path + "': " + std::strerror(errno));
    }
  }
  dev_.ops = can_ops<CandumpLogCan>();
  dev_.ctx = this;
}

CandumpLogCan::~CandumpLogCan() {
  if (out_ != nullptr) (void)std::fclose(out_);
}

bool CandumpLogCan::flush() {
  if (out_ != nullptr && std::fflush(out_) != 0) write_error_ = true;
  return !write_error_;
}

int CandumpLogCan::send(const mc_hal_can_frame_t* f) noexcept {
  const int rc = mc_hal_can_frame_check(f, true);
  if (rc != 0) {
    ++stats_.tx_rejected;
    return rc;
  }
  ++stats_.tx_frames;
  if (out_ != nullptr) {
    try {
      const std::string line = candump_format(now_s_(), iface_, *f) + "\n";
      if (std::fputs(line.c_str(), out_) < 0) write_error_ = true;
    } catch (...) {
      write_error_ = true;
    }
  }
  return write_error_ ? -EIO : 0;
}

int CandumpLogCan::receive(mc_hal_can_frame_t* f) noexcept {
  if (!script_) return -EAGAIN;
  double now = 0.0;
  try {
    now = rx_now_s_();
  } catch (...) {
    return -EIO;
  }
  if (!script_->next_due(now, f)) return -EAGAIN;
  f->timestamp_ticks = now_ticks_ ? now_ticks_() : 0u;
  ++stats_.rx_frames;
  return 0;
}

int CandumpLogCan::get_status(mc_hal_can_status_t* st) noexcept {
  *st = mc_hal_can_status_t{};
  st->state = MC_HAL_CAN_STATE_ERROR_ACTIVE;
  st->fd_capable = true;
  return write_error_ ? -EIO : 0;
}

}  // namespace hal_host
