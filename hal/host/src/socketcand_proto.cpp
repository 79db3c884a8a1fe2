#include "hal_host/socketcand_proto.hpp"

#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <vector>

namespace hal_host {
namespace socketcand {
namespace {

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n';
}

int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// A run of 1..max_digits hex digits.
bool parse_hex(const std::string& s, size_t max_digits, uint32_t* v) {
  if (s.empty() || s.size() > max_digits) return false;
  uint32_t x = 0;
  for (char c : s) {
    const int d = hex_digit(c);
    if (d < 0) return false;
    x = (x << 4) | static_cast<uint32_t>(d);
  }
  *v = x;
  return true;
}

std::vector<std::string> tokens_of(const std::string& body) {
  std::vector<std::string> t;
  size_t i = 0;
  while (i < body.size()) {
    while (i < body.size() && (body[i] == ' ' || body[i] == '\t')) ++i;
    const size_t s = i;
    while (i < body.size() && body[i] != ' ' && body[i] != '\t') ++i;
    if (i > s) t.push_back(body.substr(s, i - s));
  }
  return t;
}

// ID: 1..3 hex digits for an 11-bit identifier, 8 for a 29-bit one (as
// socketcand tells them apart: by the number of digits).
bool parse_id(const std::string& s, mc_hal_can_frame_t* f, std::string* why) {
  uint32_t id = 0;
  if (s.size() == 8 && parse_hex(s, 8, &id) && id <= MC_HAL_CAN_EXT_ID_MAX) {
    f->id = id;
    f->flags |= MC_HAL_CAN_FLAG_EXT;
    return true;
  }
  if (s.size() <= 3 && parse_hex(s, 3, &id) && id <= MC_HAL_CAN_STD_ID_MAX) {
    f->id = id;
    return true;
  }
  *why = "identifier '" + s + "': 1 to 3 hex digits up to 7FF, or 8 up to 1FFFFFFF";
  return false;
}

bool parse_len(const std::string& s, uint8_t* len, std::string* why) {
  uint32_t n = 0;
  if (!parse_hex(s, 1, &n) || n > MC_HAL_CAN_MAX_LEN) {
    *why = "length '" + s + "': 0 to 8";
    return false;
  }
  *len = static_cast<uint8_t>(n);
  return true;
}

bool parse_send(const std::vector<std::string>& t, Command* out, std::string* why) {
  mc_hal_can_frame_t f{};
  if (t.size() < 3) {
    *why = "send: expected send ID LEN DATA...";
    return false;
  }
  if (!parse_id(t[1], &f, why) || !parse_len(t[2], &f.len, why)) return false;
  if (t.size() != 3u + f.len) {
    *why = "send: length " + t[2] + " but " + std::to_string(t.size() - 3) + " data bytes";
    return false;
  }
  for (size_t i = 0; i < f.len; ++i) {
    uint32_t b = 0;
    if (!parse_hex(t[3 + i], 2, &b)) {
      *why = "send: data byte '" + t[3 + i] + "': 1 or 2 hex digits";
      return false;
    }
    f.data[i] = static_cast<uint8_t>(b);
  }
  out->verb = Verb::kSend;
  out->frame = f;
  return true;
}

bool parse_sendrtr(const std::vector<std::string>& t, Command* out, std::string* why) {
  mc_hal_can_frame_t f{};
  if (t.size() != 3) {
    *why = "sendrtr: expected sendrtr ID DLC";
    return false;
  }
  if (!parse_id(t[1], &f, why) || !parse_len(t[2], &f.len, why)) return false;
  f.flags |= MC_HAL_CAN_FLAG_RTR;
  out->verb = Verb::kSend;
  out->frame = f;
  return true;
}

bool is_unsupported(const std::string& verb) {
  static const char* const kKnown[] = {
      "add",    "update",      "delete",     "filter",    "muxfilter", "subscribe", "unsubscribe",
      "fdsend", "controlmode", "statistics", "isotpmode", "isotpconf", "sendpdu"};
  return std::any_of(std::begin(kKnown), std::end(kKnown),
                     [&verb](const char* k) { return verb == k; });
}

std::string hex_id(const mc_hal_can_frame_t& f) {
  char buf[16];
  if (f.flags & MC_HAL_CAN_FLAG_EXT) {
    (void)std::snprintf(buf, sizeof buf, "%08" PRIX32, f.id & MC_HAL_CAN_EXT_ID_MAX);
  } else {
    (void)std::snprintf(buf, sizeof buf, "%03" PRIX32, f.id & MC_HAL_CAN_STD_ID_MAX);
  }
  return buf;
}

}  // namespace

bool parse_command(const std::string& body, Command* out, std::string* why) {
  const std::vector<std::string> t = tokens_of(body);
  if (t.empty()) {
    *why = "empty command";
    return false;
  }
  const std::string& v = t[0];
  if (v == "open") {
    if (t.size() != 2 || t[1].size() > kMaxBusName) {
      *why = "open: expected open BUS (a name of at most 16 characters)";
      return false;
    }
    out->verb = Verb::kOpen;
    out->bus = t[1];
    return true;
  }
  if (v == "rawmode" || v == "bcmmode" || v == "echo") {
    if (t.size() != 1) {
      *why = v + " takes no arguments";
      return false;
    }
    out->verb = v == "rawmode" ? Verb::kRawMode : v == "bcmmode" ? Verb::kBcmMode : Verb::kEcho;
    return true;
  }
  if (v == "send") return parse_send(t, out, why);
  if (v == "sendrtr") return parse_sendrtr(t, out, why);
  *why = is_unsupported(v) ? "command not supported by this server: " + v : "unknown command";
  return false;
}

CommandSplitter::Event CommandSplitter::next(std::string* text) {
  for (;;) {
    if (skipping_) {
      const size_t k = buf_.find_first_of("<>");
      if (k == std::string::npos) {
        buf_.clear();
        return Event::kNone;
      }
      buf_.erase(0, buf_[k] == '>' ? k + 1 : k);
      skipping_ = false;
      continue;
    }
    size_t i = 0;
    while (i < buf_.size() && is_space(buf_[i])) ++i;
    buf_.erase(0, i);
    if (buf_.empty()) return Event::kNone;
    if (buf_[0] != '<') {
      const size_t k = buf_.find('<');
      buf_.erase(0, k == std::string::npos ? buf_.size() : k);
      *text = "bytes outside a command";
      return Event::kError;
    }
    const size_t k = buf_.find_first_of("<>", 1);
    if (k == std::string::npos && buf_.size() < kMaxCommandBytes) return Event::kNone;
    if (k >= kMaxCommandBytes) {     // npos too: no end within the limit
      if (k == std::string::npos) {  // drop what came, and the rest up to its end
        buf_.clear();
        skipping_ = true;
      } else {
        buf_.erase(0, buf_[k] == '>' ? k + 1 : k);
      }
      *text = "command longer than " + std::to_string(kMaxCommandBytes) + " bytes";
      return Event::kError;
    }
    if (buf_[k] == '<') {
      buf_.erase(0, k);
      *text = "command not closed before the next one";
      return Event::kError;
    }
    std::string body = buf_.substr(1, k - 1);
    buf_.erase(0, k + 1);
    if (std::any_of(body.begin(), body.end(),
                    [](char c) { return c != '\t' && (c < 0x20 || c > 0x7E); })) {
      *text = "a byte in a command that is not printable ASCII";
      return Event::kError;
    }
    *text = std::move(body);
    return Event::kCommand;
  }
}

std::string format_frame(double t_s, const mc_hal_can_frame_t& f) {
  const long long us = std::llround(t_s * 1e6);
  char ts[48];
  (void)std::snprintf(ts, sizeof ts, "%lld.%06lld", us / 1000000, us % 1000000);
  if (f.flags & MC_HAL_CAN_FLAG_RTR) {
    return "< rtr " + hex_id(f) + " " + ts + " " + std::to_string(f.len) + " >";
  }
  std::string s = "< frame " + hex_id(f) + " " + ts + " ";
  char b[4];
  for (unsigned i = 0; i < f.len && i < MC_HAL_CAN_FD_MAX_LEN; ++i) {
    (void)std::snprintf(b, sizeof b, "%02X", f.data[i]);
    s += b;
  }
  return s + " >";
}

std::string format_send(const mc_hal_can_frame_t& f) {
  const bool rtr = (f.flags & MC_HAL_CAN_FLAG_RTR) != 0;
  std::string s =
      std::string(rtr ? "< sendrtr " : "< send ") + hex_id(f) + " " + std::to_string(f.len);
  char b[4];
  for (unsigned i = 0; !rtr && i < f.len && i < MC_HAL_CAN_MAX_LEN; ++i) {
    (void)std::snprintf(b, sizeof b, " %x", f.data[i]);
    s += b;
  }
  return s + " >";
}

std::string format_error(const std::string& reason) {
  std::string r = reason;
  std::replace_if(
      r.begin(), r.end(), [](char c) { return c == '<' || c == '>' || c < 0x20 || c > 0x7E; }, '?');
  return "< error " + r + " >";
}

}  // namespace socketcand
}  // namespace hal_host
