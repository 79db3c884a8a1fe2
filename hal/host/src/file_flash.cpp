#include "hal_host/file_flash.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <sys/stat.h>
#include <unistd.h>

namespace hal_host {
namespace {

FileFlash* self(void* ctx) {
  return static_cast<FileFlash*>(ctx);
}

int op_sector_size(void* ctx, uint32_t sector, uint32_t* p_bytes) {
  return self(ctx)->sector_size(sector, p_bytes);
}
int op_erase(void* ctx, uint32_t sector) {
  return self(ctx)->erase(sector);
}
int op_program(void* ctx, uint32_t sector, uint32_t offset, const uint32_t* p_words, uint32_t n) {
  return self(ctx)->program(sector, offset, p_words, n);
}
int op_read(void* ctx, uint32_t sector, uint32_t offset, void* p_buf, uint32_t len) {
  return self(ctx)->read(sector, offset, p_buf, len);
}

const mc_hal_flash_ops_t kOps = {op_sector_size, op_erase, op_program, op_read};

std::string folder_of(const std::string& path) {
  const auto slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  return slash == 0 ? "/" : path.substr(0, slash);
}

}  // namespace

FileFlash::FileFlash(const std::string& path) : path_(path), mem_(kFileBytes, 0xFFu) {
  auto fail = [&](const std::string& why) { throw FileFlashError(path + ": " + why); };
  if (path.empty()) throw FileFlashError("flash file: empty name");
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) {
    if (!S_ISREG(st.st_mode)) fail("not a regular file");
    if (static_cast<uint64_t>(st.st_size) != kFileBytes) {
      fail("size " + std::to_string(st.st_size) + " bytes, a flash image has " +
           std::to_string(kFileBytes) + " (two 16 KiB sectors)");
    }
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (f == nullptr) {
      fail(std::strerror(errno));
    } else {
      const size_t got = std::fread(mem_.data(), 1, mem_.size(), f);
      const bool err = std::ferror(f) != 0;
      (void)std::fclose(f);
      if (err || got != mem_.size()) fail("read error");
    }
    if (::access(path.c_str(), W_OK) != 0)
      fail(std::string("not writable: ") + std::strerror(errno));
    existed_ = true;
  } else if (errno != ENOENT) {
    fail(std::strerror(errno));
  }
  // The temporary goes next to the file (rename within one folder).
  const std::string dir = folder_of(path);
  if (::access(dir.c_str(), W_OK | X_OK) != 0) {
    fail("folder '" + dir + "' not writable: " + std::strerror(errno));
  }
  dev_.ops = &kOps;
  dev_.ctx = this;
}

int FileFlash::sector_size(uint32_t sector, uint32_t* p_bytes) const noexcept {
  if (sector >= kSectors || p_bytes == nullptr) return -EINVAL;
  *p_bytes = kSectorBytes;
  return 0;
}

int FileFlash::erase(uint32_t sector) noexcept {
  if (sector >= kSectors) return -EINVAL;
  std::memset(mem_.data() + static_cast<size_t>(sector) * kSectorBytes, 0xFF, kSectorBytes);
  ++erases_;
  return persist() ? 0 : -EIO;
}

int FileFlash::program(uint32_t sector, uint32_t offset, const uint32_t* p_words,
                       uint32_t n) noexcept {
  if (sector >= kSectors || p_words == nullptr || (offset % MC_HAL_FLASH_WORD_BYTES) != 0u ||
      offset > kSectorBytes || n > (kSectorBytes - offset) / MC_HAL_FLASH_WORD_BYTES) {
    return -EINVAL;
  }
  uint8_t* base = mem_.data() + static_cast<size_t>(sector) * kSectorBytes + offset;
  for (uint32_t i = 0; i < n; ++i) {
    uint32_t w;
    const size_t at = static_cast<size_t>(i) * MC_HAL_FLASH_WORD_BYTES;
    std::memcpy(&w, base + at, 4u);
    w &= p_words[i];  // NOR: bits only clear (host and MCU are little-endian)
    std::memcpy(base + at, &w, 4u);
  }
  ++programs_;
  return persist() ? 0 : -EIO;
}

int FileFlash::read(uint32_t sector, uint32_t offset, void* p_buf, uint32_t len) const noexcept {
  if (sector >= kSectors || p_buf == nullptr || offset > kSectorBytes ||
      len > kSectorBytes - offset) {
    return -EINVAL;
  }
  std::memcpy(p_buf, mem_.data() + static_cast<size_t>(sector) * kSectorBytes + offset, len);
  return 0;
}

bool FileFlash::persist() noexcept {
  const std::string tmp = path_ + ".tmp";
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  bool ok = f != nullptr;
  if (ok) {
    ok = std::fwrite(mem_.data(), 1, mem_.size(), f) == mem_.size();
    ok = (std::fclose(f) == 0) && ok;
    ok = ok && std::rename(tmp.c_str(), path_.c_str()) == 0;
    if (!ok) (void)std::remove(tmp.c_str());
  }
  if (!ok) ++persist_errors_;
  return ok;
}

}  // namespace hal_host
