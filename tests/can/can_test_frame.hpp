// A CAN frame for the host-side CAN tests (test_can_host, test_socketcand).
#ifndef TESTS_CAN_CAN_TEST_FRAME_HPP
#define TESTS_CAN_CAN_TEST_FRAME_HPP

#include <cstddef>
#include <cstdint>
#include <initializer_list>

#include "hal/can.h"

inline mc_hal_can_frame_t Fr(uint32_t id, std::initializer_list<uint8_t> b, uint8_t flags = 0) {
  mc_hal_can_frame_t f{};
  f.id = id;
  f.flags = flags;
  f.len = static_cast<uint8_t>(b.size());
  size_t i = 0;
  for (uint8_t x : b) f.data[i++] = x;
  return f;
}

#endif  // TESTS_CAN_CAN_TEST_FRAME_HPP
