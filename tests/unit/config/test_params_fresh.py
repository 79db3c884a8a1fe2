#!/usr/bin/env python3
"""The parameter table is the single source of truth:
 1. `mc_params.py gen --root WORK` writes files byte-identical to the
    committed ones (C struct/defaults/range table, host metadata, docs table);
 2. the generator refuses a broken table (duplicate id, default out of
    range, unknown access) with exit code 2, so a bad edit cannot generate;
 3. the metadata's f32 ranges are float32-exact copies of the table.
"""
import argparse
import filecmp
import json
import os
import shutil
import subprocess
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
GEN = os.path.join(ROOT, "tools", "config", "mc_params.py")
sys.path.insert(0, os.path.dirname(GEN))
import mc_params  # noqa: E402

fails = []


def check(cond, what):
    if not cond:
        fails.append(what)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    shutil.rmtree(a.work, ignore_errors=True)
    os.makedirs(a.work)
    subprocess.run([sys.executable, GEN, "gen", "--root", a.work], check=True, capture_output=True)
    for rel in (mc_params.OUT_H, mc_params.OUT_C, mc_params.OUT_JSON, mc_params.OUT_MD):
        check(filecmp.cmp(os.path.join(a.work, rel), os.path.join(ROOT, rel), shallow=False),
              f"{rel} is stale: run tools/config/mc_params.py gen and commit")
    r = subprocess.run([sys.executable, GEN, "check"], capture_output=True, text=True)
    check(r.returncode == 0, f"mc_params.py check: {r.stderr}")

    with open(mc_params.TABLE) as f:
        text = f.read()
    bad = {
        "duplicate id": text.replace("id = 2\n", "id = 1\n", 1),
        "default out of range": text.replace("default = 0.675", "default = 1000.0", 1),
        "unknown access": text.replace('access = "stopped"', 'access = "sometimes"', 1),
    }
    for what, t in bad.items():
        p = os.path.join(a.work, "bad.toml")
        with open(p, "w") as f:
            f.write(t)
        r = subprocess.run([sys.executable, GEN, "table", "--table", p], capture_output=True, text=True)
        check(r.returncode == 2, f"{what}: generator exit {r.returncode}, want 2")

    with open(os.path.join(ROOT, mc_params.OUT_JSON)) as f:
        meta = json.load(f)
    table = mc_params.load()
    check(len(meta["params"]) == len(table["params"]), "metadata count")
    for m, p in zip(meta["params"], table["params"], strict=True):
        for k in ("min", "max", "default"):
            want = mc_params.f32(p[k]) if p["type"] == "f32" else p[k]
            check(m[k] == want, f"{p['name']}.{k}: metadata {m[k]}, table {want}")
    for f in fails:
        print("FAIL:", f)
    print(f"{len(table['params'])} parameters, {len(fails)} failures")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
