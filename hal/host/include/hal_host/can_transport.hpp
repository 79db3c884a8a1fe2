// hal_host::CanTransport: where the simulated board's CAN goes, chosen in
// one place for every scenario that runs the drive application:
//
//   interface ""                     a candump log (CandumpLogCan): the
//                                    frames sent, time-stamped with the
//                                    simulated time; no bus
//   interface "vcan0", "can0", ...   a SocketCAN interface (SocketCan)
//   interface "socketcand:HOST:PORT" a socketcand server (SocketcandCan) on
//                                    HOST:PORT, bus `can0`: python-can's
//                                    `socketcand` interface and any other
//                                    socketcand client connect to it
//
// A command script (candump -L lines, simulated time) is replayed into the
// drive's receive path on every transport, ahead of what the bus brings:
// the same commands at the same simulated instants, whatever carries the
// telemetry (the frames then match bit for bit across transports).
#ifndef HAL_HOST_CAN_TRANSPORT_HPP
#define HAL_HOST_CAN_TRANSPORT_HPP

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>

#include "hal/can.h"

namespace hal_host {

class CandumpLogCan;
class CandumpScript;
class SocketCan;
class SocketcandCan;

struct CanTransportConfig {
  std::string interface;  // see above
  std::string log_path;   // candump log (interface ""): the file written
  std::string log_iface = "can0";
  std::string script_path;        // command script ("" = none)
  size_t wait_clients = 0;        // socketcand: serve this many clients in raw mode first
  std::function<double()> now_s;  // the simulated clock [s] stamping the frames sent
  // the clock a script frame's stamp must have reached to be received
  // (default now_s): the SIL stamps a period's frames with the period's end
  // and receives at its start, so a reply to a frame stamped t arrives in
  // the next period
  std::function<double()> rx_now_s;
  std::function<uint32_t()> now_ticks;  // the board's tick counter
};

// "socketcand:HOST:PORT" -> host, port; false (and *why) if interface names
// socketcand but is malformed; false with an empty *why if it is not a
// socketcand interface at all.
bool parse_socketcand_interface(const std::string& interface, std::string* host, uint16_t* port,
                                std::string* why);

class CanTransport {
 public:
  // Opens the transport. Throws std::runtime_error (std::system_error for
  // SocketCAN) with a message for the user.
  explicit CanTransport(const CanTransportConfig& cfg);
  ~CanTransport();
  CanTransport(const CanTransport&) = delete;
  CanTransport& operator=(const CanTransport&) = delete;

  const mc_hal_can_t* hal() const { return &dev_; }
  // One line saying where the frames go (for the user, on stderr).
  std::string describe() const;
  // socketcand with wait_clients > 0: serve until that many clients are in
  // raw mode (so a logger sees the run from its first frame); else nothing.
  void wait_for_clients();
  // End of the run: flush the log, send socketcand clients what is queued
  // for them. False if that failed.
  bool finish();
  // What the run did, as summary entries (numbers and texts).
  void report(std::map<std::string, double>* num, std::map<std::string, std::string>* txt) const;

  SocketcandCan* socketcand() const { return server_.get(); }

  int send(const mc_hal_can_frame_t* f) noexcept;
  int receive(mc_hal_can_frame_t* f) noexcept;
  int get_status(mc_hal_can_status_t* st) noexcept;

 private:
  CanTransportConfig cfg_;
  std::unique_ptr<CandumpLogCan> log_;
  std::unique_ptr<SocketCan> sock_;
  std::unique_ptr<SocketcandCan> server_;
  std::unique_ptr<CandumpScript> script_;  // live transports only (the log has its own)
  const mc_hal_can_t* inner_ = nullptr;
  uint64_t script_frames_ = 0;
  mc_hal_can_t dev_{};
};

}  // namespace hal_host

#endif  // HAL_HOST_CAN_TRANSPORT_HPP
