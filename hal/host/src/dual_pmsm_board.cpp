// See dual_pmsm_board.hpp.
#include "hal_host/dual_pmsm_board.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "mcsim/status.hpp"

namespace hal_host {

namespace {

bool same_link(const mcsim::DcLinkParams& a, const mcsim::DcLinkParams& b) {
  return a.source_v == b.source_v && a.source_r_ohm == b.source_r_ohm &&
         a.source_sink == b.source_sink && a.c_f == b.c_f && a.brake_r_ohm == b.brake_r_ohm;
}

std::unique_ptr<PmsmBoard> make_axis(const PmsmBoardConfig& cfg, int k) {
  PmsmBoardConfig c = cfg;
  c.dc_link_shared = true;
  try {
    return std::make_unique<PmsmBoard>(c);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("axis M" + std::to_string(k) + ": " + e.what());
  }
}

}  // namespace

DualPmsmBoard::DualPmsmBoard(const PmsmBoardConfig& m0, const PmsmBoardConfig& m1) {
  if (!m0.dc_link_enabled || !m1.dc_link_enabled) {
    throw std::invalid_argument(
        "a two-axis board needs the DC link on both axes (dc_link_enabled): they share it");
  }
  if (!same_link(m0.dc_link, m1.dc_link)) {
    throw std::invalid_argument(
        "the two axes' DC-link values differ: one board has one capacitor and one supply");
  }
  if (m0.inverter.t_pwm_s != m1.inverter.t_pwm_s || m0.substeps != m1.substeps) {
    throw std::invalid_argument(
        "the two axes' PWM periods or sub-steps differ: both fast steps run once per period");
  }
  ax_[0] = make_axis(m0, 0);
  ax_[1] = make_axis(m1, 1);
  check_config(link_.configure(m0.dc_link), "dc_link");
  substeps_ = m0.substeps;
  for (auto& a : ax_) a->bind_shared_link(&link_);
}

PmsmBoard& DualPmsmBoard::axis(int k) {
  if (k < 0 || k >= kAxes) throw std::out_of_range("axis index must be 0 or 1");
  return *ax_[k];
}

const PmsmBoard& DualPmsmBoard::axis(int k) const {
  if (k < 0 || k >= kAxes) throw std::out_of_range("axis index must be 0 or 1");
  return *ax_[k];
}

void DualPmsmBoard::sample() {
  for (auto& a : ax_) a->sample();
}

void DualPmsmBoard::advance() {
  double i_inv[kAxes];
  brake_duty_ = 0.0;
  for (int k = 0; k < kAxes; ++k) {
    ax_[k]->advance();
    i_inv[k] = ax_[k]->inverter_a();
    brake_duty_ = std::max(brake_duty_, ax_[k]->brake_duty());
  }
  check_config(link_.advance_loads(ax_[0]->period_s(), substeps_, i_inv, kAxes, brake_duty_),
               "dc_link loads");
  for (auto& a : ax_) a->set_vbus_v(link_.v());
}

}  // namespace hal_host
