#!/usr/bin/env bash
# run_fuzz.sh <target> <source-dir> <work-dir> <seconds>
# Builds a libFuzzer target with clang-14 (ASan + UBSan, -ffp-contract=off
# like every build here) and runs it for a bounded time on a working copy of
# the committed seed corpus (tests/fuzz/corpus/<target>). Exit 0 only if no
# crash, leak or sanitizer report and the target ran (tests/fuzz/run_libfuzzer.sh). A crashing input is saved as crash-* in
# the work dir: add it to the seed corpus as a regression test.
set -euo pipefail
target=$1; src=$(cd "$2" && pwd); mkdir -p "$3"; work=$(cd "$3" && pwd); secs=$4
CC=${MC_FUZZ_CC:-clang-14}; CXX=${MC_FUZZ_CXX:-clang++-14}
FLAGS=(-g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all -ffp-contract=off)
mkdir -p "$work/obj-$target" "$work/corpus-$target"
cd "$src"
case "$target" in
  mcsim_params)
    "$CXX" "${FLAGS[@]}" -std=c++17 -I sim/cli tests/fuzz/fuzz_mcsim_params.cpp sim/cli/scenario.cpp \
      -o "$work/fuzz_$target"
    ;;
  drive_api)
    objs=()
    while IFS= read -r f; do
      o="$work/obj-$target/$(echo "$f" | tr '/' '_').o"
      "$CC" "${FLAGS[@]/-fsanitize=fuzzer,/-fsanitize=fuzzer-no-link,}" -std=c11 \
        -I firmware/kernels -I firmware/app -I firmware/app/config -I firmware/app/drive -I firmware/app/ctrl -I firmware/app/can -I hal/include -I hal/fake -c "$f" -o "$o"
      objs+=("$o")
    # the whole drive folder, and the one file of config/ it links (the
    # anticogging map's CRC)
    done < <(find firmware/kernels -name '*.c' | sort; find firmware/app/drive -name '*.c' | sort
             echo firmware/app/config/mc_crc32.c; find hal/fake -name '*.c' | sort)
    "$CXX" "${FLAGS[@]}" -std=c++17 -I firmware/kernels -I firmware/app -I firmware/app/drive -I firmware/app/ctrl -I firmware/app/can -I hal/include -I hal/fake \
      tests/fuzz/fuzz_drive_api.cpp "${objs[@]}" -o "$work/fuzz_$target"
    ;;
  boot_update)
    inc=(-I firmware/boot -I firmware/app -I firmware/app/can -I firmware/app/config
         -I firmware/app/drive -I firmware/app/ctrl -I firmware/kernels -I hal/include -I hal/fake)
    objs=()
    for f in firmware/boot/mc_boot_image.c firmware/boot/mc_boot_update.c \
             firmware/app/can/mc_boot_proto.c firmware/app/config/mc_crc32.c hal/fake/mc_fake_flash.c; do
      o="$work/obj-$target/$(echo "$f" | tr '/' '_').o"
      "$CC" "${FLAGS[@]/-fsanitize=fuzzer,/-fsanitize=fuzzer-no-link,}" -std=c11 "${inc[@]}" -c "$f" -o "$o"
      objs+=("$o")
    done
    "$CXX" "${FLAGS[@]}" -std=c++17 "${inc[@]}" tests/fuzz/fuzz_boot_update.cpp "${objs[@]}" \
      -o "$work/fuzz_$target"
    ;;
  socketcand)
    "$CXX" "${FLAGS[@]}" -std=c++17 -I hal/host/include -I hal/include tests/fuzz/fuzz_socketcand.cpp \
      hal/host/src/socketcand_proto.cpp -o "$work/fuzz_$target"
    ;;
  *) echo "unknown fuzz target $target" >&2; exit 2 ;;
esac
cp -n tests/fuzz/corpus/"$target"/* "$work/corpus-$target/" 2>/dev/null || true
exec "$src/tests/fuzz/run_libfuzzer.sh" "$target" "$work/fuzz_$target" "$work/corpus-$target" "$secs"
