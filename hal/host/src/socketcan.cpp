#include "hal_host/socketcan.hpp"

#include <cerrno>
#include <cstring>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <system_error>
#include <unistd.h>

#include "hal_host/can_ops.hpp"

namespace hal_host {
namespace {

[[noreturn]] void fail(int err, const std::string& what, const std::string& ifname) {
  throw std::system_error(err, std::generic_category(), "SocketCAN " + ifname + ": " + what);
}

// At most this many error frames are consumed by one receive() call, so it
// stays bounded on a bus that floods errors.
constexpr int kMaxErrorFramesPerReceive = 64;

}  // namespace

SocketCan::SocketCan(const std::string& ifname, bool fd, std::function<uint32_t()> now_ticks)
    : ifname_(ifname), now_ticks_(std::move(now_ticks)) {
  if (ifname.empty() || ifname.size() >= IFNAMSIZ) fail(EINVAL, "bad interface name", ifname);
  fd_ = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd_ < 0) fail(errno, "socket(PF_CAN, SOCK_RAW, CAN_RAW)", ifname);
  try {
    const unsigned idx = if_nametoindex(ifname.c_str());
    if (idx == 0) fail(errno, "no such interface", ifname);
    can_err_mask_t err_mask =
        CAN_ERR_TX_TIMEOUT | CAN_ERR_CRTL | CAN_ERR_BUSOFF | CAN_ERR_RESTARTED;
#ifdef CAN_ERR_CNT
    err_mask |= CAN_ERR_CNT;
#endif
    if (setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof err_mask) != 0) {
      fail(errno, "setsockopt(CAN_RAW_ERR_FILTER)", ifname);
    }
    const int one = 1;
    if (setsockopt(fd_, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof one) != 0) {
      fail(errno, "setsockopt(SO_RXQ_OVFL)", ifname);
    }
    if (fd) {
      struct ifreq ifr {};
      std::strncpy(ifr.ifr_name, ifname.c_str(), IFNAMSIZ - 1);
      if (ioctl(fd_, SIOCGIFMTU, &ifr) == 0 && ifr.ifr_mtu == static_cast<int>(CANFD_MTU) &&
          setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &one, sizeof one) == 0) {
        fd_capable_ = true;
      }
    }
    struct sockaddr_can addr {};
    addr.can_family = AF_CAN;
    addr.can_ifindex = static_cast<int>(idx);
    if (bind(fd_, reinterpret_cast<struct sockaddr*>(&addr), sizeof addr) != 0) {
      fail(errno, "bind", ifname);
    }
  } catch (...) {
    ::close(fd_);
    fd_ = -1;
    throw;
  }
  status_.state = MC_HAL_CAN_STATE_ERROR_ACTIVE;
  status_.fd_capable = fd_capable_;
  dev_.ops = can_ops<SocketCan>();
  dev_.ctx = this;
}

SocketCan::~SocketCan() {
  if (fd_ >= 0) ::close(fd_);
}

int SocketCan::send(const mc_hal_can_frame_t* f) noexcept {
  const int rc = mc_hal_can_frame_check(f, fd_capable_);
  if (rc != 0) return rc;
  canid_t id = f->id;
  if (f->flags & MC_HAL_CAN_FLAG_EXT) id |= CAN_EFF_FLAG;
  ssize_t n;
  size_t want;
  if (f->flags & MC_HAL_CAN_FLAG_FD) {
    struct canfd_frame cf {};
    cf.can_id = id;
    cf.len = f->len;
    cf.flags = (f->flags & MC_HAL_CAN_FLAG_BRS) ? CANFD_BRS : 0;
    std::memcpy(cf.data, f->data, f->len);
    want = CANFD_MTU;
    n = ::write(fd_, &cf, want);
  } else {
    struct can_frame cf {};
    if (f->flags & MC_HAL_CAN_FLAG_RTR) id |= CAN_RTR_FLAG;
    cf.can_id = id;
    cf.can_dlc = f->len;
    if (!(f->flags & MC_HAL_CAN_FLAG_RTR)) std::memcpy(cf.data, f->data, f->len);
    want = CAN_MTU;
    n = ::write(fd_, &cf, want);
  }
  if (n == static_cast<ssize_t>(want)) {
    ++stats_.tx_frames;
    return 0;
  }
  const int e = (n < 0) ? errno : EIO;
  if (e == ENOBUFS || e == EAGAIN) {
    ++stats_.tx_nobufs;
    return -ENOBUFS;
  }
  if (e == ENETDOWN) {
    ++stats_.tx_netdown;
    return -ENETDOWN;
  }
  ++stats_.tx_errors;
  return -EIO;
}

