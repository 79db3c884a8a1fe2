#!/usr/bin/env bash
# run_mdtool_vcan_test.sh MCSIM WORKDIR PYTHON REPO
# mdtool against the SIL firmware on SocketCAN vcan0: natively when this
# kernel has vcan, otherwise in the VM of tools/vm/mc_vm.sh
# (tests/can/vm/mdtool_vcan.sh), then the checks on the host.
set -euo pipefail
MCSIM=$(readlink -f "$1"); W=$(mkdir -p "$2" && cd "$2" && pwd); PY=$3; ROOT=$(cd "$4" && pwd)
JOB=$ROOT/tests/can/vm/mdtool_vcan.sh
if "$ROOT/tools/vm/mc_vm.sh" native 2>/dev/null; then
  bash "$JOB" "$MCSIM" "$W" "$PY" "$ROOT"
else
  case "$W" in *" "*) echo "work dir must not contain spaces" >&2; exit 2 ;; esac
  script=$W/vm_job.sh
  printf '#!/bin/sh\nexec bash %q %q %q %q %q\n' "$JOB" "$MCSIM" "$W" "$PY" "$ROOT" > "$script"
  # the VM runs two SIL sessions (mdtool commands, then the parameter round
  # trip): more than the default 600 s on a loaded machine
  MC_VM_TIMEOUT=${MC_VM_TIMEOUT:-1100} "$ROOT/tools/vm/mc_vm.sh" run "$script"
fi
cd "$W/run"
exec "$PY" - "$ROOT" <<'PYEOF'
import json, os, sys
root = sys.argv[1]
sys.path.insert(0, os.path.join(root, "tools", "mdtool", "src"))
from mdtool.can import log
fails = []
def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        fails.append(what)
rc = {f: int(open(f + ".rc").read()) for f in ("scan", "status", "config", "monitor", "calibrate", "run", "mcsim")}
out = {f: open(f + ".out").read() for f in ("scan", "status", "config", "monitor", "calibrate", "run")}
check(rc["scan"] == 0 and "node 1: mode IDLE" in out["scan"], "scan finds node 1 (IDLE): " + out["scan"].strip())
check(rc["status"] == 0 and "mode IDLE" in out["status"] and "CURRENTS" in out["status"],
      "status: heartbeat and telemetry")
check(rc["config"] == 0 and out["config"].startswith("r_ohm") and "stopped" in out["config"],
      "config get: the SIL serves the parameter table, as the image: " + out["config"].strip())
check(rc["monitor"] == 0 and os.path.getsize("monitor.png") > 1000, "monitor --no-gui wrote monitor.png")
check(rc["calibrate"] == 0 and "DONE" in out["calibrate"] and "staged on the drive" in out["calibrate"],
      "calibrate: progress to DONE, results staged on the drive: " + out["calibrate"].strip()[-300:])
if rc["calibrate"] == 0:
    import tomllib
    cal = json.load(open("cal.json"))["results"]
    with open(os.path.join(root, "sim", "motors", "paper002-test-motor.toml"), "rb") as f:
        mot = tomllib.load(f)["motor"]
    # issue 18's bounds (R 2 %, flux 3 %, pole pairs exact), on the live bus
    check(abs(cal["r_ohm"] / mot["r_ohm"] - 1) < 0.02 and abs(cal["flux_wb"] / mot["flux_wb"] - 1) < 0.03
          and cal["pole_pairs"] == mot["pole_pairs"], f"calibrate's results: {cal}")
check(rc["run"] == 0 and "ran speed 20" in out["run"] and "settled: speed" in out["run"],
      "run speed 20 --settle 1.0: " + out["run"].strip()[-200:])
check(rc["mcsim"] == 0, "the SIL ended after the drive was disabled")
s = json.load(open("can-telemetry.json"))
check(s.get("final_stop_reason") == 2, f"the drive stopped on the disable command (stop_reason {s.get('final_stop_reason')})")
import csv
rows = list(csv.DictReader(open("can-telemetry.csv")))
w = [float(r["omega_m_true_rad_s"]) for r in rows]
# mdtool saw 3 SPEED frames in a row within 1.0 rad/s of 20 before it
# disabled; the true speed of the plant agrees within the encoder tracking
# loop's error (0.5 rad/s of slack on top of the band).
near = [x for x in w if abs(x - 20.0) <= 1.5]
check(len(near) > 0, f"the speed step reached 20 +- 1.5 rad/s (max {max(w):.2f})")
rec = json.load(open("rec.json"))
cd = [f for f in log.read_candump("candump.log")]
log.convert("rec.blf", "rec.mf4")  # asammdf on the host (see mdtool_vcan.sh)
mf = log.read_frames("rec.mf4")
check(rec["kernel_dropped"] == 0 and rec["seq_lost"] == 0, f"mdtool record: {rec}")
# the same frames, in the same order per identifier (two sockets may see a
# frame sent from this host interleaved differently with the others)
def per_id(fr):
    d = {}
    for f in fr:
        d.setdefault(f[2], []).append(f[3])
    return d
same = len(cd) == len(mf) and per_id(cd) == per_id(mf)
check(same, f"rec.blf (as rec.mf4) holds the frames candump saw ({len(mf)} vs {len(cd)})")
# parameters over CAN against the firmware (tests/can/vm/mdtool_vcan.sh)
rc = {f: int(open(f + ".rc").read()) for f in ("cfg_get1", "cfg_set", "cfg_get2", "cfg_node", "cfg_refuse",
                                                 "cfg_mcsim2")}
out = {f: open(f + ".out").read() for f in ("cfg_get1", "cfg_set", "cfg_get2", "cfg_node", "cfg_refuse")}
def value_of(text):
    return float(text.split()[1])
check(rc["cfg_get1"] == 0 and abs(value_of(out["cfg_get1"]) - 150.0) < 1e-3,
      "config get: the scenario's speed_max_rad_s (150): " + out["cfg_get1"].strip())
check(rc["cfg_set"] == 0 and "applied" in out["cfg_set"] and "saved (record 1)" in out["cfg_set"],
      "config set --save: staged, applied, saved: " + out["cfg_set"].strip().replace("\n", "; "))
# float32 of 123.5 is exact
check(rc["cfg_get2"] == 0 and value_of(out["cfg_get2"]) == 123.5,
      "config get after set: " + out["cfg_get2"].strip())
check(rc["cfg_node"] == 0 and "can_node_id: confirmed" in out["cfg_node"]
      and "can_node_id = 2 " in out["cfg_node"],
      "a new node id: WRITE answered NEEDS_CONFIRM, mdtool's CONFIRM staged it: "
      + out["cfg_node"].strip().replace("\n", "; "))
check(rc["cfg_refuse"] == 0 and "status RANGE" in out["cfg_refuse"] and "after: 123.5" in out["cfg_refuse"],
      "20000 rad/s (outside the table) refused RANGE by the drive, value kept: "
      + out["cfg_refuse"].strip().replace("\n", "; "))
s2 = json.load(open("cfg2/can-telemetry.json"))
from mdtool.can.params import ParamTable
pid = str(ParamTable().get("speed_max_rad_s")["id"])
check(rc["cfg_mcsim2"] == 0 and s2.get("cfg_boot_status") == "STORED"
      and pid in str(s2.get("cfg_from_store", "")).split(","),
      f"second boot on the saved flash: {s2.get('cfg_boot_status')}, from store {s2.get('cfg_from_store')}")
print("mdtool vcan checks: " + ("FAILED" if fails else "passed"))
sys.exit(1 if fails else 0)
PYEOF
