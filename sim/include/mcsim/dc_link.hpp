// mcsim/dc_link.hpp: the DC link of a drive board: a supply (ideal source
// v_s behind an internal resistance r_s, optionally one-way: a diode, or a
// bench supply that cannot sink current), the bus capacitor C, and an
// optional brake resistor r_b switched by a chopper at duty d_b. The
// inverter draws i_inv (positive: power into the motor; negative while
// braking: the bridge pushes current into the bus).
//
//   C dv/dt = i_s - i_inv - d_b v / r_b,   i_s = (v_s - v) / r_s
//   one-way source: i_s = max(0, (v_s - v) / r_s)
//
// For a constant i_inv and d_b over a sub-step h the equation is linear in
// v, dv/dt = a - b v, and is integrated exactly: v(h) = v_inf + (v0 - v_inf)
// e^{-b h}, v_inf = a / b (b = 0: v0 + a h). The diode's state is decided at
// the start of each sub-step and re-checked at its end: a sub-step whose
// end voltage crosses v_s with the diode conducting is split at the crossing
// (exact: the crossing time is ln((v0 - v_inf)/(v_s - v_inf)) / b).
//
// The energies flowing in and out are accumulated exactly for the
// exponential solution (integrals of v and v^2 over the sub-step in closed
// form), so the balance
//   E_source = E_rs + E_brake + E_inverter + (C/2)(v^2 - v0^2)
// holds to rounding; a test checks it, and the regen-stop scenario checks
// the motor side (E_inverter against kinetic energy and losses) with it.
//
// Several loads (advance_loads): the inverters of several axes on the one
// capacitor and supply (issue 34 item 2: braking on one axis feeds the
// other), i_inv = sum_k i_inv_k; each load's energy integral v i_inv_k is
// kept apart (load_j(k)), so the balance reads
//   E_source = E_rs + E_brake + sum_k E_load_k + (C/2)(v^2 - v0^2).
//
// The supply's current: source_a() at the present voltage, and
// source_avg_a() the mean of i_s over the last advance (the charge the
// source delivered over it, in closed form like the energies; positive:
// drawn from the supply). It is the plant's i_bus_a of issue 33.
//
// Nothing here allocates; no firmware header (the plant is independent).
#ifndef MCSIM_DC_LINK_HPP
#define MCSIM_DC_LINK_HPP

#include <algorithm>
#include <cmath>

#include "mcsim/status.hpp"

namespace mcsim {

constexpr int kDcLinkMaxLoads = 4;

struct DcLinkParams {
  double source_v = 24.0;      // open-circuit supply voltage [V], > 0
  double source_r_ohm = 0.05;  // supply internal resistance [ohm], > 0
  bool source_sink = true;     // false: the supply cannot sink current (diode)
  double c_f = 1.0e-3;         // bus capacitance [F], > 0
  double brake_r_ohm = 0.0;    // brake resistor [ohm]; 0 = none
  // kOk or kNotFinite (a value not finite or out of range).
  Status validate() const {
    const bool ok = std::isfinite(source_v) && source_v > 0.0 && std::isfinite(source_r_ohm) &&
                    source_r_ohm > 0.0 && std::isfinite(c_f) && c_f > 0.0 &&
                    std::isfinite(brake_r_ohm) && brake_r_ohm >= 0.0;
    return ok ? Status::kOk : Status::kNotFinite;
  }
};

// Energies since configure() [J].
struct DcLinkEnergy {
  double source_j = 0;    // delivered by the ideal source v_s (integral v_s i_s)
  double source_r_j = 0;  // dissipated in r_s
  double brake_j = 0;     // dissipated in the brake resistor
  double inverter_j = 0;  // drawn by the inverter (integral v i_inv; < 0 when braking)
  double load_j[kDcLinkMaxLoads] = {0, 0, 0, 0};  // per load (advance_loads); [0] for advance()
  double source_c = 0;  // charge delivered by the source (integral i_s) [C]
};

class DcLink {
 public:
  Status configure(const DcLinkParams& p) {
    const Status s = p.validate();
    if (s != Status::kOk) return s;
    p_ = p;
    v_ = p.source_v;
    v0_ = v_;
    e_ = DcLinkEnergy{};
    source_avg_a_ = 0.0;
    return Status::kOk;
  }
  const DcLinkParams& params() const { return p_; }
  double v() const { return v_; }
  const DcLinkEnergy& energy() const { return e_; }
  // Energy stored in the capacitor above its initial value [J].
  double cap_delta_j() const { return 0.5 * p_.c_f * (v_ * v_ - v0_ * v0_); }
  // Source current at the present voltage [A].
  double source_a() const {
    const double i = (p_.source_v - v_) / p_.source_r_ohm;
    return (!p_.source_sink && i < 0.0) ? 0.0 : i;
  }
  // Mean source current over the last advance (0 before the first) [A].
  double source_avg_a() const { return source_avg_a_; }
  // Energy drawn by load k (< 0: fed back) since configure() [J]; 0 for k
  // outside [0, kDcLinkMaxLoads).
  double load_j(int k) const { return (k >= 0 && k < kDcLinkMaxLoads) ? e_.load_j[k] : 0.0; }

