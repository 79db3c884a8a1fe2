// hal_host::FileFlash: the SIL board's flash (hal/flash.h), kept in a file so
// that a simulated drive keeps its configuration across runs (mcsim --flash).
//
// Sector map: two 16 KiB sectors, index 0 and 1, modelled on the STM32F405's
// sectors 1 and 2 (RM0090: 16 KiB each), the pair the configuration store
// uses (mc_cfg_store: A = 0, B = 1). The file is the raw image: exactly
// 32768 bytes, sector 0 then sector 1.
//
// NOR semantics as the HAL documents them: erase sets a sector to 0xFF;
// program ANDs each word into the image (bits only clear: programming a
// word that is not erased gives the AND of both, as on the F405, which does
// not refuse it); read copies.
//
// Persistence: every completed erase or program call writes the whole image
// to "<file>.tmp" and renames it over the file, so the file always holds the
// image after some completed operation: a killed mcsim never leaves a torn
// file. (A program call is persisted as a whole: a kill in the middle loses
// that call, one of the states the store survives.) A file that does not
// exist is an erased flash; it is created by the first erase or program.
//
// The constructor throws FileFlashError("<file>: <reason>") for a file of
// the wrong size, one that cannot be read, or a folder where the file
// and its temporary cannot be written; nothing is written then.
#ifndef HAL_HOST_FILE_FLASH_HPP
#define HAL_HOST_FILE_FLASH_HPP

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "hal/flash.h"

namespace hal_host {

struct FileFlashError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class FileFlash {
 public:
  static constexpr uint32_t kSectors = 2u;
  static constexpr uint32_t kSectorBytes = 16u * 1024u;
  static constexpr uint32_t kFileBytes = kSectors * kSectorBytes;

  explicit FileFlash(const std::string& path);
  FileFlash(const FileFlash&) = delete;
  FileFlash& operator=(const FileFlash&) = delete;

  const mc_hal_flash_t* hal() const { return &dev_; }
  const std::string& path() const { return path_; }
  // Whether the file existed when opened (false: an erased flash).
  bool existed() const { return existed_; }
  uint32_t erases() const { return erases_; }
  uint32_t programs() const { return programs_; }  // program calls
  uint32_t persist_errors() const { return persist_errors_; }

  int sector_size(uint32_t sector, uint32_t* p_bytes) const noexcept;
  int erase(uint32_t sector) noexcept;
  int program(uint32_t sector, uint32_t offset, const uint32_t* p_words, uint32_t n) noexcept;
  int read(uint32_t sector, uint32_t offset, void* p_buf, uint32_t len) const noexcept;

 private:
  bool persist() noexcept;

  std::string path_;
  std::vector<uint8_t> mem_;
  mc_hal_flash_t dev_{};
  bool existed_ = false;
  uint32_t erases_ = 0, programs_ = 0, persist_errors_ = 0;
};

}  // namespace hal_host

#endif  // HAL_HOST_FILE_FLASH_HPP
