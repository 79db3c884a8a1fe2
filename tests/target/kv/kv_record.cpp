// Records the input vectors of the kernel families (kv.h) into a directory,
// one <family>.in per family:
//   foc         the FOC inputs the drive handed its current controller in
//               SIL runs of the foc-current-step scenario (FocSil, 0.03 s
//               at 20 kHz, without and with current-sensor noise), then
//               random operating points and the error cases (NaN current,
//               infinite angle, vbus <= 0) followed by normal records again;
//   the others  edge values (0, -0, +-pi, huge, denormal, NaN, inf; q31
//               extremes) and uniformly drawn operating points (fixed-seed
//               std::mt19937, the same file on every run).
// usage: kv_record <dir>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "foc_sil.hpp"

namespace {

using Words = std::vector<uint32_t>;

uint32_t fw(float v) {
  uint32_t b;
  std::memcpy(&b, &v, sizeof b);
  return b;
}
uint32_t qw(int32_t v) { return static_cast<uint32_t>(v); }

class Rng {
 public:
  explicit Rng(uint32_t seed) : g_(seed) {}
  float f(float lo, float hi) { return std::uniform_real_distribution<float>(lo, hi)(g_); }
  int32_t q() { return static_cast<int32_t>(g_()); }

 private:
  std::mt19937 g_;
};

const float kNan = std::numeric_limits<float>::quiet_NaN();
const float kInf = std::numeric_limits<float>::infinity();
const std::vector<float> kEdgesF = {0.0f, -0.0f, 3.14159265f, -3.14159265f, 1.5707963f,
                                    1.0e-40f, -1.0e-40f, 1.0e6f, -3.0e9f, 1.0e30f, kNan, kInf,
                                    -kInf, 1.0f, -1.0f};
const std::vector<int32_t> kEdgesQ = {0, 1, -1, INT32_MAX, INT32_MIN, INT32_MIN + 1,
                                      0x40000000, -0x40000000, 0x20000000, 12345};

Words math_f32() {
  Words w;
  for (float x : kEdgesF)
    for (float y : kEdgesF) w.insert(w.end(), {fw(x), fw(y)});
  Rng r(1);
  for (int i = 0; i < 4000; ++i) {
    const float x = r.f(-100.0f, 100.0f);
    const float y = r.f(-10.0f, 10.0f);
    w.insert(w.end(), {fw(x), fw(y)});
  }
  return w;
}

Words math_q31() {
  Words w;
  for (int32_t a : kEdgesQ)
    for (int32_t b : kEdgesQ) w.insert(w.end(), {qw(a), qw(b), fw(0.5f)});
  for (float x : kEdgesF) w.insert(w.end(), {qw(0), qw(1), fw(x)});
  Rng r(2);
  for (int i = 0; i < 4000; ++i) {
    const int32_t a = r.q();
    const int32_t b = r.q();
    w.insert(w.end(), {qw(a), qw(b), fw(r.f(-1.5f, 1.5f))});
  }
  return w;
}

Words transforms() {
  Words w;
  for (float x : kEdgesF) {
    w.insert(w.end(), {fw(x), fw(1.0f), fw(-1.0f), fw(x), qw(INT32_MAX), qw(INT32_MIN), qw(0),
                       qw(INT32_MIN)});
  }
  Rng r(3);
  for (int i = 0; i < 4000; ++i) {
    const float ia = r.f(-50.0f, 50.0f), ib = r.f(-50.0f, 50.0f), ic = r.f(-50.0f, 50.0f);
    const float th = r.f(-4.0f, 4.0f);
    const int32_t qa = r.q(), qb = r.q(), qc = r.q(), qt = r.q();
    w.insert(w.end(), {fw(ia), fw(ib), fw(ic), fw(th), qw(qa), qw(qb), qw(qc), qw(qt)});
  }
  return w;
}

Words svpwm() {
  Words w;
  for (float v : kEdgesF) {
    w.insert(w.end(), {fw(v), fw(10.0f), fw(24.0f), qw(INT32_MAX), qw(INT32_MIN), qw(0x40000000)});
    w.insert(w.end(), {fw(10.0f), fw(5.0f), fw(v), qw(1000), qw(-1000), qw(0)});
  }
  Rng r(4);
  for (int i = 0; i < 4000; ++i) {
    const float va = r.f(-300.0f, 300.0f), vb = r.f(-300.0f, 300.0f), vbus = r.f(10.0f, 400.0f);
    const int32_t qa = r.q(), qb = r.q();
    const int32_t qbus = static_cast<int32_t>(static_cast<uint32_t>(r.q()) >> 1);
    w.insert(w.end(), {fw(va), fw(vb), fw(vbus), qw(qa), qw(qb), qw(qbus)});
  }
  return w;
}

Words pi() {
  Words w;
  Rng r(5);
  for (int i = 0; i < 4000; ++i) {
    float lo = r.f(-15.0f, 0.0f), hi = r.f(0.0f, 15.0f);
    float e = r.f(-8.0f, 8.0f);
    if (i % 500 == 250) std::swap(lo, hi);  // refused dynamic limits
    if (i % 1000 == 700) e = kNan;          // refused error
    w.insert(w.end(), {fw(e), fw(r.f(-2.0f, 2.0f)), fw(lo), fw(hi), qw(r.q()), qw(r.q() >> 2)});
  }
  return w;
}

void foc_record(Words& w, float ia, float ib, float ic, bool three, float th, float om,
                float vbus, float idr, float iqr) {
  w.insert(w.end(), {fw(ia), fw(ib), fw(ic), three ? 1u : 0u, fw(th), fw(om), fw(vbus), fw(idr),
                     fw(iqr)});
}

// The FOC inputs of one SIL run of foc-current-step, as the drive formed them.
void foc_from_sil(Words& w, double noise_rms_a) {
  mcsim::FocSilOptions o;
  o.bw_rad_s = 2.0 * 3.14159265358979323846 * 200.0;
  o.J_kgm2 = 0.1;
  o.noise_rms_a = noise_rms_a;
  mcsim::FocSil sil(o);
  mc_drive_t& d = sil.drive();
  (void)mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT);
  const long n = std::lround(0.03 * o.pwm_hz);
  for (long k = 0; k < n; ++k) {
    const double t = sil.board().t_s();
    (void)mc_drive_set_current_ref(&d, (t >= 0.015) ? -1.0f : 0.0f, (t >= 0.002) ? 2.0f : 0.0f);
    sil.step();
    const mc_drive_telemetry_t& tm = d.tm;
    const float omega_e = tm.omega_m_rad_s * static_cast<float>(d.cfg.pole_pairs);
    foc_record(w, tm.ia_a, tm.ib_a, tm.ic_a, false, tm.theta_e_rad, omega_e, tm.vbus_v,
               tm.id_ref_a, tm.iq_ref_a);
  }
}

