#include "hal_host/socketcand.hpp"

#include <algorithm>
#include <arpa/inet.h>
#include <cerrno>
#include <cstring>
#include <linux/inet_diag.h>
#include <linux/netlink.h>
#include <linux/sock_diag.h>
#include <linux/sockios.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <stdexcept>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include "hal_host/can_ops.hpp"

namespace hal_host {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

[[noreturn]] void fail(int err, const std::string& what, const std::string& where) {
  throw std::runtime_error("socketcand server on " + where + ": " + what + ": " +
                           std::strerror(err));
}

// Bytes read from one client per service() call (bounds the work of a step).
constexpr size_t kReadChunk = 4096;
constexpr int kReadChunksPerService = 16;
// Queued bytes beyond which the written part is dropped from the front.
constexpr size_t kCompactBytes = 64u << 10;

}  // namespace

SocketcandCan::SocketcandCan(const std::string& host, uint16_t port, const std::string& channel,
                             std::function<double()> now_s, std::function<uint32_t()> now_ticks,
                             size_t queue_bytes)
    : host_(host == "localhost" ? "127.0.0.1" : host),
      channel_(channel),
      queue_bytes_(queue_bytes),
      now_s_(std::move(now_s)),
      now_ticks_(std::move(now_ticks)) {
  const std::string where = host + ":" + std::to_string(port);
  if (!now_s_) throw std::invalid_argument("SocketcandCan: a clock is required");
  if (channel_.empty() || channel_.size() > socketcand::kMaxBusName) {
    throw std::invalid_argument("SocketcandCan: bad channel name '" + channel_ + "'");
  }
  struct sockaddr_in a {};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  if (inet_pton(AF_INET, host_.c_str(), &a.sin_addr) != 1) {
    throw std::runtime_error("socketcand server: host '" + host +
                             "' is not an IPv4 address (or localhost)");
  }
  listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (listen_fd_ < 0) fail(errno, "socket", where);
  const int one = 1;
  if (setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) != 0 ||
      bind(listen_fd_, reinterpret_cast<struct sockaddr*>(&a), sizeof a) != 0 ||
      listen(listen_fd_, static_cast<int>(kMaxClients)) != 0) {
    const int e = errno;
    ::close(listen_fd_);
    listen_fd_ = -1;
    fail(e, "bind/listen", where);
  }
  socklen_t len = sizeof a;
  if (getsockname(listen_fd_, reinterpret_cast<struct sockaddr*>(&a), &len) == 0) {
    port_ = ntohs(a.sin_port);
  }
  dev_.ops = can_ops<SocketcandCan>();
  dev_.ctx = this;
}

SocketcandCan::~SocketcandCan() {
  for (auto& c : clients_) {
    if (c->fd >= 0) ::close(c->fd);
  }
  if (listen_fd_ >= 0) ::close(listen_fd_);
  if (diag_fd_ >= 0) ::close(diag_fd_);
}

size_t SocketcandCan::raw_clients() const {
  return static_cast<size_t>(std::count_if(clients_.begin(), clients_.end(), [](const auto& c) {
    return c->mode == Mode::kRaw && !c->holding && !c->closing && !c->dead;
  }));
}

void SocketcandCan::close_client(Client& c) noexcept {
  if (c.fd >= 0) ::close(c.fd);
  c.fd = -1;
  c.dead = true;
}

void SocketcandCan::reply(Client& c, const std::string& text) noexcept {
  if (c.out.size() - c.off + text.size() > queue_bytes_) {
    close_client(c);  // it sends and never reads: its replies would grow without bound
    return;
  }
  try {
    c.out += text;
  } catch (...) {
    close_client(c);
  }
}

void SocketcandCan::queue_frame(Client& c, const std::string& line) noexcept {
  if (c.out.size() - c.off + line.size() > queue_bytes_) {
    ++stats_.tx_client_drops;
    return;
  }
  try {
    c.out += line;
  } catch (...) {
    close_client(c);
  }
}

