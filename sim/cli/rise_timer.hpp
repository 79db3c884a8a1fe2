// 10-90 % rise time of a signal after a step, from consecutive samples
// (linear interpolation between them), in constant memory: the scenarios'
// current-step figure and the SIL tests that check a loop's rise against
// its design (ln 9 / bandwidth for a first-order loop). StepResponse adds
// the overshoot and the settling time over a window.
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

// A step's response over [t0, t_end): the 10-90 % rise, the overshoot past
// the target (a fraction of the step, 0 when it never passes it) and the
// settling time (from t0 to the last sample outside target +- band; 0 when
// none is), in constant memory.
class StepResponse {
 public:
  StepResponse(double t0, double t_end, double y0, double target, double band)
      : rise_(t0, y0, target), t0_(t0), t_end_(t_end), y0_(y0), target_(target), band_(band) {}
  void add(double t, double y) {
    if (t >= t_end_) return;
    rise_.add(t, y);
    if (t < t0_) return;
    const double past = (target_ >= y0_) ? y - target_ : target_ - y;
    if (past > peak_past_) peak_past_ = past;
    if (std::abs(y - target_) > band_) t_out_ = t;
  }
  double rise_s() const { return rise_.rise_s(); }
  double overshoot_frac() const {
    const double step = std::abs(target_ - y0_);
    return step > 0.0 ? peak_past_ / step : 0.0;
  }
  double settle_s() const { return std::isnan(t_out_) ? 0.0 : t_out_ - t0_; }

 private:
  RiseTimer rise_;
  double t0_, t_end_, y0_, target_, band_;
  double peak_past_ = 0.0;
  double t_out_ = std::nan("");
};

}  // namespace mcsim
