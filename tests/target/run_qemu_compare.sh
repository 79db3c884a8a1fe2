#!/usr/bin/env bash
# run_qemu_compare.sh <qemu-system-arm> <host-exe> <target-elf>
# Runs the host program and the M4F image (QEMU netduinoplus2, semihosting),
# and fails unless both exit 0 and print exactly the same lines.
set -uo pipefail
qemu=$1; host=$2; elf=$3
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
"$host" > "$tmp/host.txt"; hrc=$?
# Semihosting text goes to a chardev file, apart from QEMU's own messages.
timeout 60 "$qemu" -M netduinoplus2 -nographic -monitor none -serial null \
  -chardev file,id=sh0,path="$tmp/target.txt" \
  -semihosting-config enable=on,target=native,chardev=sh0 -kernel "$elf"; trc=$?
echo "host (exit $hrc):";   cat "$tmp/host.txt"
echo "target (exit $trc):"; cat "$tmp/target.txt"
[ "$hrc" -eq 0 ] || { echo "FAIL: host sweep exited $hrc"; exit 1; }
[ "$trc" -eq 0 ] || { echo "FAIL: target sweep exited $trc (QEMU or a fault)"; exit 1; }
[ -s "$tmp/host.txt" ] || { echo "FAIL: no output"; exit 1; }
if ! diff -u "$tmp/host.txt" "$tmp/target.txt"; then
  echo "FAIL: host and Cortex-M4F results differ"; exit 1
fi
echo "PASS: $(wc -l < "$tmp/host.txt") kernel sweeps bit-identical on host and Cortex-M4F"
