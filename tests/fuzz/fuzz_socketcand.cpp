// libFuzzer target: the socketcand server's text side (hal/host
// socketcand_proto: the stream splitter and the command parser), which reads
// whatever a TCP client sends. Input: the bytes a client sends, cut into
// reads at the positions its first byte chooses. For any input:
// - the splitter's buffer stays bounded (kMaxCommandBytes plus one read);
// - every command body it returns is printable ASCII without '<' or '>';
// - every command parsed is a valid classic frame (mc_hal_can_frame_check),
//   a bus name of at most kMaxBusName characters, or a mode/echo;
// - a parsed frame written back as a client would (format_send) parses to
//   the same frame, and the server's "< frame ... >" line for it is one
//   command of the protocol's shape;
// - an error reply (format_error) is one command with no '<' or '>' inside.
// Anything else (a crash, a sanitizer report, an abort here) is a bug.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>

#include "hal_host/socketcand_proto.hpp"

namespace sc = hal_host::socketcand;

namespace {

void require(bool ok) {
  if (!ok) std::abort();
}

bool one_command(const std::string& s) {
  return s.size() >= 4 && s.front() == '<' && s.back() == '>' &&
         s.find_first_of("<>", 1) == s.size() - 1;
}

bool same(const mc_hal_can_frame_t& a, const mc_hal_can_frame_t& b) {
  return a.id == b.id && a.flags == b.flags && a.len == b.len &&
         ((a.flags & MC_HAL_CAN_FLAG_RTR) || std::memcmp(a.data, b.data, a.len) == 0);
}

void check_command(const std::string& body) {
  for (char c : body) require(c != '<' && c != '>' && (c == '\t' || (c >= 0x20 && c <= 0x7E)));
  sc::Command cmd;
  std::string why;
  if (!sc::parse_command(body, &cmd, &why)) {
    require(!why.empty());
    require(one_command(sc::format_error(why)));
    return;
  }
  if (cmd.verb == sc::Verb::kOpen) {
    require(!cmd.bus.empty() && cmd.bus.size() <= sc::kMaxBusName);
    return;
  }
  if (cmd.verb != sc::Verb::kSend) return;
  require(mc_hal_can_frame_check(&cmd.frame, false) == 0);
  const std::string back = sc::format_send(cmd.frame);
  require(one_command(back));
  sc::Command again;
  require(sc::parse_command(back.substr(1, back.size() - 2), &again, &why));
  require(again.verb == sc::Verb::kSend && same(cmd.frame, again.frame));
  require(one_command(sc::format_frame(1.5, cmd.frame)));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const size_t cut = 1 + data[0] % 64;  // bytes per read
  const char* p = reinterpret_cast<const char*>(data + 1);
  size_t n = size - 1;
  sc::CommandSplitter split;
  std::string text;
  while (n > 0) {
    const size_t k = n < cut ? n : cut;
    split.feed(p, k);
    p += k;
    n -= k;
    for (;;) {
      const auto ev = split.next(&text);
      if (ev == sc::CommandSplitter::Event::kNone) break;
      if (ev == sc::CommandSplitter::Event::kCommand) {
        check_command(text);
      } else {
        require(one_command(sc::format_error(text)));
      }
    }
    require(split.buffered() <= sc::kMaxCommandBytes + cut);
  }
  return 0;
}