void socketcan_apply_error(uint32_t can_id, const uint8_t data[8], mc_hal_can_status_t* status,
                           SocketCanStats* stats) noexcept {
  ++stats->rx_error_frames;
  if (can_id & CAN_ERR_CRTL) {
    const uint8_t c = data[1];
    if (c & CAN_ERR_CRTL_RX_OVERFLOW) ++status->rx_overrun_count;
    if (c & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) {
      status->state = MC_HAL_CAN_STATE_ERROR_PASSIVE;
    } else if (c & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING)) {
      status->state = MC_HAL_CAN_STATE_ERROR_WARNING;
    }
#ifdef CAN_ERR_CRTL_ACTIVE
    if (c & CAN_ERR_CRTL_ACTIVE) status->state = MC_HAL_CAN_STATE_ERROR_ACTIVE;
#endif
  }
  if (can_id & CAN_ERR_RESTARTED) status->state = MC_HAL_CAN_STATE_ERROR_ACTIVE;
  if (can_id & CAN_ERR_BUSOFF) {
    if (status->state != MC_HAL_CAN_STATE_BUS_OFF) ++stats->bus_off_events;
    status->state = MC_HAL_CAN_STATE_BUS_OFF;
  }
#ifdef CAN_ERR_CNT
  if (can_id & CAN_ERR_CNT) {
    status->tx_err_count = data[6];
    status->rx_err_count = data[7];
  }
#endif
}

int SocketCan::receive(mc_hal_can_frame_t* f) noexcept {
  for (int i = 0; i < kMaxErrorFramesPerReceive; ++i) {
    struct canfd_frame cf {};
    struct iovec iov {
      &cf, sizeof cf
    };
    alignas(struct cmsghdr) char ctrl[CMSG_SPACE(sizeof(uint32_t))];
    struct msghdr msg {};
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = ctrl;
    msg.msg_controllen = sizeof ctrl;
    const ssize_t n = ::recvmsg(fd_, &msg, MSG_DONTWAIT);
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK) return -EAGAIN;
      if (errno == EINTR) continue;
      return -EIO;
    }
    for (struct cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
      if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL) {
        uint32_t dropped;
        std::memcpy(&dropped, CMSG_DATA(c), sizeof dropped);
        stats_.rx_dropped = dropped;
      }
    }
    if (n != static_cast<ssize_t>(CAN_MTU) && n != static_cast<ssize_t>(CANFD_MTU)) return -EIO;
    if (cf.can_id & CAN_ERR_FLAG) {
      uint8_t d[8] = {0};
      std::memcpy(d, cf.data, sizeof d);
      socketcan_apply_error(cf.can_id, d, &status_, &stats_);
      continue;
    }
    mc_hal_can_frame_t out{};
    if (cf.can_id & CAN_EFF_FLAG) {
      out.flags |= MC_HAL_CAN_FLAG_EXT;
      out.id = cf.can_id & CAN_EFF_MASK;
    } else {
      out.id = cf.can_id & CAN_SFF_MASK;
    }
    if (n == static_cast<ssize_t>(CANFD_MTU)) {
      out.flags |= MC_HAL_CAN_FLAG_FD;
      if (cf.flags & CANFD_BRS) out.flags |= MC_HAL_CAN_FLAG_BRS;
      out.len = cf.len <= CANFD_MAX_DLEN ? cf.len : CANFD_MAX_DLEN;
    } else {
      if (cf.can_id & CAN_RTR_FLAG) out.flags |= MC_HAL_CAN_FLAG_RTR;
      out.len = cf.len <= CAN_MAX_DLEN ? cf.len : CAN_MAX_DLEN;
    }
    if (!(out.flags & MC_HAL_CAN_FLAG_RTR)) std::memcpy(out.data, cf.data, out.len);
    out.timestamp_ticks = now_ticks_ ? now_ticks_() : 0u;
    *f = out;
    ++stats_.rx_frames;
    return 0;
  }
  return -EAGAIN;
}

int SocketCan::get_status(mc_hal_can_status_t* st) noexcept {
  *st = status_;
  st->rx_overrun_count = status_.rx_overrun_count + stats_.rx_dropped;
  st->fd_capable = fd_capable_;
  return 0;
}

}  // namespace hal_host
