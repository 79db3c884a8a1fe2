// hal_host::SocketCan: the HAL's CAN on a Linux SocketCAN interface
// (socket(PF_CAN, SOCK_RAW, CAN_RAW), e.g. vcan0 or a USB adapter's can0).
//
// - Non-blocking: send() never waits; a full socket/driver queue (ENOBUFS,
//   EAGAIN) is -ENOBUFS, a bus-off or down interface (ENETDOWN) is
//   -ENETDOWN, each counted.
// - Error frames are subscribed to (CAN_RAW_ERR_FILTER): controller state
//   (warning / passive / bus-off / restarted), error counters when the
//   driver reports them, rx overflows; they update get_status() and are
//   never returned by receive().
// - Frames the kernel dropped because this socket's receive queue was full
//   are counted with SO_RXQ_OVFL (rx_overrun_count).
// - CAN FD: with fd = true the socket is switched to CAN_RAW_FD_FRAMES when
//   the interface's MTU allows it; fd_capable says whether that worked.
#ifndef HAL_HOST_SOCKETCAN_HPP
#define HAL_HOST_SOCKETCAN_HPP

#include <cstdint>
#include <functional>
#include <string>

#include "hal/can.h"

namespace hal_host {

struct SocketCanStats {
  uint64_t tx_frames = 0;
  uint64_t tx_nobufs = 0;   // ENOBUFS / EAGAIN: queue full, frame dropped
  uint64_t tx_netdown = 0;  // ENETDOWN: bus-off or interface down
  uint64_t tx_errors = 0;   // any other send error
  uint64_t rx_frames = 0;
  uint64_t rx_error_frames = 0;
  uint64_t bus_off_events = 0;
  uint32_t rx_dropped = 0;  // kernel's SO_RXQ_OVFL count for this socket
};

// Fold one SocketCAN error frame (can_id with CAN_ERR_FLAG, the 8 data bytes
// of linux/can/error.h) into a bus status and the counters. A function of
// its own so it can be tested on a kernel without CAN.
void socketcan_apply_error(uint32_t can_id, const uint8_t data[8], mc_hal_can_status_t* status,
                           SocketCanStats* stats) noexcept;

class SocketCan {
 public:
  // Opens and binds the socket. Throws std::system_error with the failing
  // call and interface (EAFNOSUPPORT on a kernel without CAN, ENODEV for an
  // unknown interface). now_ticks stamps received frames (may be empty).
  explicit SocketCan(const std::string& ifname, bool fd = false,
                     std::function<uint32_t()> now_ticks = nullptr);
  ~SocketCan();
  SocketCan(const SocketCan&) = delete;
  SocketCan& operator=(const SocketCan&) = delete;

  const mc_hal_can_t* hal() const { return &dev_; }
  const SocketCanStats& stats() const { return stats_; }
  const std::string& ifname() const { return ifname_; }

  int send(const mc_hal_can_frame_t* f) noexcept;
  int receive(mc_hal_can_frame_t* f) noexcept;
  int get_status(mc_hal_can_status_t* st) noexcept;

 private:
  int fd_ = -1;
  bool fd_capable_ = false;
  std::string ifname_;
  std::function<uint32_t()> now_ticks_;
  mc_hal_can_status_t status_{};
  SocketCanStats stats_;
  mc_hal_can_t dev_{};
};

}  // namespace hal_host

#endif  // HAL_HOST_SOCKETCAN_HPP
