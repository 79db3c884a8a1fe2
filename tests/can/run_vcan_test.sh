#!/usr/bin/env bash
# run_vcan_test.sh MCSIM WORKDIR PYTHON REPO
# The `can` end-to-end test on real SocketCAN. Natively when this kernel can
# create a vcan interface (and we may); otherwise in the small VM of
# tools/vm/mc_vm.sh (Debian kernel with can/vcan modules, host root over
# 9p). Never skips: a missing VM part is a failure naming the package.
set -euo pipefail
MCSIM=$(readlink -f "$1"); W=$(mkdir -p "$2" && cd "$2" && pwd); PY=$3; ROOT=$(cd "$4" && pwd)
E2E=$ROOT/tests/can/vm/vcan_e2e.sh
enc() { "$PY" "$ROOT/tools/can/mc_can.py" encode "$@"; }
FRAMES="$(enc SET_CONTROL_MODE control_mode=CURRENT) $(enc SET_ENABLE enable=1)"
FRAMES+=" $(enc SET_CURRENT_REF i_q_ref_a=0.5) $(enc SET_CURRENT_REF i_q_ref_a=1.0)"
if "$ROOT/tools/vm/mc_vm.sh" native 2>/dev/null; then
  echo "[can] this kernel has vcan: running natively"
  MC_E2E_FRAMES=$FRAMES bash "$E2E" "$MCSIM" "$W" "$PY" "$ROOT"
else
  echo "[can] no vcan on this kernel ($(uname -r)): running in the VM (tools/vm/mc_vm.sh)"
  case "$W" in *" "*) echo "work dir must not contain spaces" >&2; exit 2 ;; esac
  script=$W/vm_job.sh
  printf '#!/bin/sh\nMC_E2E_FRAMES=%q exec bash %q %q %q %q %q\n' "$FRAMES" "$E2E" "$MCSIM" "$W" "$PY" "$ROOT" > "$script"
  "$ROOT/tools/vm/mc_vm.sh" run "$script"
fi
cd "$W/run"
"$PY" "$ROOT/tools/can/mc_can.py" stats candump.log
exec "$PY" "$ROOT/tests/can/check_can_run.py" --csv can-telemetry.csv --json can-telemetry.json \
  --log candump.log --logger-log logger.log --logger-report logger.json
