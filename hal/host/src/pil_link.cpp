// See pil_link.hpp.
#include "hal_host/pil_link.hpp"

#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <thread>

extern "C" {
#include "mc_pil_frame.h"
}

extern char** environ;  // NOLINT(readability-redundant-declaration): POSIX, for posix_spawn

namespace hal_host {

namespace {

std::runtime_error sys_error(const std::string& what) {
  return std::runtime_error("PilLink: " + what + ": " + std::strerror(errno));
}

int poll_ms(int fd, short events, int timeout_ms) {
  pollfd p{};
  p.fd = fd;
  p.events = events;
  int rc;
  do {
    rc = ::poll(&p, 1, timeout_ms);
  } while (rc < 0 && errno == EINTR);
  return rc;
}

}  // namespace

PilLink::PilLink(const PilLinkOptions& o) : opt_(o) {
  try {
    start();
  } catch (...) {
    cleanup();
    throw;
  }
}

void PilLink::start() {
  char tmpl[] = "/tmp/mc_pil_XXXXXX";
  if (::mkdtemp(tmpl) == nullptr) throw sys_error("mkdtemp");
  dir_ = tmpl;
  sock_path_ = dir_ + "/usart1.sock";

  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  if (sock_path_.size() >= sizeof(addr.sun_path))
    throw std::runtime_error("PilLink: socket path too long");
  std::memcpy(addr.sun_path, sock_path_.c_str(), sock_path_.size() + 1);
  listen_fd_ = ::socket(AF_UNIX, SOCK_STREAM, 0);
  if (listen_fd_ < 0) throw sys_error("socket");
  if (::bind(listen_fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    throw sys_error("bind " + sock_path_);
  }
  if (::listen(listen_fd_, 1) != 0) throw sys_error("listen");

  // QEMU: USART1 (the first -serial) connects to our socket as a client;
  // semihosting (exit code, diagnostics) is enabled for the END frame.
  std::vector<std::string> args = {opt_.qemu,  "-M",   "netduinoplus2", "-display",          "none",
                                   "-monitor", "none", "-serial",       "unix:" + sock_path_};
  if (!opt_.semihost_log.empty()) {
    args.insert(args.end(), {"-chardev", "file,id=sh0,path=" + opt_.semihost_log,
                             "-semihosting-config", "enable=on,target=native,chardev=sh0"});
  } else {
    args.insert(args.end(), {"-semihosting-config", "enable=on,target=native"});
  }
  if (opt_.boot_elf.empty()) {
    args.insert(args.end(), {"-kernel", opt_.elf});
  } else {
    args.insert(args.end(), {"-kernel", opt_.boot_elf, "-device", "loader,file=" + opt_.elf});
  }
  std::vector<char*> argv;
  argv.reserve(args.size() + 1);
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const int rc = ::posix_spawn(&pid_, opt_.qemu.c_str(), nullptr, nullptr, argv.data(), environ);
  if (rc != 0) {
    pid_ = -1;
    errno = rc;
    throw sys_error("posix_spawn " + opt_.qemu);
  }

  if (poll_ms(listen_fd_, POLLIN, 10000) <= 0) {
    throw std::runtime_error("PilLink: QEMU did not connect to USART1 within 10 s");
  }
  fd_ = ::accept(listen_fd_, nullptr, nullptr);
  if (fd_ < 0) throw sys_error("accept");
}

PilLink::~PilLink() {
  cleanup();
}

void PilLink::cleanup() noexcept {
  if (pid_ > 0 && !finished_) {
    // Best effort: ask the target to stop, then make sure QEMU is gone.
    if (fd_ >= 0) {
      uint8_t buf[MC_PIL_MAX_FRAME];
      const std::size_t n = mc_pil_encode_end(0, buf, sizeof buf);
      (void)::send(fd_, buf, n, MSG_NOSIGNAL);
    }
    if (wait_exit(2.0) == -2) {
      (void)::kill(pid_, SIGKILL);
      (void)::waitpid(pid_, nullptr, 0);
    }
  }
  if (fd_ >= 0) (void)::close(fd_);
  if (listen_fd_ >= 0) (void)::close(listen_fd_);
  if (!sock_path_.empty()) (void)::unlink(sock_path_.c_str());
  if (!dir_.empty()) (void)::rmdir(dir_.c_str());
  fd_ = -1;
  listen_fd_ = -1;
  sock_path_.clear();
  dir_.clear();
}

void PilLink::send(const uint8_t* p, std::size_t n) {
  std::size_t done = 0;
  while (done < n) {
    const ssize_t w = ::send(fd_, p + done, n - done, MSG_NOSIGNAL);
    if (w < 0) {
      if (errno == EINTR) continue;
      throw sys_error("send");
    }
    done += static_cast<std::size_t>(w);
  }
}

void PilLink::read_exact(uint8_t* p, std::size_t n) {
  const int timeout_ms = static_cast<int>(opt_.receive_timeout_s * 1000.0);
  std::size_t done = 0;
  while (done < n) {
    const int pr = poll_ms(fd_, POLLIN, timeout_ms);
    if (pr == 0) {
      throw std::runtime_error("PilLink: no answer from the target within the timeout");
    }
    if (pr < 0) throw sys_error("poll");
    const ssize_t r = ::recv(fd_, p + done, n - done, 0);
    if (r == 0) {
      const int st = wait_exit(1.0);
      throw std::runtime_error("PilLink: the target closed the link (QEMU exit status " +
                               std::to_string(st) + ")");
    }
    if (r < 0) {
      if (errno == EINTR) continue;
      throw sys_error("recv");
    }
    done += static_cast<std::size_t>(r);
  }
}

std::vector<uint8_t> PilLink::receive_frame() {
  std::vector<uint8_t> f(MC_PIL_HEADER_LEN);
  read_exact(f.data(), MC_PIL_HEADER_LEN);
  if (f[0] != MC_PIL_SYNC)
    throw std::runtime_error("PilLink: frame does not start with the sync byte");
  const std::size_t n = mc_pil_frame_len(f.data(), f.size());
  f.resize(n);
  read_exact(f.data() + MC_PIL_HEADER_LEN, n - MC_PIL_HEADER_LEN);
  return f;
}

// Exit status of QEMU if it ends within timeout_s; -2 if it is still running.
int PilLink::wait_exit(double timeout_s) {
  if (pid_ <= 0) return -1;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  for (;;) {
    int status = 0;
    const pid_t r = ::waitpid(pid_, &status, WNOHANG);
    if (r == pid_) {
      pid_ = -1;
      finished_ = true;
      return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }
    if (r < 0) return -1;
    if (std::chrono::steady_clock::now() > deadline) return -2;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

int PilLink::finish(int32_t exit_code) {
  uint8_t buf[MC_PIL_MAX_FRAME];
  const std::size_t n = mc_pil_encode_end(exit_code, buf, sizeof buf);
  send(buf, n);
  const int st = wait_exit(10.0);
  if (st == -2) {
    (void)::kill(pid_, SIGKILL);
    (void)::waitpid(pid_, nullptr, 0);
    pid_ = -1;
    finished_ = true;
    return -1;
  }
  return st;
}

}  // namespace hal_host
