#!/usr/bin/env bash
# The whole test suite (called by tools/bootstrap.sh test, after set-up):
#  1. host debug build: every test (unit, sil, can, lint, target);
#  2. host-asan build: the same minus lint, fuzz, campaign, docs, the two
#     SocketCAN VM tests (the preset's filter: the SIL's CAN code runs under
#     ASan natively in the other can tests; ASan inside an emulated VM only
#     slows a wall-clock-paced test), can.mdtool_bus (Python alone) and
#     sil.mcsim_memory (ASan's quarantine and shadow memory make peak RSS a
#     measure of the sanitizer, not of the scenario), under ASan + UBSan;
#  3. the STM32F405 images (example board, ODrive v3.6, VESC 6) with warnings
#     as errors and their size budgets;
#  4. the host-release preset built whole (every target; its tests are the
#     debug build's): users build it, and its -O3 finds warnings (errors
#     here) that the debug build's -O0 does not.
set -euo pipefail
cd "$(dirname "$0")/.."
JOBS=$(nproc)
log() { printf '\033[1m[test]\033[0m %s\n' "$*"; }

for p in stm32f405 stm32f405-odrive36 stm32f405-vesc6; do
  log "cross build: $p"
  cmake --preset "$p" >/dev/null
  cmake --build --preset "$p" -j "$JOBS"
done

log "host-release build (the optimised preset, whole)"
cmake --preset host-release >/dev/null
cmake --build --preset host-release -j "$JOBS"

log "host-asan build and tests (ASan + UBSan)"
cmake --preset host-asan >/dev/null
cmake --build --preset host-asan -j "$JOBS"
ctest --preset host-asan -j "$JOBS"

log "host build and full suite"
cmake --preset host >/dev/null
cmake --build --preset host -j "$JOBS"
ctest --preset host -j "$JOBS"
