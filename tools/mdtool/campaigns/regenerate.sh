#!/usr/bin/env bash
# Runs the shipped campaigns and the SIL benchmark and writes their reports
# into results/ (the files the README links; never typed by hand):
#   tools/mdtool/campaigns/regenerate.sh [all | campaigns | bench | NAME ...]
#   results/NAME/: summary.md, envelope.png, envelope.csv, results.parquet
#                  (+ histograms.png where the report asks for them)
#   results/bench-sil/: bench.json and bench.md (mdtool bench-sil)
# Scratch: $OUT (default out/campaigns). mdtool: this checkout's Release
# build (build/host-release/tests/sil/campaign/py, made by
# `cmake --preset host-release && cmake --build build/host-release --target
# mdtool_py mcsim`), else its Debug build (build/host, several times slower),
# else the venv's installed one; MDTOOL="command" (and MCSIM=path for the
# benchmark's subprocess runs) override.
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/../../.." && pwd)
cd "$ROOT"  # the copies of the results name the motor files relative to here
OUT=${OUT:-$ROOT/out/campaigns}
MCSIM=${MCSIM:-}
if [[ -n "${MDTOOL:-}" ]]; then
  read -r -a MD <<< "$MDTOOL"
else
  MD=("$ROOT/.venv/bin/mdtool")
  for b in build/host-release build/host; do
    if compgen -G "$ROOT/$b/tests/sil/campaign/py/mdtool/_sil*.so" > /dev/null; then
      MD=(env "PYTHONPATH=$ROOT/$b/tests/sil/campaign/py" "$ROOT/.venv/bin/python"
          -m mdtool.cli)
      [[ -z "$MCSIM" && -x "$ROOT/$b/sim/cli/mcsim" ]] && MCSIM=$ROOT/$b/sim/cli/mcsim
      break
    fi
  done
fi
echo "mdtool: ${MD[*]}${MCSIM:+; mcsim: $MCSIM}" >&2

report() { # name x y metric [report options...]
  local name=$1 x=$2 y=$3 metric=$4
  shift 4
  rm -rf "${OUT:?}/$name" "$HERE/results/$name"
  "${MD[@]}" sweep "$HERE/$name.toml" --out "$OUT/$name" | tail -1
  "${MD[@]}" report "$OUT/$name" --x "$x" --y "$y" ${metric:+--metric "$metric"} \
    --report-dir "$HERE/results/$name" --with-results "$@" > /dev/null
  echo "$HERE/results/$name"
}

sensorless_envelope() {
  report sensorless-envelope in.model_r_scale in.model_flux_scale ""
}
current_loop_rise() {
  report current-loop-rise in.motor.r_ohm in.board.pwm_hz out.iq_rise_time_ratio
}
commissioning_accuracy() {
  # Each identified quantity against its bound (issue 18), and the speed
  # error of the runs on the identified values (the bounds of
  # tests/sil/commission: 2 % sensored, 5 % sensorless).
  report commissioning-accuracy in.motor.pole_pairs in.motor.flux_wb pass_rate \
    --hist error.r_frac=0.02 --hist error.ld_frac=0.05 --hist error.lq_frac=0.05 \
    --hist error.flux_frac=0.03 --hist error.encoder_offset_deg=1 \
    --hist error.pole_pairs_diff=0.5 --hist error.adc_offset_max_frac=0.002 \
    --hist verify.sensored_speed_err_frac=0.02 --hist verify.sensorless_speed_err_frac=0.05 \
    --hist verify.sensored_faulted=0.5 --hist verify.sensorless_faulted=0.5
  # The sensorless start's known limit: did the sensorless run on the
  # identified values fault, over the rotor's start angle x pole pairs
  # (1 = some run of the cell faulted; blank: the law refused every motor
  # of the cell, e.g. salient ones).
  "${MD[@]}" report "$OUT/commissioning-accuracy" --x in.verify_sensorless_theta_e_rad \
    --y in.motor.pole_pairs --metric verify.sensorless_faulted \
    --report-dir "$HERE/results/commissioning-accuracy/sensorless-start" > /dev/null
}
bench() {
  mkdir -p "$HERE/results/bench-sil"
  "${MD[@]}" bench-sil ${MCSIM:+--mcsim "$MCSIM"} --json "$HERE/results/bench-sil/bench.json" \
    --md "$HERE/results/bench-sil/bench.md" > /dev/null
  echo "$HERE/results/bench-sil"
}

[[ $# -eq 0 ]] && set -- all
for what in "$@"; do
  case $what in
    all) sensorless_envelope; current_loop_rise; commissioning_accuracy; bench ;;
    campaigns) sensorless_envelope; current_loop_rise; commissioning_accuracy ;;
    bench) bench ;;
    sensorless-envelope) sensorless_envelope ;;
    current-loop-rise) current_loop_rise ;;
    commissioning-accuracy) commissioning_accuracy ;;
    *) echo "regenerate.sh: unknown '$what' (all, campaigns, bench or a campaign name)" >&2
       exit 2 ;;
  esac
done
