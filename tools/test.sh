#!/usr/bin/env bash
# The whole test suite (called by tools/bootstrap.sh test, after set-up):
#  1. host debug build: every test (unit, sil, can, lint, target);
#  2. host-asan build: the same minus lint, fuzz and campaign, under ASan + UBSan;
#  3. stm32f405 cross build with warnings as errors.
set -euo pipefail
cd "$(dirname "$0")/.."
JOBS=$(nproc)
log() { printf '\033[1m[test]\033[0m %s\n' "$*"; }

log "cross build: stm32f405"
cmake --preset stm32f405 >/dev/null
cmake --build --preset stm32f405 -j "$JOBS"

log "host-asan build and tests (ASan + UBSan)"
cmake --preset host-asan >/dev/null
cmake --build --preset host-asan -j "$JOBS"
ctest --preset host-asan -j "$JOBS"

log "host build and full suite"
cmake --preset host >/dev/null
cmake --build --preset host -j "$JOBS"
ctest --preset host -j "$JOBS"
