#!/usr/bin/env bash
# The whole test suite (called by tools/bootstrap.sh test, after set-up):
#  1. (none of its own: the STM32F405 images of every shipped board, the
#     example board, ODrive v3.6 56 V and 24 V, VESC 6: image and
#     bootloader, with their presets' settings, warnings as errors and their
#     size budgets, are built as part of step 2:
#     tests/target/CMakeLists.txt, mc_image_<board>);
#  2. the host-release preset built whole (every target): users build it
#     (demo, benchmarks), and its -O3 finds warnings (errors here) that -O0
#     does not;
#  3. host-asan build: the suite minus lint, fuzz, campaign, docs, the two
#     SocketCAN VM tests (the preset's filter: the SIL's CAN code runs under
#     ASan natively in the other can tests; ASan inside an emulated VM only
#     slows a wall-clock-paced test), can.mdtool_bus (Python alone) and
#     sil.mcsim_memory (ASan's quarantine and shadow memory make peak RSS a
#     measure of the sanitizer, not of the scenario), the --pil scenario
#     runs but speed-step (tests/README.md says why) and the tests labelled
#     nosan (no binary of the build runs: Python alone, or a benchmark image
#     under QEMU; their images are not in this build's `all`), under ASan +
#     UBSan, at -O0 (Debug) with the sanitizers' checks;
#  4. the whole suite (every label) on the host-release build of step 2. The
#     unsanitised -O0 build (`host`) is not built again: it would compile
#     every target a third time for no check the two above lack (no code of
#     the project uses assert(), so NDEBUG removes nothing), and the whole
#     suite must fit 30 minutes on 2 cores with another core busy
#     (lint.no_assert keeps it so).
set -euo pipefail
cd "$(dirname "$0")/.."
JOBS=$(nproc)
log() { printf '\033[1m[test]\033[0m %s\n' "$*"; }

log "host-release build (the optimised preset, whole)"
cmake --preset host-release >/dev/null
cmake --build --preset host-release -j "$JOBS"

log "host-asan build and tests (ASan + UBSan)"
cmake --preset host-asan >/dev/null
cmake --build --preset host-asan -j "$JOBS"
ctest --preset host-asan -j "$JOBS"

log "host-release: the full suite"
ctest --preset host-release -j "$JOBS"
