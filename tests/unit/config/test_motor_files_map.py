#!/usr/bin/env python3
"""The simulator's motor and board files map onto the drive's parameter table
(tools/config/params.toml): every numeric key of a [motor] or [board] table
in sim/motors/ is a parameter of the same name, and every value the library
uses is inside that parameter's range, so any library motor can be stored in
a drive as it is. Keys that are not drive parameters, each for a reason:
  name, source      text describing the file, not stored in the drive
  delay_periods     the simulated board's computation delay (a property of
                    the simulation, fixed by the firmware's timing on a MCU)
  description       a board file that names the image's board description
                    instead of holding values (tests/sil/boards checks it
                    reads what the image is built from)
  slots, cogging_*  the plant's cogging torque (sim/include/mcsim/cogging.hpp):
                    a property of the motor the drive does not store; the
                    drive measures its effect (the anticogging map), it is
                    not configured with it
A [stepper] table (a two-phase stepper for csmc-drive, issue 34 item 3) is
not checked: the drive has no stepper parameters yet (the image's half of
that item comes later), so none of its keys is stored in a drive.
Also checks that the check can fail: a file with an unknown key and one with
a value out of range are reported.
    test_motor_files_map.py --repo ROOT
"""
import argparse
import glob
import json
import os
import sys
import tomllib

NOT_PARAMS = {"name", "source", "delay_periods", "description", "slots"}
NOT_PARAM_PREFIXES = ("cogging_",)


def problems_of(path, params):
    with open(path, "rb") as f:
        doc = tomllib.load(f)
    out = []
    for table in ("motor", "board"):
        for key, value in doc.get(table, {}).items():
            if key in NOT_PARAMS or key.startswith(NOT_PARAM_PREFIXES):
                continue
            p = params.get(key)
            if p is None:
                out.append(f"{path}: [{table}] {key} has no parameter of that name")
                continue
            if not (p["min"] <= value <= p["max"]):
                out.append(f"{path}: [{table}] {key} = {value} outside the parameter's range "
                           f"[{p['min']}, {p['max']}]")
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repo", required=True)
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    with open(os.path.join(a.repo, "tools", "config", "params_meta.json")) as f:
        meta = json.load(f)
    params = {p["name"]: p for p in meta["params"]}
    files = sorted(glob.glob(os.path.join(a.repo, "sim", "motors", "*.toml")))
    fails = []
    if len(files) < 6:
        fails.append(f"only {len(files)} files in sim/motors")
    n = 0
    for f in files:
        fails += problems_of(f, params)
        n += 1
    # the check itself can fail
    os.makedirs(a.work, exist_ok=True)
    bad = os.path.join(a.work, "bad.toml")
    with open(bad, "w") as f:
        f.write('[motor]\nname = "x"\nr_ohm = 1e9\nfoo_h = 1.0\n')
    got = problems_of(bad, params)
    if len(got) != 2:
        fails.append(f"the check missed a bad file: {got}")
    for m in fails:
        print("FAIL:", m)
    print(f"{n} motor/board files map onto {len(params)} parameters")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
