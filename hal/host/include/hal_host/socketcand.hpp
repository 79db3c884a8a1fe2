// hal_host::SocketcandCan: the HAL's CAN served over TCP with the
// socketcand protocol (socketcand_proto.hpp), so that any socketcand client
// (python-can's `socketcand` interface: mdtool, a logger, cantools scripts)
// reaches the simulated drive on a machine without SocketCAN, root or
// kernel modules.
//
// - One listening socket (IPv4, HOST:PORT; port 0: the kernel picks one,
//   port() tells it); up to kMaxClients clients at once, each greeted with
//   < hi >, opening the one bus `channel` (can0), then in raw mode.
// - The drive's frames (send()) go to every client in raw mode, time-stamped
//   with the caller's clock (the simulated time). Frames a client sends go
//   to the drive (receive(), a queue of kRxQueueFrames: a full queue drops
//   the frame and counts it as an rx overrun, as a controller's FIFO does)
//   and to every other client in raw mode (as on a bus).
// - Nothing blocks: the sockets are served (accept, read, parse, write)
//   whenever receive() finds its queue empty (once per slow-loop step) and
//   written to after every send(). A client that reads slowly has its
//   frames queued (kMaxClientQueueBytes each; beyond it frames are dropped
//   for that client and counted: its sequence counters show the gap; a
//   client whose replies to its own commands would pass that size, as it
//   sends and never reads, is disconnected).
// - A malformed command is answered < error REASON > and changes nothing;
//   < open > of another bus is answered < error could not open bus > and
//   the connection closed (as socketcand does).
// - python-can's client reads the reply to < rawmode > with one recv() and
//   compares it with "< ok >", so frames must not follow that reply before
//   the client has read it: they are held (queued, not lost) until the
//   client's socket has nothing unread (sock_diag on the loopback
//   interface; elsewhere kRawHoldFallbackS), at most kRawHoldMaxS.
#ifndef HAL_HOST_SOCKETCAND_HPP
#define HAL_HOST_SOCKETCAND_HPP

#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "hal/can.h"
#include "hal_host/socketcand_proto.hpp"

namespace hal_host {

struct SocketcandStats {
  uint64_t clients_accepted = 0;
  uint64_t clients_refused = 0;      // beyond kMaxClients
  uint64_t clients_max = 0;          // most connected at once
  uint64_t commands = 0;             // commands carried out
  uint64_t commands_refused = 0;     // answered < error ... >
  uint64_t rx_frames = 0;            // frames from clients queued for the drive
  uint64_t rx_overruns = 0;          // frames from clients dropped: the drive's queue was full
  uint64_t tx_frames = 0;            // frames the drive sent
  uint64_t tx_client_drops = 0;      // frames not queued for a client that read too slowly
  uint64_t unflushed_clients = 0;    // finish(): clients closed with frames still queued
  uint64_t raw_holds_seen_read = 0;  // holds ended because the client was seen to read
  uint64_t raw_holds_timed = 0;      // holds ended by kRawHoldFallbackS / kRawHoldMaxS
};

class SocketcandCan {
 public:
  static constexpr size_t kMaxClients = 16;
  static constexpr size_t kRxQueueFrames = 1024;
  static constexpr size_t kMaxClientQueueBytes = 16u << 20;  // ~400,000 frames
  static constexpr double kRawHoldMaxS = 5.0;
  static constexpr double kRawHoldFallbackS = 0.3;

  // Listens on host (an IPv4 address or "localhost") and port. Throws
  // std::runtime_error naming the address and the failing call. now_s
  // stamps the frames sent to clients; now_ticks the frames received.
  // queue_bytes: the per-client queue (tests make it small).
  SocketcandCan(const std::string& host, uint16_t port, const std::string& channel,
                std::function<double()> now_s, std::function<uint32_t()> now_ticks = nullptr,
                size_t queue_bytes = kMaxClientQueueBytes);
  ~SocketcandCan();
  SocketcandCan(const SocketcandCan&) = delete;
  SocketcandCan& operator=(const SocketcandCan&) = delete;

  const mc_hal_can_t* hal() const { return &dev_; }
  const SocketcandStats& stats() const { return stats_; }
  const std::string& host() const { return host_; }
  uint16_t port() const { return port_; }
  const std::string& channel() const { return channel_; }
  // Clients connected now, and those of them receiving frames (raw mode,
  // past the hold).
  size_t clients() const { return clients_.size(); }
  size_t raw_clients() const;

  // Serve until n clients are in raw mode; false after timeout_s (< 0: no
  // limit).
  bool wait_for_clients(size_t n, double timeout_s);
  // End of the run: stop listening, send every client what is queued for
  // it (at most timeout_s), then close. False if something was left.
  bool finish(double timeout_s);
  // Accept, read, parse, answer and write, without blocking.
  void service() noexcept;

  int send(const mc_hal_can_frame_t* f) noexcept;
  int receive(mc_hal_can_frame_t* f) noexcept;
  int get_status(mc_hal_can_status_t* st) noexcept;

 private:
  enum class Mode { kNoBus, kBcm, kRaw };
  struct Client {
    int fd = -1;
    Mode mode = Mode::kNoBus;
    socketcand::CommandSplitter in;
    std::string out;  // bytes queued; out[off..] not yet written
    size_t off = 0;
    size_t hold_at = 0;    // while holding: write no further than this
    bool holding = false;  // after < ok > to < rawmode >: see the header
    bool closing = false;  // write what is queued, then close
    bool dead = false;     // closed: removed by the next service()
    std::chrono::steady_clock::time_point hold_t0;
    uint32_t peer_ip = 0, own_ip = 0;  // network order (sock_diag lookup)
    uint16_t peer_port = 0, own_port = 0;
  };
  void accept_new() noexcept;
  void read_client(Client& c) noexcept;
  void handle(Client& c, const std::string& body) noexcept;
  void reply(Client& c, const std::string& text) noexcept;
  void write_client(Client& c) noexcept;
  void update_hold(Client& c) noexcept;
  void queue_frame(Client& c, const std::string& line) noexcept;
  void inject(const Client& from, const mc_hal_can_frame_t& f) noexcept;
  void close_client(Client& c) noexcept;
  int peer_unread(const Client& c) noexcept;

  int listen_fd_ = -1;
  int diag_fd_ = -1;  // NETLINK_SOCK_DIAG, opened on first use (-2: unavailable)
  uint32_t diag_seq_ = 0;
  std::string host_, channel_;
  uint16_t port_ = 0;
  size_t queue_bytes_;
  std::function<double()> now_s_;
  std::function<uint32_t()> now_ticks_;
  std::vector<std::unique_ptr<Client>> clients_;
  std::deque<mc_hal_can_frame_t> rx_;
  SocketcandStats stats_;
  mc_hal_can_t dev_{};
};

}  // namespace hal_host

#endif  // HAL_HOST_SOCKETCAND_HPP
