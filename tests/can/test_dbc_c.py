#!/usr/bin/env python3
"""The DBC is the single source of truth for the firmware's CAN codec.

 1. `mc_can.py gen-c` regenerates firmware/app/can/mc_can_dbc.{h,c} byte for byte
    (edit the DBC, regenerate, commit both: this test fails otherwise);
 2. the C tables (dumped by can_codec_tool) equal the DBC as cantools reads
    it: ids, lengths, directions, bit positions; scale, offset, min, max to
    float32 precision (the tables are float: 1e-7 relative);
 3. C-packed frames decode with cantools to the packed values within half a
    quantisation step (round to nearest) plus float32 rounding of the value;
 4. cantools-encoded frames unpack in C to cantools' decoded values within
    float32 rounding (1e-6 relative, 1e-9 absolute);
 5. random payloads: the C unpacker reports RANGE exactly when a cantools-
    decoded signal is outside the DBC range by more than half a step.
"""
import argparse
import filecmp
import os
import random
import subprocess
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "tools", "can"))
import mc_can  # noqa: E402

ERR_RANGE = 3
fails = []


def check(cond, what):
    if not cond:
        fails.append(what)


def run(codec, mode, lines):
    out = subprocess.run([codec, mode], input="\n".join(lines) + "\n", capture_output=True,
                         text=True, check=True).stdout
    return out.splitlines()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--codec", required=True)
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    rng = random.Random(11)

    # 1. regeneration changes nothing
    subprocess.run([sys.executable, os.path.join(ROOT, "tools", "can", "mc_can.py"), "gen-c",
                    "--out-dir", a.work], check=True, capture_output=True)
    for f in ("mc_can_dbc.h", "mc_can_dbc.c"):
        check(filecmp.cmp(os.path.join(a.work, f), os.path.join(ROOT, "firmware", "app", "can", f),
                          shallow=False),
              f"firmware/app/can/{f} differs from what tools/can/mc_can.py gen-c makes of the DBC")

    # 2. tables
    db = mc_can.load_db()
    msgs = sorted(db.messages, key=mc_can.cmd_of)
    lines = subprocess.run([a.codec, "table"], capture_output=True, text=True, check=True).stdout.splitlines()
    it = iter(lines)
    for idx, m in enumerate(msgs):
        mi, cmd, dlc, d, ns = map(int, next(it).split())
        check((mi, cmd, dlc, ns) == (idx, mc_can.cmd_of(m), m.length, len(m.signals)),
              f"{m.name}: C table {mi, cmd, dlc, ns}")
        check(d == (0 if m.senders == ["Drive"] else 1), f"{m.name}: direction {d}")
        for s in m.signals:
            f = next(it).split()
            check((int(f[0]), int(f[1]), int(f[2])) == (s.start, s.length, int(s.is_signed)),
                  f"{m.name}.{s.name}: bits {f[:3]}")
            for got, want, what in zip(map(float, f[3:]), (s.scale, s.offset, s.minimum, s.maximum),
                                       ("scale", "offset", "min", "max"), strict=True):
                check(abs(got - want) <= 1e-7 * max(1.0, abs(want)), f"{m.name}.{s.name}.{what}: {got} vs {want}")

    # 3. C pack -> cantools decode
    reqs, vals = [], []
    for idx, m in enumerate(msgs):
        for _ in range(300):
            v = []
            for s in m.signals:
                x = rng.uniform(s.minimum, s.maximum)
                v.append(round(x) if s.scale == 1 else x)
            reqs.append(f"{idx} 1 " + " ".join(repr(x) for x in v))
            vals.append((m, v))
    worst = 0.0
    for (m, v), out in zip(vals, run(a.codec, "pack", reqs), strict=True):
        fid, hexdata = out.split()[0], (out.split() + [""])[1]
        check(int(fid, 16) == m.frame_id, f"{m.name}: id {fid}")
        dec = db.decode_message(m.frame_id, bytes.fromhex(hexdata), decode_choices=False, scaling=True)
        for s, x in zip(m.signals, v, strict=True):
            tol = 0.5 * s.scale + 2.4e-7 * max(1.0, abs(x))
            err = abs(dec[s.name] - x)
            worst = max(worst, err / tol)
            check(err <= tol, f"{m.name}.{s.name}: packed {x}, cantools decodes {dec[s.name]}")
    print(f"C pack -> cantools decode: {len(reqs)} frames, worst error {worst:.3f} x tolerance")

    # 4. cantools encode -> C unpack
    reqs, exp = [], []
    for m in msgs:
        for _ in range(300):
            v = {s.name: (rng.randint(int(s.minimum), int(s.maximum)) if s.scale == 1
                          else rng.uniform(s.minimum, s.maximum)) for s in m.signals}
            data = m.encode(v, scaling=True, strict=False) if m.signals else b""
            reqs.append(f"{m.frame_id:03X} {data.hex()}")
            exp.append((m, db.decode_message(m.frame_id, data, decode_choices=False) if m.signals else {}))
    for (m, dec), out in zip(exp, run(a.codec, "unpack", reqs), strict=True):
        f = out.split()
        check(int(f[0]) == 0, f"{m.name}: C unpack error {f[0]} on a cantools frame")
        for s, x in zip(m.signals, map(float, f[2:]), strict=True):
            check(abs(x - dec[s.name]) <= 1e-6 * abs(dec[s.name]) + 1e-9 + 1.2e-7 * abs(s.offset),
                  f"{m.name}.{s.name}: C {x}, cantools {dec[s.name]}")
    print(f"cantools encode -> C unpack: {len(reqs)} frames agree")

    # 5. random payloads: RANGE iff out of range
    reqs, exp = [], []
    for m in msgs:
        if not m.signals:
            continue
        for _ in range(300):
            data = bytes(rng.getrandbits(8) for _ in range(m.length))
            dec = db.decode_message(m.frame_id, data, decode_choices=False)
            out_of = any(not (s.minimum - s.scale / 2 <= dec[s.name] <= s.maximum + s.scale / 2)
                         for s in m.signals)
            reqs.append(f"{m.frame_id:03X} {data.hex()}")
            exp.append((m, out_of, data))
    n_range = 0
    for (m, out_of, data), out in zip(exp, run(a.codec, "unpack", reqs), strict=True):
        e = int(out.split()[0])
        n_range += e == ERR_RANGE
        check((e == ERR_RANGE) == out_of and e in (0, ERR_RANGE),
              f"{m.name} {data.hex()}: C error {e}, cantools says out of range: {out_of}")
    print(f"random payloads: {n_range} of {len(reqs)} out of range, C and cantools agree")

    for f in fails[:30]:
        print("FAIL:", f)
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