  // Advance by h_s with the inverter current i_inv_a and the brake duty
  // brake_duty (clamped to [0, 1]; ignored without a resistor) held
  // constant, in n equal sub-steps.
  void advance(double h_s, int n, double i_inv_a, double brake_duty) {
    (void)advance_loads(h_s, n, &i_inv_a, 1, brake_duty);  // one load: cannot fail
  }

  // Advance with n_loads inverters (i_inv_a[k], each held) on the link:
  // their currents add. kBadLoadCount (nothing changed) for n_loads outside
  // [1, kDcLinkMaxLoads] or a null pointer.
  Status advance_loads(double h_s, int n, const double* i_inv_a, int n_loads, double brake_duty) {
    if (i_inv_a == nullptr || n_loads < 1 || n_loads > kDcLinkMaxLoads) {
      return Status::kBadLoadCount;
    }
    double i_sum = i_inv_a[0];
    for (int k = 1; k < n_loads; ++k) i_sum += i_inv_a[k];
    const double q0 = e_.source_c;
    advance_total(h_s, n, i_sum, brake_duty, i_inv_a, n_loads);
    source_avg_a_ = (h_s > 0.0) ? (e_.source_c - q0) / h_s : 0.0;
    return Status::kOk;
  }

 private:
  void advance_total(double h_s, int n, double i_inv_a, double brake_duty, const double* loads,
                     int n_loads) {
    const double d = (p_.brake_r_ohm > 0.0) ? std::clamp(brake_duty, 0.0, 1.0) : 0.0;
    const double gb = (p_.brake_r_ohm > 0.0) ? d / p_.brake_r_ohm : 0.0;
    const double h = h_s / n;
    for (int k = 0; k < n; ++k) {
      double left = h;
      // The diode changes state at most once in a sub-step (twice with
      // rounding at the crossing); the third piece takes the rest.
      for (int pass = 0; pass < 3 && left > 0.0; ++pass) {
        const bool on =
            p_.source_sink || v_ < p_.source_v || (v_ == p_.source_v && i_inv_a + gb * v_ > 0.0);
        const double gs = on ? 1.0 / p_.source_r_ohm : 0.0;
        const double b = (gs + gb) / p_.c_f;
        const double a = (gs * p_.source_v - i_inv_a) / p_.c_f;
        double t = left;
        if (pass < 2 && !p_.source_sink) {
          const double vs = p_.source_v;
          if (b > 0.0) {
            const double vinf = a / b;
            if ((on && v_ < vs && vinf > vs) || (!on && v_ > vs && vinf < vs)) {
              t = std::min(left, std::log((v_ - vinf) / (vs - vinf)) / b);
            }
          } else if (!on && v_ > vs && a < 0.0) {
            t = std::min(left, (vs - v_) / a);
          }
        }
        sub(t, a, b, gs, gb, i_inv_a, loads, n_loads);
        if (t < left) v_ = p_.source_v;  // stopped at the crossing
        left -= t;
      }
    }
  }

  // One exact piece: v' = a - b v over t; energies from the integrals of v
  // and v^2 in closed form.
  void sub(double t, double a, double b, double gs, double gb, double i_inv, const double* loads,
           int n_loads) {
    if (!(t > 0.0)) return;
    const double v0 = v_;
    double v1, iv, iv2;  // v(t), int v, int v^2
    if (b * t < 1.0e-9) {
      v1 = v0 + (a - b * v0) * t;
      iv = 0.5 * (v0 + v1) * t;
      iv2 = (v0 * v0 + v0 * v1 + v1 * v1) / 3.0 * t;
    } else {
      const double vinf = a / b, e = std::exp(-b * t), c = v0 - vinf;
      v1 = vinf + c * e;
      const double i1 = (1.0 - e) / b, i2 = (1.0 - e * e) / (2.0 * b);
      iv = vinf * t + c * i1;
      iv2 = vinf * vinf * t + 2.0 * vinf * c * i1 + c * c * i2;
    }
    // i_s = gs (v_s - v): source power v_s i_s, resistor loss gs (v_s - v)^2.
    const double vs = p_.source_v;
    e_.source_j += gs * vs * (vs * t - iv);
    e_.source_r_j += gs * (vs * vs * t - 2.0 * vs * iv + iv2);
    e_.brake_j += gb * iv2;
    e_.inverter_j += i_inv * iv;
    for (int k = 0; k < n_loads; ++k) e_.load_j[k] += loads[k] * iv;
    e_.source_c += gs * (vs * t - iv);
    v_ = v1;
  }

  DcLinkParams p_{};
  double v_ = 24.0, v0_ = 24.0;
  double source_avg_a_ = 0.0;
  DcLinkEnergy e_{};
};

}  // namespace mcsim

#endif  // MCSIM_DC_LINK_HPP