void SocketcandCan::accept_new() noexcept {
  if (listen_fd_ < 0) return;
  for (;;) {
    struct sockaddr_in peer {};
    socklen_t len = sizeof peer;
    const int fd = accept4(listen_fd_, reinterpret_cast<struct sockaddr*>(&peer), &len,
                           SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) return;  // EAGAIN: none waiting; anything else: retried next time
    if (clients_.size() >= kMaxClients) {
      const std::string e = socketcand::format_error("too many clients");
      (void)::send(fd, e.data(), e.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
      ::close(fd);
      ++stats_.clients_refused;
      continue;
    }
    const int one = 1;
    (void)setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    try {
      auto c = std::make_unique<Client>();
      c->fd = fd;
      c->peer_ip = peer.sin_addr.s_addr;
      c->peer_port = peer.sin_port;
      struct sockaddr_in own {};
      len = sizeof own;
      if (getsockname(fd, reinterpret_cast<struct sockaddr*>(&own), &len) == 0) {
        c->own_ip = own.sin_addr.s_addr;
        c->own_port = own.sin_port;
      }
      c->out = "< hi >";
      clients_.push_back(std::move(c));
    } catch (...) {
      ::close(fd);
      continue;
    }
    ++stats_.clients_accepted;
    if (clients_.size() > stats_.clients_max) stats_.clients_max = clients_.size();
  }
}

void SocketcandCan::inject(const Client& from, const mc_hal_can_frame_t& f) noexcept {
  if (rx_.size() >= kRxQueueFrames) {
    ++stats_.rx_overruns;
  } else {
    try {
      rx_.push_back(f);
      ++stats_.rx_frames;
    } catch (...) {
      ++stats_.rx_overruns;
    }
  }
  // the other clients see it as they would on the bus (not the sender)
  std::string line;
  for (auto& c : clients_) {
    if (c.get() == &from || c->mode != Mode::kRaw || c->closing || c->dead) continue;
    try {
      if (line.empty()) line = socketcand::format_frame(now_s_(), f);
    } catch (...) {
      return;
    }
    queue_frame(*c, line);
  }
}

void SocketcandCan::handle(Client& c, const std::string& body) noexcept {
  socketcand::Command cmd;
  std::string why;
  try {
    bool ok = socketcand::parse_command(body, &cmd, &why);
    if (ok && c.mode == Mode::kNoBus && cmd.verb != socketcand::Verb::kOpen) {
      ok = false;
      why = "open the bus first: open " + channel_;
    } else if (ok && c.mode != Mode::kNoBus && cmd.verb == socketcand::Verb::kOpen) {
      ok = false;
      why = "the bus is open already";
    }
    if (ok && cmd.verb == socketcand::Verb::kOpen && cmd.bus != channel_) {
      ++stats_.commands_refused;
      reply(c, socketcand::format_error("could not open bus"));
      c.closing = true;  // as socketcand: refused, then disconnected
      return;
    }
    if (!ok) {
      ++stats_.commands_refused;
      reply(c, socketcand::format_error(why));
      return;
    }
  } catch (...) {
    close_client(c);
    return;
  }
  ++stats_.commands;
  switch (cmd.verb) {
    case socketcand::Verb::kOpen:
      c.mode = Mode::kBcm;
      reply(c, "< ok >");
      break;
    case socketcand::Verb::kRawMode:
      reply(c, "< ok >");
      if (c.mode != Mode::kRaw) {
        c.mode = Mode::kRaw;
        c.holding = true;
        c.hold_at = c.out.size();
        c.hold_t0 = Clock::now();
      }
      break;
    case socketcand::Verb::kBcmMode:
      c.mode = Mode::kBcm;
      c.holding = false;
      reply(c, "< ok >");
      break;
    case socketcand::Verb::kEcho:
      reply(c, "< echo >");
      break;
    case socketcand::Verb::kSend:
      inject(c, cmd.frame);
      break;
  }
}

void SocketcandCan::read_client(Client& c) noexcept {
  char buf[kReadChunk];
  for (int i = 0; i < kReadChunksPerService && !c.dead && !c.closing; ++i) {
    const ssize_t n = ::recv(c.fd, buf, sizeof buf, MSG_DONTWAIT);
    if (n == 0) {
      close_client(c);  // the client went away
      return;
    }
    if (n < 0) {
      if (errno == EINTR) continue;
      if (errno != EAGAIN && errno != EWOULDBLOCK) close_client(c);
      return;
    }
    try {
      c.in.feed(buf, static_cast<size_t>(n));
      std::string text;
      for (;;) {
        const auto ev = c.in.next(&text);
        if (ev == socketcand::CommandSplitter::Event::kNone) break;
        if (ev == socketcand::CommandSplitter::Event::kCommand) {
          handle(c, text);
        } else {
          ++stats_.commands_refused;
          reply(c, socketcand::format_error(text));
        }
        if (c.dead || c.closing) return;
      }
    } catch (...) {
      close_client(c);
      return;
    }
  }
}

int SocketcandCan::peer_unread(const Client& c) noexcept {
  int outq = 0;
  if (ioctl(c.fd, SIOCOUTQ, &outq) == 0 && outq > 0) return 1;  // not even delivered
  if (diag_fd_ == -2) return -1;
  if (diag_fd_ < 0) {
    diag_fd_ = ::socket(AF_NETLINK, SOCK_DGRAM | SOCK_CLOEXEC, NETLINK_SOCK_DIAG);
    if (diag_fd_ < 0) {
      diag_fd_ = -2;
      return -1;
    }
  }
  struct {
    struct nlmsghdr nlh;
    struct inet_diag_req_v2 r;
  } req{};
  req.nlh.nlmsg_len = sizeof req;
  req.nlh.nlmsg_type = SOCK_DIAG_BY_FAMILY;
  req.nlh.nlmsg_flags = NLM_F_REQUEST;
  req.nlh.nlmsg_seq = ++diag_seq_;
  req.r.sdiag_family = AF_INET;
  req.r.sdiag_protocol = IPPROTO_TCP;
  req.r.idiag_states = ~0u;
  // the client's socket: its local end is our peer, its remote end is us
  req.r.id.idiag_sport = c.peer_port;
  req.r.id.idiag_dport = c.own_port;
  req.r.id.idiag_src[0] = c.peer_ip;
  req.r.id.idiag_dst[0] = c.own_ip;
  req.r.id.idiag_cookie[0] = INET_DIAG_NOCOOKIE;
  req.r.id.idiag_cookie[1] = INET_DIAG_NOCOOKIE;
  struct sockaddr_nl kernel {};
  kernel.nl_family = AF_NETLINK;
  if (sendto(diag_fd_, &req, sizeof req, 0, reinterpret_cast<struct sockaddr*>(&kernel),
             sizeof kernel) != static_cast<ssize_t>(sizeof req)) {
    return -1;
  }
  alignas(struct nlmsghdr) char buf[4096];
  for (;;) {  // the answer is queued before sendto returns; drop stale ones
    ssize_t n = ::recv(diag_fd_, buf, sizeof buf, MSG_DONTWAIT);
    if (n <= 0) return -1;
    for (auto* h = reinterpret_cast<struct nlmsghdr*>(buf); NLMSG_OK(h, n); h = NLMSG_NEXT(h, n)) {
      if (h->nlmsg_seq != diag_seq_) continue;
      if (h->nlmsg_type != SOCK_DIAG_BY_FAMILY) return -1;  // NLMSG_ERROR: not local
      const auto* m = static_cast<const struct inet_diag_msg*>(NLMSG_DATA(h));
      return m->idiag_rqueue > 0 ? 1 : 0;
    }
  }
}

void SocketcandCan::update_hold(Client& c) noexcept {
  if (!c.holding || c.dead || c.off < c.hold_at) return;  // < ok > not written yet
  const double t = seconds_since(c.hold_t0);
  const int unread = peer_unread(c);
  if (unread == 0) {
    c.holding = false;
    ++stats_.raw_holds_seen_read;
  } else if (t >= kRawHoldMaxS || (unread < 0 && t >= kRawHoldFallbackS)) {
    c.holding = false;
    ++stats_.raw_holds_timed;
  }
}

void SocketcandCan::write_client(Client& c) noexcept {
  if (c.dead) return;
  const size_t limit = c.holding ? c.hold_at : c.out.size();
  while (c.off < limit) {
    const ssize_t n =
        ::send(c.fd, c.out.data() + c.off, limit - c.off, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n < 0) {
      if (errno == EINTR) continue;
      if (errno != EAGAIN && errno != EWOULDBLOCK) close_client(c);
      return;
    }
    c.off += static_cast<size_t>(n);
  }
  if (c.off == c.out.size()) {
    c.out.clear();
    c.hold_at -= std::min(c.hold_at, c.off);
    c.off = 0;
  } else if (c.off >= kCompactBytes) {
    c.out.erase(0, c.off);
    c.hold_at -= std::min(c.hold_at, c.off);
    c.off = 0;
  }
}

void SocketcandCan::service() noexcept {
  accept_new();
  for (const auto& cp : clients_) {
    Client& c = *cp;
    if (!c.closing) read_client(c);
    update_hold(c);
    write_client(c);
    if (c.closing && !c.dead && c.off == c.out.size()) close_client(c);
  }
  for (size_t i = 0; i < clients_.size();) {
    if (clients_[i]->dead) {
      clients_.erase(clients_.begin() + static_cast<std::ptrdiff_t>(i));
    } else {
      ++i;
    }
  }
}

bool SocketcandCan::wait_for_clients(size_t n, double timeout_s) {
  const auto t0 = Clock::now();
  for (;;) {
    service();
    if (raw_clients() >= n) return true;
    if (timeout_s >= 0.0 && seconds_since(t0) >= timeout_s) return false;
    (void)::poll(nullptr, 0, 2);
  }
}

bool SocketcandCan::finish(double timeout_s) {
  if (listen_fd_ >= 0) {
    ::close(listen_fd_);
    listen_fd_ = -1;
  }
  const auto t0 = Clock::now();
  bool flushed = false;
  for (;;) {
    for (const auto& c : clients_) c->holding = false;
    service();
    flushed = true;
    for (const auto& c : clients_) flushed = flushed && c->off == c->out.size();
    if (flushed || seconds_since(t0) >= timeout_s) break;
    (void)::poll(nullptr, 0, 2);
  }
  // Read what the clients sent last (a socket closed with unread input
  // resets the connection, which may discard what the client has not read
  // yet), then close: the kernel sends what it holds, then the end.
  char buf[kReadChunk];
  for (const auto& c : clients_) {
    if (c->off != c->out.size()) ++stats_.unflushed_clients;
    while (c->fd >= 0 && ::recv(c->fd, buf, sizeof buf, MSG_DONTWAIT) > 0) {
    }
    close_client(*c);
  }
  clients_.clear();
  return flushed;
}

int SocketcandCan::send(const mc_hal_can_frame_t* f) noexcept {
  const int rc = mc_hal_can_frame_check(f, false);
  if (rc != 0) return rc;
  ++stats_.tx_frames;
  std::string line;
  for (const auto& c : clients_) {
    if (c->mode != Mode::kRaw || c->closing || c->dead) continue;
    try {
      if (line.empty()) line = socketcand::format_frame(now_s_(), *f);
    } catch (...) {
      return -EIO;
    }
    queue_frame(*c, line);
    update_hold(*c);
    write_client(*c);
  }
  return 0;
}

int SocketcandCan::receive(mc_hal_can_frame_t* f) noexcept {
  if (rx_.empty()) service();
  if (rx_.empty()) return -EAGAIN;
  *f = rx_.front();
  rx_.pop_front();
  f->timestamp_ticks = now_ticks_ ? now_ticks_() : 0u;
  return 0;
}

int SocketcandCan::get_status(mc_hal_can_status_t* st) noexcept {
  *st = mc_hal_can_status_t{};
  st->state = MC_HAL_CAN_STATE_ERROR_ACTIVE;
  st->rx_overrun_count = static_cast<uint32_t>(stats_.rx_overruns);
  st->fd_capable = false;
  return 0;
}

}  // namespace hal_host
