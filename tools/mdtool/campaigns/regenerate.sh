#!/usr/bin/env bash
# Runs every shipped campaign and writes its report into results/NAME/
# (summary.md, envelope.png, envelope.csv), the files the README links:
#   tools/mdtool/campaigns/regenerate.sh [OUT]     (OUT: scratch, default out/campaigns)
# Needs the project's venv with mdtool (tools/bootstrap.sh setup).
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/../../.." && pwd)
MD=${MDTOOL:-$ROOT/.venv/bin/mdtool}
OUT=${1:-$ROOT/out/campaigns}
report() { # name x y [metric]
  local name=$1 x=$2 y=$3 metric=${4:-}
  rm -rf "$OUT/$name"
  "$MD" sweep "$HERE/$name.toml" --out "$OUT/$name" | tail -1
  "$MD" report "$OUT/$name" --x "$x" --y "$y" ${metric:+--metric "$metric"} \
    --report-dir "$HERE/results/$name" > /dev/null
  echo "$HERE/results/$name"
}
report sensorless-envelope in.model_r_scale in.model_flux_scale
report current-loop-rise in.motor.r_ohm in.board.pwm_hz out.iq_rise_time_ratio
