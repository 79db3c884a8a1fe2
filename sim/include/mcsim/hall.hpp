// mcsim/hall.hpp: three digital Hall sensors on the stator, as a BLDC
// motor's commutation sensors (hub, e-bike and hoverboard motors; issue 32
// item 2). Independent of the firmware's decoder: the plant only says
// which sensors are high.
//
// Sensor k (A, B, C = 0, 1, 2) sits at the electrical angle
//   phi_k = offset_e_rad + k s,  s = 120 deg (the usual placement) or 60 deg
// and is high while the electrical angle th_e = p theta_m is in
//   [phi_k + e_rise_k, phi_k + pi + e_fall_k)   (mod 2 pi)
// where e_rise_k, e_fall_k are the edges' placement errors (mounting,
// sensor offset, magnet asymmetry: each edge its own, as a commissioning
// measures them). With 120 deg spacing the six 60-degree sectors from
// phi_A read A B C = 101, 100, 110, 010, 011, 001 (bits A = 1, B = 2, C = 4:
// 5, 1, 3, 2, 6, 4); 000 and 111 never occur on a healthy set. With 60 deg
// spacing: 100, 110, 111, 011, 001, 000 (1, 3, 7, 6, 4, 0): 010 and 101
// never occur.
//
// Hysteresis (a Hall switch's operate and release points): a sensor
// changes state only once th_e is inside the new region by half the band
// h: moving forward its edges are seen at edge + h/2, moving backward at
// edge - h/2. The sensor is sampled (sample() once per PWM period): the
// electrical angle may move less than (60 deg - h) between samples.
//
// Power-up (reset()): each sensor's state is that of its region without
// hysteresis. Faults (set_fault): all low (000: the sensors' supply lost),
// all high (111: the connector off, the inputs' pull-ups), one sensor stuck
// low or high (a broken wire or sensor); the output is the faulted one, the
// sensors keep tracking the angle underneath.
//
// Nothing here allocates; no firmware header.
#ifndef MCSIM_HALL_HPP
#define MCSIM_HALL_HPP

#include <cstdint>

#include "mcsim/status.hpp"

namespace mcsim {

enum class HallSpacing : int { k120 = 0, k60 = 1 };
enum class HallFault : int { kNone = 0, kAllLow, kAllHigh, kStuckLow, kStuckHigh };

struct HallParams {
  int pole_pairs = 1;  // th_e = pole_pairs theta_m, >= 1
  HallSpacing spacing = HallSpacing::k120;
  double offset_e_rad = 0.0;  // phi_A
  // Placement errors [rad electrical]: A rise, A fall, B rise, B fall,
  // C rise, C fall; each |e| + hysteresis/2 below 30 deg (edges keep order).
  double edge_error_e_rad[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  double hysteresis_e_rad = 0.0;  // full band, >= 0

  // kOk, kNotFinite, kBadPolePairs, kBadSensor (spacing not one of the two,
  // an edge error or the band too large).
  Status validate() const;
};

class HallSensors {
 public:
  // Validates p and powers up at theta_m = 0; on error keeps everything.
  Status configure(const HallParams& p);
  const HallParams& params() const { return p_; }
  // Power-up with the rotor at theta_m_rad: states without hysteresis,
  // no fault.
  void reset(double theta_m_rad);
  // The state (A bit 0, B bit 1, C bit 2) at theta_m_rad.
  std::uint8_t sample(double theta_m_rad);
  // kBadSensor (nothing changed) for a sensor outside 0..2 with a stuck fault.
  Status set_fault(HallFault f, int sensor = 0);
  HallFault fault() const { return fault_; }
  // Electrical angle of sensor k's rising (or falling) edge, placement
  // error included, hysteresis excluded, in [0, 2 pi).
  double edge_e_rad(int sensor, bool rising) const;

 private:
  // Whether th_e is inside sensor k's high region by more than margin from
  // both edges (margin >= 0), or inside its low region so (high = false).
  bool inside(int k, double th_e, bool high, double margin) const;
  HallParams p_{};
  bool state_[3] = {false, false, false};
  HallFault fault_ = HallFault::kNone;
  int fault_sensor_ = 0;
};

}  // namespace mcsim

#endif  // MCSIM_HALL_HPP
