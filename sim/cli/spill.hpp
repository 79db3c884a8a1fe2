// Rows of doubles spilled to an anonymous temporary file (std::tmpfile,
// removed when closed) and read back in order: a scenario that writes two
// runs side by side, or compares them sample by sample, keeps the first
// run's rows here instead of in memory, so its memory does not grow with
// the run's length (sim/README.md, "Memory").
#pragma once

#include <cstddef>
#include <cstdio>
#include <stdexcept>
#include <vector>

namespace mcsim {

class Spill {
 public:
  explicit Spill(size_t width) : width_(width), f_(std::tmpfile()) {
    if (f_ == nullptr) throw std::runtime_error("cannot create a temporary file for a trace");
  }
  ~Spill() { std::fclose(f_); }
  Spill(const Spill&) = delete;
  Spill& operator=(const Spill&) = delete;

  size_t width() const { return width_; }
  size_t rows() const { return rows_; }

  void put(const double* row) {
    if (std::fwrite(row, sizeof(double), width_, f_) != width_) {
      throw std::runtime_error("write error on a trace's temporary file");
    }
    ++rows_;
  }
  void put(const std::vector<double>& row) {
    if (row.size() != width_) throw std::logic_error("spill row width");
    put(row.data());
  }
  /// Reading starts at the first row.
  void rewind() {
    if (std::fflush(f_) != 0 || std::fseek(f_, 0, SEEK_SET) != 0) {
      throw std::runtime_error("cannot read back a trace's temporary file");
    }
  }
  /// The next row; false after the last.
  bool get(double* row) {
    const size_t n = std::fread(row, sizeof(double), width_, f_);
    if (n == width_) return true;
    if (n != 0 || std::ferror(f_))
      throw std::runtime_error("read error on a trace's temporary file");
    return false;
  }

 private:
  size_t width_;
  std::FILE* f_;
  size_t rows_ = 0;
};

}  // namespace mcsim
