#!/usr/bin/env bash
# run_can_fuzz.sh <source-dir> <work-dir> <seconds>
# Builds the CAN command/unpacker libFuzzer target with clang-14 (ASan +
# UBSan, -ffp-contract=off like every build) and runs it for a bounded time
# on a working copy of the committed seed corpus (tests/can/fuzz/corpus).
# New inputs libFuzzer finds stay in <work-dir>/corpus (kept between runs of
# the same build tree); a crashing input is saved as crash-* there: add it
# to the seed corpus as a regression test. Exit 0 only without a crash,
# leak or sanitizer report.
set -euo pipefail
src=$(cd "$1" && pwd); mkdir -p "$2"; work=$(cd "$2" && pwd); secs=$3
CC=${MC_FUZZ_CC:-clang-14}; CXX=${MC_FUZZ_CXX:-clang++-14}
command -v "$CC" >/dev/null || { echo "$CC missing (Debian packages clang-14 libfuzzer-14-dev libclang-rt-14-dev)" >&2; exit 2; }
FLAGS=(-g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all -ffp-contract=off)
INC=(-I "$src/firmware/kernels" -I "$src/firmware/app" -I "$src/firmware/app/config" -I "$src/firmware/app/drive" -I "$src/firmware/app/ctrl" -I "$src/firmware/app/can" -I "$src/hal/include" -I "$src/hal/fake")
mkdir -p "$work/obj" "$work/corpus"
objs=()
while IFS= read -r f; do
  o="$work/obj/$(echo "${f#$src/}" | tr '/' '_').o"
  "$CC" "${FLAGS[@]/-fsanitize=fuzzer,/-fsanitize=fuzzer-no-link,}" -std=c11 "${INC[@]}" -c "$f" -o "$o"
  objs+=("$o")
done < <(find "$src/firmware/kernels" -name '*.c' | sort
         # the whole drive folder (a module added there links without a list
         # to keep), the CAN files the command decoder needs
         find "$src/firmware/app/drive" -name '*.c' | sort
         for f in can/mc_can_proto can/mc_can_dbc can/mc_telemetry can/mc_can_cmd; do echo "$src/firmware/app/$f.c"; done
         find "$src/firmware/app/config" -name '*.c' | sort
         find "$src/hal/fake" -name '*.c' | sort)
"$CXX" "${FLAGS[@]}" -std=c++17 "${INC[@]}" "$src/tests/can/fuzz/fuzz_can_cmd.cpp" "${objs[@]}" \
  -o "$work/fuzz_can_cmd"
cp -n "$src"/tests/can/fuzz/corpus/* "$work/corpus/" 2>/dev/null || true
exec "$src/tests/fuzz/run_libfuzzer.sh" can_cmd "$work/fuzz_can_cmd" "$work/corpus" "$secs" -max_len=600
