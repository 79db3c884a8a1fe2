#!/usr/bin/env bash
# The main job (tools/bootstrap.sh demo runs it after set-up): what a user
# does on the bench with a new motor, on the simulated drive (the unmodified
# firmware in the loop with a simulated motor and board):
#  0. build mcsim (optimised) and the STM32F405 images of the three boards;
#  1. a motor file and a board file (MC_DEMO_MOTOR / MC_DEMO_BOARD, default
#     the ODrive D5065 on an ODrive v3.6 24 V): the drive knows only the board;
#  2. commissioning: the drive measures the current-sensor offsets, R, Ld,
#     Lq, pole pairs, encoder direction and offset, flux (mcsim run commission);
#  3. a sensored and a sensorless speed step with the drive's motor model
#     taken from what commissioning measured (R, L, flux as identified);
#  4. CAN: the drive streams its DBC-described telemetry while a command
#     script runs it; the host tool (mdtool) counts and decodes the log;
#  5. figures of each run, then where every result is and what it shows.
# Environment: MC_DEMO_OUT (default out/demo), MC_PYTHON (the venv's python).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
JOBS=$(nproc)
PY=${MC_PYTHON:-$ROOT/.venv/bin/python}
MDTOOL=("$PY" -m mdtool.cli)
OUT=${MC_DEMO_OUT:-$ROOT/out/demo}
MOTOR=${MC_DEMO_MOTOR:-sim/motors/odrive-d5065.toml}
BOARD=${MC_DEMO_BOARD:-sim/motors/odrive-v36-24v.toml}
log() { printf '\033[1m[demo]\033[0m %s\n' "$*"; }

log "0. building mcsim (host-release) and the STM32F405 images (example, ODrive v3.6, VESC 6)"
cmake --preset host-release >/dev/null
cmake --build --preset host-release -j "$JOBS" --target mcsim
for p in stm32f405 stm32f405-odrive36 stm32f405-vesc6; do
  cmake --preset "$p" >/dev/null
  cmake --build --preset "$p" -j "$JOBS" >/dev/null
done
MCSIM=$ROOT/build/host-release/sim/cli/mcsim
F=(--motor "$MOTOR" --board "$BOARD")
rm -rf "$OUT" && mkdir -p "$OUT"

log "1. your motor: $MOTOR on $BOARD"
"$MCSIM" describe speed-step "${F[@]}" > "$OUT/gains.txt"
echo "  the controller gains derived from the two files: $OUT/gains.txt"

log "2. commissioning (the drive measures the motor; nothing but the board is known)"
"$MCSIM" run commission "${F[@]}" --out "$OUT/1-commission" >/dev/null
# identified vs true, and the drive-model scales for the runs below
read -r R_SCALE L_SCALE FLUX_SCALE < <("$PY" - "$OUT/1-commission/commission.json" <<'PYEOF'
import json, sys
s = json.load(open(sys.argv[1]))
if s["fault"]:
    sys.exit(f"commissioning stopped: {s['fault']}")
i, t = s["identified"], s["true"]
rows = [("R", "r_ohm", "ohm", 1), ("Ld", "ld_h", "uH", 1e6), ("Lq", "lq_h", "uH", 1e6),
        ("flux", "flux_wb", "mWb", 1e3), ("pole pairs", "pole_pairs", "", 1),
        ("encoder offset", "encoder_offset_rad", "rad (el.)", 1),
        ("encoder direction", "encoder_direction", "", 1),
        ("ADC offset a", "adc_offset_a_a", "A", 1), ("ADC offset b", "adc_offset_b_a", "A", 1)]
print(f"  {'':18}{'identified':>14}{'true':>14}   unit", file=sys.stderr)
for name, k, unit, f in rows:
    print(f"  {name:18}{i[k] * f:14.6g}{t[k] * f:14.6g}   {unit}", file=sys.stderr)
print(f"  in {s['duration_s']:.2f} s simulated", file=sys.stderr)
if i["pole_pairs"] != t["pole_pairs"] or i["encoder_direction"] != t["encoder_direction"]:
    sys.exit("commissioning got the pole pairs or the encoder direction wrong: stopping")
l_scale = 0.5 * (i["ld_h"] / t["ld_h"] + i["lq_h"] / t["lq_h"])
print(f"{i['r_ohm'] / t['r_ohm']:.9g} {l_scale:.9g} {i['flux_wb'] / t['flux_wb']:.9g}")
PYEOF
)
MODEL=(--set "model_r_scale=$R_SCALE" --set "model_l_scale=$L_SCALE" --set "model_flux_scale=$FLUX_SCALE")
echo "  the drive's model below: R x$R_SCALE, L x$L_SCALE, flux x$FLUX_SCALE of the true motor's"

