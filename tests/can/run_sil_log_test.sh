#!/usr/bin/env bash
# run_sil_log_test.sh MCSIM WORKDIR PYTHON REPO
# The telemetry/command path without a kernel CAN stack: the SIL drive
# writes its frames to a candump log (simulated time stamps) and replays
# the demo command script (tools/can/demo_commands.log); check_can_run.py
# checks the log against the SIL's CSV, including the timing of the safe
# stop; the logger decodes and plots the log.
set -euo pipefail
MCSIM=$1 W=$2 PY=$3 ROOT=$4
rm -rf "$W" && mkdir -p "$W" && cd "$W"
MCSIM_CAN_LOG=$W/can.log MCSIM_CAN_CMDS=$ROOT/tools/can/demo_commands.log \
  "$MCSIM" run can-telemetry --out "$W"
"$PY" "$ROOT/tools/can/mc_can.py" stats can.log --json stats.json
"$PY" "$ROOT/tools/can/mc_can.py" decode can.log --out decoded
"$PY" "$ROOT/tools/can/mc_can.py" plot decoded/CURRENTS.csv -o currents.png
test -s currents.png
"$PY" "$ROOT/tests/can/check_can_run.py" --csv can-telemetry.csv --json can-telemetry.json \
  --log can.log --timed --cmds "$ROOT/tools/can/demo_commands.log"
