// The link options of the PIL tests: this build's QEMU, the PIL image
// started through the emulated bootloader (it checks the sealed image), the
// target's semihosting text in the build's test folder.
#pragma once

#include <string>

#include "hal_host/pil_link.hpp"

inline hal_host::PilLinkOptions pil_test_link(const std::string& log_name,
                                              double receive_timeout_s = 10.0) {
  hal_host::PilLinkOptions l;
  l.qemu = MC_QEMU_ARM;
  l.elf = MC_PIL_ELF;
  l.boot_elf = MC_BOOT_PIL_ELF;  // the image starts through the bootloader
  l.semihost_log = std::string(MC_PIL_LOG_DIR) + "/" + log_name;
  // Lock-step: the target answers every frame; this only bounds how long a
  // crashed target is waited for.
  l.receive_timeout_s = receive_timeout_s;
  return l;
}
