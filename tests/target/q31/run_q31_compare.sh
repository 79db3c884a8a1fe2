#!/usr/bin/env bash
# run_q31_compare.sh <qemu-system-arm> <machine> <host-exe> <target-elf>
# Runs the host sweep and the target image (QEMU <machine>, semihosting);
# fails unless both exit 0 and print exactly the same lines.
set -uo pipefail
qemu=$1; machine=$2; host=$3; elf=$4
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
"$host" > "$tmp/host.txt"; hrc=$?
timeout 120 "$qemu" -M "$machine" -nographic -monitor none -serial null \
  -chardev file,id=sh0,path="$tmp/target.txt" \
  -semihosting-config enable=on,target=native,chardev=sh0 -kernel "$elf"; trc=$?
echo "host (exit $hrc):";   cat "$tmp/host.txt"
echo "target $machine (exit $trc):"; cat "$tmp/target.txt"
[ "$hrc" -eq 0 ] || { echo "FAIL: host sweep exited $hrc"; exit 1; }
[ "$trc" -eq 0 ] || { echo "FAIL: target sweep exited $trc (QEMU or a fault)"; exit 1; }
[ -s "$tmp/host.txt" ] || { echo "FAIL: no output"; exit 1; }
if ! diff -u "$tmp/host.txt" "$tmp/target.txt"; then
  echo "FAIL: host and $machine results differ"; exit 1
fi
echo "PASS: $(wc -l < "$tmp/host.txt") q31 kernel sweeps bit-identical on host and $machine"
