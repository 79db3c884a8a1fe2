// 10-90 % rise time of a signal after a step, from consecutive samples
// (linear interpolation between them), in constant memory: the scenarios'
// current-step figure and the SIL tests that check a loop's rise against
// its design (ln 9 / bandwidth for a first-order loop).
#pragma once

#include <cmath>

namespace mcsim {

class RiseTimer {
 public:
  // The step at t0 takes y from y0 to target (either sign).
  RiseTimer(double t0, double y0, double target) : t0_(t0), y0_(y0), target_(target) {}
  void add(double t, double y) {
    if (t >= t0_ && have_) {
      cross(0.1, &t10_, t, y);
      cross(0.9, &t90_, t, y);
    }
    tp_ = t;
    yp_ = y;
    have_ = true;
  }
  // NaN while a level has not been crossed.
  double rise_s() const { return t90_ - t10_; }

 private:
  void cross(double frac, double* tc, double t, double y) const {
    if (!std::isnan(*tc)) return;
    const double lvl = y0_ + frac * (target_ - y0_);
    const double a = yp_ - lvl, b = y - lvl;
    if ((target_ > y0_ && a < 0 && b >= 0) || (target_ < y0_ && a > 0 && b <= 0)) {
      *tc = tp_ + (t - tp_) * a / (a - b);
    }
  }
  double t0_, y0_, target_;
  double tp_ = 0, yp_ = 0;
  bool have_ = false;
  double t10_ = std::nan(""), t90_ = std::nan("");
};

}  // namespace mcsim
