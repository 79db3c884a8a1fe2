#!/usr/bin/env bash
# mdtool against the SIL firmware on a real SocketCAN interface (natively
# where the kernel has vcan, otherwise in tools/vm/mc_vm.sh's VM):
#   mdtool_vcan.sh MCSIM WORKDIR PYTHON REPO
# The SIL drive (mcsim can-telemetry, paced to the wall clock) on vcan0;
# candump -L and `mdtool record rec.blf` record (not .mf4 in the VM: asammdf's compiled
# dependencies use instructions the emulated CPU lacks; the host converts); then mdtool scan, status,
# config get (the SIL has no parameter service attached: the drive's
# refusal, CMD_ERROR UNSUPPORTED, must come back decoded, exit 4), monitor
# (headless, to a PNG) and run speed (the keep-alive sent by mdtool; held
# until the measured speed settles, counted in telemetry frames, so a slow
# emulated clock cannot fail it; the drive stops when it disables). Leaves every output and exit code in
# WORKDIR/run for tests/can/run_mdtool_vcan_test.sh to check on the host.
set -u
MCSIM=$1 W=$2 PY=$3 ROOT=$4
IF=${MC_CAN_IFACE:-vcan0}
RUN=$W/run
rm -rf "$RUN" && mkdir -p "$RUN" && cd "$RUN" || exit 2
say() { echo "[mdtool_vcan] $*"; }
pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done; }
trap cleanup EXIT
wait_for() { local n=$(( $1 * 10 )); shift; while ! "$@"; do n=$((n - 1)); [ $n -gt 0 ] || return 1; sleep 0.1; done; }
if ! ip link show "$IF" >/dev/null 2>&1; then
  ip link add dev "$IF" type vcan || { say "cannot create $IF"; exit 3; }
fi
ip link set up "$IF" || exit 3
# asammdf hidden (tests/can/vm/no_asammdf: its compiled deps SIGILL on the emulated CPU)
export PYTHONPATH=$ROOT/tests/can/vm/no_asammdf:$ROOT/tools/mdtool/src

candump -L -r 16777216 "$IF" > candump.log &
pids+=($!); CD=$!
"$PY" -m mdtool.cli record rec.blf --channel "$IF" --report rec.json --ready rec.ready > record.out 2>&1 &
REC=$!; pids+=("$REC")  # python itself (a shell function here would fork a subshell)
wait_for 120 test -e rec.ready || { say "recorder did not start"; cat record.out; exit 1; }
MCSIM_CAN_IF=$IF "$MCSIM" run can-telemetry --out "$RUN" --duration 900 --set end_after_stop_s=0.3 \
  --set realtime=1 --set timeout_s=2.0 --set pwm_hz=2000 --set slow_loop_div=2 --set substeps=1 \
  --set bw_hz=20 --set speed_pll_bw_rad_s=500 > mcsim.out 2>&1 &
SIM=$!; pids+=("$SIM")
wait_for 60 grep -q " 021#" candump.log || { say "no heartbeat from the SIL"; cat mcsim.out; exit 1; }
say "drive is streaming"
# every mdtool command in one Python process (tests/can/vm/mdtool_batch.py:
# the same entry point as the command line; one interpreter start instead of
# five, which the emulated CPU makes slow on a busy machine)
B="--interface socketcan --channel $IF"
cat > steps.txt <<EOS
scan scan $B --timeout 10
status status $B --timeout 10 --listen 3
config config get r_ohm $B --timeout 5
monitor monitor HEARTBEAT.mode CURRENTS.i_q_a $B --timeout 5 --no-gui --frames 10 --png monitor.png
run run speed 20 --duration 1 --settle 1.0 --settle-timeout 300 --keepalive 0.1 $B --timeout 5
EOS
"$PY" "$ROOT/tests/can/vm/mdtool_batch.py" steps.txt > batch.out 2>&1
say "run done ($(cat run.rc)); waiting for the SIL to end"
wait "$SIM"; echo $? > mcsim.rc
sleep 1
kill -INT "$CD"; kill -TERM "$REC"
wait "$CD" "$REC" 2>/dev/null
echo $? > record.rc
for f in scan status config monitor run record; do say "$f (exit $(cat $f.rc)): $(tail -c 600 $f.out)"; done
exit 0