Words foc() {
  Words w;
  foc_from_sil(w, 0.0);
  foc_from_sil(w, 0.05);
  Rng r(6);
  for (int i = 0; i < 400; ++i) {
    foc_record(w, r.f(-5.0f, 5.0f), r.f(-5.0f, 5.0f), r.f(-5.0f, 5.0f), (i & 1) != 0,
               r.f(-7.0f, 7.0f), r.f(-1500.0f, 1500.0f), r.f(150.0f, 210.0f), r.f(-3.0f, 0.0f),
               r.f(-8.0f, 8.0f));
  }
  foc_record(w, kNan, 0.0f, 0.0f, false, 0.0f, 0.0f, 200.0f, 0.0f, 1.0f);
  foc_record(w, 1.0f, 0.0f, 0.0f, false, kInf, 0.0f, 200.0f, 0.0f, 1.0f);
  foc_record(w, 1.0f, 0.0f, 0.0f, false, 0.0f, 0.0f, 0.0f, 0.0f, 1.0f);
  foc_record(w, 1.0f, 0.0f, 0.0f, false, 0.0f, 0.0f, -5.0f, 0.0f, 1.0f);
  for (int i = 0; i < 20; ++i) {
    foc_record(w, 1.0f, -0.5f, -0.5f, false, 0.1f * i, 100.0f, 200.0f, 0.0f, 1.0f);
  }
  return w;
}

bool write(const std::string& dir, const char* family, const Words& w) {
  const std::string path = dir + "/" + family + ".in";
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return false;
  // Little-endian words: the host is x86-64, the target reads them as they are.
  const bool ok = std::fwrite(w.data(), sizeof(uint32_t), w.size(), f) == w.size();
  return (std::fclose(f) == 0) && ok;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: kv_record <dir>\n");
    return 2;
  }
  const std::string dir = argv[1];
  const bool ok = write(dir, "math_f32", math_f32()) && write(dir, "math_q31", math_q31()) &&
                  write(dir, "transforms", transforms()) && write(dir, "svpwm", svpwm()) &&
                  write(dir, "pi", pi()) && write(dir, "foc", foc());
  if (!ok) {
    std::fprintf(stderr, "kv_record: cannot write into %s\n", dir.c_str());
    return 1;
  }
  return 0;
}
