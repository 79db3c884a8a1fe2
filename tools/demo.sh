#!/usr/bin/env bash
# The main job (tools/bootstrap.sh demo runs it after set-up):
#  1. build the host tools (optimised) and the STM32F405 firmware;
#  2. run the SIL scenarios: the firmware's FOC current loop on the simulated
#     motor, and the two plant-only runs; write CSV + JSON summaries;
#  3. turn each CSV into a PNG figure;
#  4. print what was built and made, and where.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
JOBS=$(nproc)
PY=${MC_PYTHON:-$ROOT/.venv/bin/python}
OUT=${MC_DEMO_OUT:-$ROOT/out/demo}
log() { printf '\033[1m[demo]\033[0m %s\n' "$*"; }

log "building host-release and stm32f405"
cmake --preset host-release >/dev/null
cmake --build --preset host-release -j "$JOBS" --target mcsim
cmake --preset stm32f405 >/dev/null
cmake --build --preset stm32f405 -j "$JOBS"

MCSIM=build/host-release/sim/cli/mcsim
mkdir -p "$OUT"
for s in foc-current-step pmsm-open-loop-step stepper-constant-voltage; do
  log "mcsim run $s"
  "$MCSIM" run "$s" --out "$OUT" >/dev/null
  "$PY" tools/plot/mcplot.py "$OUT/$s.csv" >/dev/null
done

log "CAN telemetry: the SIL drive streams its DBC-described frames; commands from a script"
mkdir -p "$OUT/can"
if tools/vm/mc_vm.sh native >/dev/null 2>&1; then
  log "  (this kernel has vcan; 'ctest -L can' also runs the live vcan0 test)"
fi
MCSIM_CAN_LOG="$OUT/can/can.log" MCSIM_CAN_CMDS=tools/can/demo_commands.log \
  "$MCSIM" run can-telemetry --out "$OUT/can" >/dev/null
"$PY" tools/can/mc_can.py stats "$OUT/can/can.log"
"$PY" tools/can/mc_can.py decode "$OUT/can/can.log" --out "$OUT/can/decoded" >/dev/null
"$PY" tools/can/mc_can.py plot "$OUT/can/decoded/CURRENTS.csv" >/dev/null

log "SIL benchmark (closed-loop FOC, 20 kHz PWM, 4 RK4 sub-steps, one core)"
"$MCSIM" bench | tee "$OUT/bench.json"

log "FOC current step (firmware in the loop), from $OUT/foc-current-step.json:"
"$PY" - "$OUT/foc-current-step.json" <<'PYEOF'
import json, sys
s = json.load(open(sys.argv[1]))
print(f"  designed 10-90% rise time  {s['rise_time_designed_s']*1e3:.3f} ms")
print(f"  measured  i_q rise time     {s['iq_rise_time_s']*1e3:.3f} ms  (x{s['iq_rise_time_ratio']:.2f})")
print(f"  measured  i_d rise time     {s['id_rise_time_s']*1e3:.3f} ms  (x{s['id_rise_time_ratio']:.2f})")
print(f"  final i_q / i_d             {s['iq_final_a']:.3f} A / {s['id_final_a']:.3f} A")
PYEOF

log "built:"
printf '  %s\n' "$ROOT/$MCSIM"
find build/stm32f405 -maxdepth 4 \( -name '*.a' -o -name '*.elf' \) -type f | sort | sed "s|^|  $ROOT/|"
log "Cortex-M4F libraries (arm-none-eabi-size, bytes):"
for a in build/stm32f405/firmware/kernels/libmc_kernels.a build/stm32f405/firmware/app/libmc_app.a; do
  printf '  %-40s %s bytes of code+data\n' "$(basename "$a")" \
    "$(arm-none-eabi-size -t "$a" | tail -1 | awk '{print $1 + $2}')"
done
log "results in $OUT:"
ls -1 "$OUT" | sed 's/^/  /'
