// Measured values of a test as GoogleTest properties, for the documents.
//
// mc_record("x3_max_err", e, 6e-4) records the value a test measured and the
// bound it asserts on it. With --gtest_output=json:FILE they appear in FILE
// as properties of the test; tools/docs/gen_docs.py runs the test that way
// and renders the documents' tables from them (value and bound), so a
// document never restates a number by hand. %.17g keeps every bit of a
// double, so a re-run can be compared exactly.
#pragma once

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

inline void mc_record(const std::string& key, double value) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", value);
  ::testing::Test::RecordProperty(key, buf);
}

inline void mc_record(const std::string& key, double value, double bound) {
  mc_record(key, value);
  mc_record(key + ".bound", bound);
}

// The same with the value's unit (text, `key.unit`). bound <= 0: a value
// the test shows but does not bound itself (no `key.bound`).
inline void mc_record(const std::string& key, double value, double bound, const std::string& unit) {
  if (bound > 0.0) {
    mc_record(key, value, bound);
  } else {
    mc_record(key, value);
  }
  ::testing::Test::RecordProperty(key + ".unit", unit);
}
