// hal_host::PilLink: the host end of the processor-in-the-loop link. Starts
// QEMU (netduinoplus2, the STM32F405's Cortex-M4F) on a firmware image whose
// USART1 is connected to a Unix socket this object listens on, and moves
// whole frames (firmware/targets/pil/mc_pil_frame.h) across it.
//
// Blocking, with a deadline per receive: the emulated target answers each
// frame within milliseconds, so a missing answer is an error (the target
// faulted or exited), reported with QEMU's exit status.
#ifndef HAL_HOST_PIL_LINK_HPP
#define HAL_HOST_PIL_LINK_HPP

#include <sys/types.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace hal_host {

struct PilLinkOptions {
  std::string qemu;  // qemu-system-arm executable
  std::string elf;   // the PIL firmware image
  // The emulated bootloader (firmware/boot, hal/pil/mc_boot_pil.c), or ""
  // for an image linked to start at the reset vector. With it, QEMU loads
  // both; the bootloader checks the image (linked for the application slot,
  // sealed) and starts it, or exits (status 4: it found no host for an
  // update) when the image is not valid.
  std::string boot_elf;
  std::string semihost_log;  // file for the target's semihosting text ("" = none)
  double receive_timeout_s = 10.0;
};

class PilLink {
 public:
  // Throws std::runtime_error if QEMU cannot be started or does not connect.
  explicit PilLink(const PilLinkOptions& o);
  ~PilLink();
  PilLink(const PilLink&) = delete;
  PilLink& operator=(const PilLink&) = delete;

  // Send a whole encoded frame. Throws std::runtime_error on a write error.
  void send(const uint8_t* p, std::size_t n);
  // Receive one whole frame (sync byte to CRC). Throws std::runtime_error on
  // timeout, end of stream or a byte that is not a frame start.
  std::vector<uint8_t> receive_frame();
  // Send END with exit_code, wait for QEMU to exit (bounded) and return its
  // exit status (the target's semihosting exit code), or -1 if it had to be
  // killed.
  int finish(int32_t exit_code);

 private:
  void start();
  void cleanup() noexcept;
  void read_exact(uint8_t* p, std::size_t n);
  int wait_exit(double timeout_s);

  PilLinkOptions opt_;
  std::string dir_;
  std::string sock_path_;
  int listen_fd_ = -1;
  int fd_ = -1;
  pid_t pid_ = -1;
  bool finished_ = false;
};

}  // namespace hal_host

#endif  // HAL_HOST_PIL_LINK_HPP