log "3. speed steps on the identified values"
"$MCSIM" run speed-step "${F[@]}" "${MODEL[@]}" --out "$OUT/2-speed-step" >/dev/null
"$MCSIM" run sensorless-speed-step "${F[@]}" "${MODEL[@]}" --out "$OUT/3-sensorless" >/dev/null
"$PY" tools/plot/mcplot.py "$OUT/2-speed-step/speed-step.csv" \
  --columns omega_m_rad_s,omega_ref_rad_s,i_q_a,i_q_ref_a,i_d_a >/dev/null
"$PY" tools/plot/mcplot.py "$OUT/3-sensorless/sensorless-speed-step.csv" \
  --columns omega_m_rad_s,omega_ref_rad_s,i_q_a,i_d_a >/dev/null
# The start-up plots the I-f frame's speed (omega_if_rad_s: the rotor follows
# it until the hand-over, NaN after), not omega_ref_rad_s, the speed command's
# ramp, which runs ahead of the I-f frame (issue 31: it read as a lost start).
"$PY" tools/plot/mcplot.py "$OUT/3-sensorless/sensorless-speed-step.csv" --tmax 0.12 \
  -o "$OUT/3-sensorless/start-up.png" --title "sensorless start-up: I-f, then the flux observer" \
  --columns omega_m_rad_s,omega_if_rad_s,theta_e_rad,theta_e_hat_rad >/dev/null
"$PY" - "$OUT" <<'PYEOF'
import json, sys
o = sys.argv[1]
s = json.load(open(f"{o}/2-speed-step/speed-step.json"))
print(f"  sensored:   0 -> {s['param.speed_rad_s']:g} rad/s, 2 % settling {s['settle_2pct_s'] * 1e3:.1f} ms, "
      f"final {s['omega_final_rad_s']:.3f} rad/s, faults {s['faults']}")
s = json.load(open(f"{o}/3-sensorless/sensorless-speed-step.json"))
print(f"  sensorless: I-f start, hand-over {s['handovers']}x, locked at {s['t_lock_s'] * 1e3:.1f} ms, "
      f"angle error rms {s['angle_err_rms_rad']:.3f} rad, final {s['omega_final_rad_s']:.3f} rad/s "
      f"after a load step to {s['load1_nm']:.3g} N.m, fallbacks {s['fallbacks']}, faults {s['faults']}")
PYEOF

log "4. CAN: the drive's telemetry while a command script runs it (tools/can/demo_commands.log)"
mkdir -p "$OUT/4-can"
if tools/vm/mc_vm.sh native >/dev/null 2>&1; then
  echo "  (this kernel has vcan: 'ctest -L can' also runs the drive live on vcan0 with mdtool)"
fi
MCSIM_CAN_LOG="$OUT/4-can/can.log" MCSIM_CAN_CMDS=tools/can/demo_commands.log \
  "$MCSIM" run can-telemetry --out "$OUT/4-can" >/dev/null
"${MDTOOL[@]}" stats "$OUT/4-can/can.log" --json "$OUT/4-can/stats.json" | sed 's/^/  /'
"${MDTOOL[@]}" decode "$OUT/4-can/can.log" --out "$OUT/4-can/decoded" >/dev/null
for m in CURRENTS SPEED; do
  "$PY" tools/plot/mcplot.py "$OUT/4-can/decoded/$m.csv" >/dev/null
done

log "SIL speed (closed-loop FOC, 20 kHz PWM, 4 RK4 sub-steps, one core)"
"$MCSIM" bench > "$OUT/bench.json"
"$PY" -c 'import json, sys; print("  %.0fx real time" % json.load(open(sys.argv[1]))["rtf"])' "$OUT/bench.json"

log "5. where everything is ($OUT):"
cat <<EOF
  gains.txt                         the controller gains derived from the motor and board files
  1-commission/commission.json      identified vs true: R, Ld, Lq, flux, pole pairs, encoder, ADC offsets
  2-speed-step/speed-step.png       sensored speed step on the identified model: speed, i_q, i_d
  3-sensorless/sensorless-speed-step.png
                                    I-f start, hand-over to the flux observer, load step: speed, currents
  3-sensorless/start-up.png         the first 120 ms: true vs estimated electrical angle
  4-can/can.log                     the telemetry as candump -L would log it (open it in SavvyCAN,
                                    cantools or 'mdtool decode' with tools/can/motordrive.dbc)
  4-can/decoded/*.csv, *.png        one CSV per message (units in the column names), CURRENTS and SPEED plotted
  4-can/stats.json                  frames per message, rates, sequence gaps (lost frames), bus load
  bench.json                        SIL speed, real-time factor
  the MCU images:
EOF
find build/stm32f405 build/stm32f405-odrive36 build/stm32f405-vesc6 -maxdepth 5 -name 'mc_stm32f405*.elf' \
  -type f | sort | sed "s|^|    $ROOT/|"
echo "  next: your motor (README 'Your motor'), the CAN tool (tools/mdtool/README.md), the boards"
echo "  (firmware/targets/stm32f405/README.md)."
