// The socketcand protocol (Linux-CAN project, doc/protocol.md of
// github.com/linux-can/socketcand): ASCII commands in angle brackets over
// one TCP connection per client. This file is the text side only (no
// sockets), so a fuzzer and the unit tests reach it directly; the server
// is hal_host::SocketcandCan (socketcand.hpp).
//
// What a client sends (the subset a bus client needs, what python-can's
// `socketcand` interface uses):
//   < open can0 >                  choose the bus (NO_BUS mode only)
//   < rawmode >  < bcmmode >       every frame of the bus / none
//   < echo >                       answered with < echo >
//   < send ID LEN B0 B1 ... >      one frame: ID 1..3 hex digits (11-bit,
//                                  <= 7FF) or 8 (29-bit, <= 1FFFFFFF),
//                                  LEN 0..8, LEN bytes of 1..2 hex digits
//   < sendrtr ID DLC >             a remote frame
// What the server sends:
//   < hi >  < ok >  < echo >  < error REASON >
//   < frame ID SECONDS.MICROSECONDS DATA >   DATA: the bytes as one run of
//                                  upper-case hex digits (as socketcand
//                                  writes it; python-can reads it so)
//   < rtr ID SECONDS.MICROSECONDS DLC >
// The broadcast manager's commands (add, update, delete, filter,
// subscribe, ...), CAN FD (fdsend) and the control and ISO-TP modes are
// refused with `< error ... >`.
#ifndef HAL_HOST_SOCKETCAND_PROTO_HPP
#define HAL_HOST_SOCKETCAND_PROTO_HPP

#include <cstddef>
#include <string>

#include "hal/can.h"

namespace hal_host {
namespace socketcand {

// Longest command accepted, '<' to '>' inclusive (the longest valid one,
// `< send 1FFFFFFF 8 ` and eight bytes, is 42).
constexpr size_t kMaxCommandBytes = 256;
// Longest bus name (socketcand's limit).
constexpr size_t kMaxBusName = 16;

enum class Verb { kOpen, kRawMode, kBcmMode, kEcho, kSend };

struct Command {
  Verb verb = Verb::kEcho;
  std::string bus;             // kOpen
  mc_hal_can_frame_t frame{};  // kSend (data or remote frame)
};

// Parse the text between '<' and '>' (a body from CommandSplitter). True
// and *out for a command this server carries out; false and *why for
// anything else: unknown or unsupported commands, malformed identifiers,
// lengths or data (why may quote the client's token: send it through
// format_error).
bool parse_command(const std::string& body, Command* out, std::string* why);

// Splits a client's byte stream into commands. Whitespace between commands
// is skipped; bytes outside a command, a command that is not closed before
// the next '<', one with a byte that is not printable ASCII, or one longer
// than kMaxCommandBytes are errors (the stream resynchronises at the next
// command). The buffer never holds more than kMaxCommandBytes bytes plus
// the bytes of the last feed.
class CommandSplitter {
 public:
  enum class Event { kNone, kCommand, kError };
  void feed(const char* p, size_t n) { buf_.append(p, n); }
  // The next command (*text = its body) or error (*text = the reason), or
  // kNone when the buffer holds no complete command.
  Event next(std::string* text);
  size_t buffered() const { return buf_.size(); }

 private:
  std::string buf_;
  bool skipping_ = false;  // inside an over-long command: drop through '>'
};

// "< frame ID SECONDS.MICROSECONDS DATA >" (t_s rounded to the microsecond,
// as the candump log), or "< rtr ... >" for a remote frame.
std::string format_frame(double t_s, const mc_hal_can_frame_t& f);
// "< send ID LEN B0 ... >" as a client writes it (tests, fuzzer).
std::string format_send(const mc_hal_can_frame_t& f);
// "< error REASON >"; '<' and '>' in the reason are replaced.
std::string format_error(const std::string& reason);

}  // namespace socketcand
}  // namespace hal_host

#endif  // HAL_HOST_SOCKETCAND_PROTO_HPP
