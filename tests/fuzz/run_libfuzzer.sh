#!/usr/bin/env bash
# run_libfuzzer.sh NAME BINARY CORPUS_DIR SECONDS [libFuzzer options...]
# Runs one built libFuzzer target for a bounded time and reports what it did
# as one machine-readable line:
#   [fuzz] {"target": NAME, "executions": N, "seconds": S, "exec_per_s": R, "corpus": C}
# Exit 0 only when libFuzzer exited 0 (no crash, leak, timeout or sanitizer
# report) AND it executed at least MC_FUZZ_MIN_EXECS inputs (default 1000):
# a target that links but never runs (0 executions) is a failure, not a pass.
# 1000 is far below what any target does here (tens of thousands per second
# on one core); it only catches "ran nothing", on however busy a machine.
set -uo pipefail
name=$1 bin=$2 corpus=$3 secs=$4; shift 4
min=${MC_FUZZ_MIN_EXECS:-1000}
out=$(mktemp)
"$bin" -max_total_time="$secs" -print_final_stats=1 -timeout=5 "$@" "$corpus" >"$out" 2>&1
rc=$?
tail -25 "$out"
execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$out" | tail -1)
rm -f "$out"
execs=${execs:-0}
ncorp=$(find "$corpus" -type f | wc -l)
rate=$(awk -v n="$execs" -v s="$secs" 'BEGIN { printf "%.0f", n / s }')
printf '[fuzz] {"target": "%s", "executions": %d, "seconds": %s, "exec_per_s": %s, "corpus": %d}\n' \
  "$name" "$execs" "$secs" "$rate" "$ncorp"
if [ "$rc" -ne 0 ]; then echo "[fuzz] $name: libFuzzer exited $rc" >&2; exit "$rc"; fi
if [ "$execs" -lt "$min" ]; then echo "[fuzz] $name: only $execs executions (< $min)" >&2; exit 1; fi
exit 0
