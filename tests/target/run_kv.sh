#!/usr/bin/env bash
# run_kv.sh <qemu-system-arm> <kv_host> <kv_m4f.elf> <family> <vector-dir>
# Runs one kernel family over its recorded input vectors on the host and on
# the emulated Cortex-M4F (QEMU netduinoplus2, files through semihosting) and
# fails unless both succeed and write bit-identical outputs.
set -uo pipefail
qemu=$1; host=$2; elf=$3; family=$4; dir=$5
in="$dir/$family.in"
[ -s "$in" ] || { echo "FAIL: no input vectors $in"; exit 1; }
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
"$host" run "$family" "$in" "$tmp/host.out"; hrc=$?
[ "$hrc" -eq 0 ] || { echo "FAIL: host run exited $hrc"; exit 1; }
timeout 60 "$qemu" -M netduinoplus2 -nographic -monitor none -serial null \
  -chardev file,id=sh0,path="$tmp/target.txt" \
  -semihosting-config "enable=on,target=native,chardev=sh0,arg=kv,arg=$family,arg=$in,arg=$tmp/target.out" \
  -kernel "$elf"; trc=$?
cat "$tmp/target.txt"
[ "$trc" -eq 0 ] || { echo "FAIL: target run exited $trc (QEMU, a fault or kv_run)"; exit 1; }
echo "input: $(($(stat -c %s "$in") / 4)) words"
"$host" compare "$family" "$tmp/host.out" "$tmp/target.out" || {
  echo "FAIL: host and Cortex-M4F outputs differ"; exit 1; }
