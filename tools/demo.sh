#!/usr/bin/env bash
# The main job (called by tools/bootstrap.sh demo, after set-up): build for
# host and target and report what was built and where.
set -euo pipefail
cd "$(dirname "$0")/.."
JOBS=$(nproc)
log() { printf '\033[1m[demo]\033[0m %s\n' "$*"; }

cmake --preset host-release >/dev/null
cmake --build --preset host-release -j "$JOBS"
cmake --preset stm32f405 >/dev/null
cmake --build --preset stm32f405 -j "$JOBS"

log "built:"
find build/host-release build/stm32f405 -maxdepth 4 \
  \( -name '*.a' -o -name '*.elf' -o -name 'mcsim' \) -type f | sort | sed 's/^/  /'
log "Cortex-M4F kernel library size (arm-none-eabi-size, bytes):"
arm-none-eabi-size -t build/stm32f405/firmware/kernels/libmc_kernels.a | tail -1 | sed 's/^/  /'
