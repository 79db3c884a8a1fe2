// hal_host::CandumpLogCan: the HAL's CAN without a bus. Every frame sent is
// written as one line of a candump log (the `candump -L` text format, which
// can-utils' canplayer, python-can and tools/can/mc_can.py read):
//
//   (0000000001.250000) can0 121#0A000000000000FF
//
// with the time stamp taken from the caller's clock (the simulated time in
// the SIL). Optionally, frames to receive come from a second candump log
// (a command script): each is handed to receive() once the clock has
// reached its time stamp. This is what the SIL uses when no SocketCAN
// interface is given, and what lets the command path run without a kernel
// CAN stack.
//
// Also here: the candump line format and parser shared by the host tools.
#ifndef HAL_HOST_CANDUMP_LOG_HPP
#define HAL_HOST_CANDUMP_LOG_HPP

#include <cstdint>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "hal/can.h"

namespace hal_host {

// One candump -L line (without the newline) for a frame at t_s seconds.
std::string candump_format(double t_s, const std::string& iface, const mc_hal_can_frame_t& f);

// Parse one line; false if it is not a candump -L line (error frames, with
// the CAN_ERR_FLAG bit in an 8-digit id, are not data frames: false too).
bool candump_parse(const std::string& line, double* t_s, mc_hal_can_frame_t* f);

// A command script: candump -L lines (blank lines and lines starting with
// '#' skipped), time stamps non-decreasing. Each frame is handed out once
// the caller's clock has reached its time stamp.
class CandumpScript {
 public:
  // Throws std::runtime_error naming the file that cannot be read or the
  // line that cannot be used.
  explicit CandumpScript(const std::string& path);
  // The next frame whose time has come (timestamp_ticks as in the file: 0).
  bool next_due(double now_s, mc_hal_can_frame_t* f);
  size_t size() const { return frames_.size(); }
  size_t taken() const { return next_; }

 private:
  struct Timed {
    double t_s;
    mc_hal_can_frame_t f;
  };
  std::vector<Timed> frames_;
  size_t next_ = 0;
};

struct CandumpLogStats {
  uint64_t tx_frames = 0;
  uint64_t tx_rejected = 0;  // refused by mc_hal_can_frame_check
  uint64_t rx_frames = 0;
};

class CandumpLogCan {
 public:
  // out_path: log to write ("" = none, frames are only counted).
  // rx_path: command script to replay ("" = none). now_s: the clock that
  // stamps the frames sent; rx_now_s (default now_s): the clock a script
  // frame's time stamp must have reached to be received (the SIL stamps a
  // period's frames with the period's end and receives at its start, so a
  // reply to a frame stamped t, sent at t, arrives in the next period).
  // Throws std::runtime_error naming the file that cannot be opened or the
  // script line that cannot be parsed.
  CandumpLogCan(const std::string& out_path, const std::string& iface,
                std::function<double()> now_s, const std::string& rx_path = "",
                std::function<uint32_t()> now_ticks = nullptr,
                std::function<double()> rx_now_s = nullptr);
  ~CandumpLogCan();
  CandumpLogCan(const CandumpLogCan&) = delete;
  CandumpLogCan& operator=(const CandumpLogCan&) = delete;

  const mc_hal_can_t* hal() const { return &dev_; }
  const CandumpLogStats& stats() const { return stats_; }
  // Flush the log (also done by the destructor); false on a write error.
  bool flush();

  int send(const mc_hal_can_frame_t* f) noexcept;
  int receive(mc_hal_can_frame_t* f) noexcept;
  int get_status(mc_hal_can_status_t* st) noexcept;

 private:
  std::FILE* out_ = nullptr;
  bool write_error_ = false;
  std::string iface_;
  std::function<double()> now_s_;
  std::function<double()> rx_now_s_;
  std::function<uint32_t()> now_ticks_;
  std::unique_ptr<CandumpScript> script_;
  CandumpLogStats stats_;
  mc_hal_can_t dev_{};
};

}  // namespace hal_host

#endif  // HAL_HOST_CANDUMP_LOG_HPP
