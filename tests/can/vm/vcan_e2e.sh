#!/usr/bin/env bash
# End-to-end test on a real SocketCAN interface (run natively where the
# kernel has vcan, otherwise inside tools/vm/mc_vm.sh's VM; needs
# CAP_NET_ADMIN to create the interface):
#   vcan_e2e.sh MCSIM WORKDIR PYTHON REPO
# The SIL drive (mcsim can-telemetry, paced to the wall clock) streams on
# vcan0 while `candump -L` and the logger (tools/can/mc_can.py record)
# record; `cansend` selects current mode, enables, sets i_q = 0.5 A then
# 1.0 A, sends a malformed SET_CURRENT_REF (3 bytes) and heartbeats, then
# falls silent. Leaves candump.log, logger.log and the SIL's CSV/JSON in
# WORKDIR/run for tests/can/check_can_run.py (run_vcan_test.sh runs it on
# the host: Python is slow in the emulated VM). The cansend arguments come
# from the DBC through `mc_can.py encode`, computed by the caller
# (MC_E2E_FRAMES="MODE ENABLE IQ05 IQ10"). Exit 0 when the recording
# worked.
set -u
MCSIM=$1 W=$2 PY=$3 ROOT=$4
IF=${MC_CAN_IFACE:-vcan0}
RUN=$W/run
rm -rf "$RUN" && mkdir -p "$RUN" && cd "$RUN" || exit 2
say() { echo "[vcan_e2e] $*"; }
pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done; }
trap cleanup EXIT

wait_for() { # seconds, test command...
  local n=$(( $1 * 10 )); shift
  while ! "$@"; do
    n=$((n - 1)); [ $n -gt 0 ] || return 1
    sleep 0.1
  done
}

if ! ip link show "$IF" >/dev/null 2>&1; then
  ip link add dev "$IF" type vcan || { say "cannot create $IF (no vcan, or no CAP_NET_ADMIN)"; exit 3; }
fi
ip link set up "$IF" || exit 3
say "kernel $(uname -r), interface $IF up"

# both receivers queue up to 16 MiB in the kernel (about 20,000 frames) so a
# receiver that is not scheduled for a while loses nothing (root: forced size)
# python-can imports asammdf when installed; asammdf's compiled module
# executes instructions QEMU's default CPU lacks (SIGILL): hide it here.
export PYTHONPATH=$ROOT/tests/can/vm/no_asammdf${PYTHONPATH:+:$PYTHONPATH}
candump -L -r 16777216 "$IF" > candump.log &
CD=$!; pids+=("$CD")
"$PY" "$ROOT/tools/can/mc_can.py" record --iface "$IF" --out logger.log --report logger.json --ready rec.ready > record.out 2>&1 &
REC=$!; pids+=("$REC")
wait_for 120 test -e rec.ready || { say "logger did not start"; cat record.out; exit 1; }

# 5 kHz PWM (at 2 kHz the 200 V ripple exceeds the 10 A limit: no safe gains), one RK4 step per period, slow loop (CAN) at 1 kHz: light
# enough to keep up with the wall clock under QEMU's instruction emulation.
# The run ends 0.3 s after the drive stopped (at most 30 s simulated).
MCSIM_CAN_IF=$IF "$MCSIM" run can-telemetry --out "$RUN" --duration 30 --set end_after_stop_s=0.3 \
  --set realtime=1 --set timeout_s=2.0 --set pwm_hz=5000 --set slow_loop_div=5 --set substeps=1 \
  --set bw_hz=20 --set speed_pll_bw_rad_s=500 > mcsim.out 2>&1 &
SIM=$!; pids+=("$SIM")
# the drive is up once its first heartbeat (id 0x021) is on the bus
wait_for 60 grep -q " 021#" candump.log || { say "no heartbeat from the SIL"; cat mcsim.out; exit 1; }
say "drive is streaming; sending commands"

read -r MODE ENABLE IQ05 IQ10 <<< "$MC_E2E_FRAMES"
BAD=032#0000E8   # SET_CURRENT_REF with 3 data bytes instead of 6
cansend "$IF" "$MODE"
cansend "$IF" "$ENABLE"
cansend "$IF" "$IQ05"
for i in 1 2 3 4 5; do
  cansend "$IF" "037#0$i"      # HOST_HEARTBEAT
  [ $i -eq 2 ] && cansend "$IF" "$IQ10"
  [ $i -eq 3 ] && cansend "$IF" "$BAD"
  sleep 0.2
done
say "heartbeats stopped; waiting for the SIL to finish"
wait "$SIM"; rc=$?
[ $rc -eq 0 ] || { say "mcsim failed ($rc)"; cat mcsim.out; exit 1; }
# Let both receivers drain what is still queued before they are told to stop:
# candump stops reading at once on SIGINT, so on a busy machine (it may be
# seconds behind in the emulated VM) its log would lose the tail. Wait until
# neither log has grown for 2 s (at most 60 s). The logger drains its socket
# after SIGTERM anyway.
size() { stat -c %s candump.log logger.log 2>/dev/null | tr '\n' ' '; }
prev=$(size); still=0
for _ in $(seq 1 120); do
  sleep 0.5
  now=$(size)
  if [ "$now" = "$prev" ]; then still=$((still + 1)); else still=0; prev=$now; fi
  [ $still -ge 4 ] && break
done
kill -INT "$CD"; kill -TERM "$REC"
wait "$CD" "$REC" 2>/dev/null
cat record.out
say "recorded: $(wc -l < candump.log) frames (candump), $(wc -l < logger.log) (logger)"
# the drop counter the logger reports counts real drops
"$PY" "$ROOT/tests/can/vm/drop_counter_check.py" "$IF" "$ROOT" || exit 1
