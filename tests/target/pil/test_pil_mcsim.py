#!/usr/bin/env python3
"""mcsim run --pil against mcsim run, file by file (issue 29 item 5).

    test_pil_mcsim.py --mcsim M --motor FILE --board B --duration S --work DIR \\
        SCENARIO [--set key=value ...] [--expect key=value ...]
    test_pil_mcsim.py ... --sim-s S ... SCENARIO --set BOUND=S

(--sim-s: a scenario that takes no --duration, bounded by one of its own
parameters, e.g. commission's t_max_s: S is only the cost line's simulated
time)

(--board motor: the motor file's own [board] table, e.g. the IPM's)

runs SCENARIO twice on the same motor and board, once on the SIL and once with
--pil (the board's whole image on QEMU), each into its own directory, and
requires the same exit code and the same files (the CSV, or the partial CSV of
a run whose verdict fails at this short duration, the JSON summary and, for
can-telemetry, the candump log of the CAN bus) equal byte for byte; a
difference prints the file and its first differing line. Both runs see the
same environment (can-telemetry's command script: MCSIM_CAN_CMDS). Each
--expect KEY=VALUE is a number the summary must hold exactly (what the run
did: commands refused, the stop's reason), so two runs that did nothing
alike do not pass.
With --flash-prep KEY=VALUE (repeatable): first one SIL run of SCENARIO
at its full length with --flash F and those --set only (e.g. cogging's
calibration, anticogging=1: the map SAVEd in F), which must pass and write F;
then both runs boot a copy of F each (--flash flash.bin in their directories,
the same text in both summaries), and each copy must still equal F after its
run (a run that boots the board's flash does not write it).
--expect KEY=nonzero asks for a finite non-zero number.
Prints the PIL cost as one JSON line ("[pil-cost] {...}"): wall seconds of the
PIL run per simulated second (QEMU's boot included, as a user pays it).

    test_pil_mcsim.py --mcsim M --motor FILE --self-test --work DIR

checks the comparison itself (a one-character change in a file is found and
its line printed) and --pil's refusals (a scenario that does not run the
drive application; a missing image, named; nothing written), without QEMU.
"""

import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import time


def first_difference(a_path, b_path):
    """None when the files are equal byte for byte, else a message naming the
    first differing line (1-based) and both versions of it."""
    with open(a_path, "rb") as f:
        a = f.read()
    with open(b_path, "rb") as f:
        b = f.read()
    if a == b:
        return None
    la, lb = a.split(b"\n"), b.split(b"\n")
    for i in range(max(len(la), len(lb))):
        x = la[i] if i < len(la) else b"<end of file>"
        y = lb[i] if i < len(lb) else b"<end of file>"
        if x != y:
            return "%s and %s differ first at line %d:\n  sil: %s\n  pil: %s" % (
                a_path,
                b_path,
                i + 1,
                x.decode(errors="replace"),
                y.decode(errors="replace"),
            )
    return "%s and %s differ (same lines, different bytes)" % (a_path, b_path)


def compare_dirs(sil_dir, pil_dir):
    """The list of differences between the two output directories."""
    errors = []
    names_s, names_p = sorted(os.listdir(sil_dir)), sorted(os.listdir(pil_dir))
    if names_s != names_p:
        errors.append("the runs wrote different files: sil %s, pil %s" % (names_s, names_p))
    for n in names_s:
        if n in names_p:
            d = first_difference(os.path.join(sil_dir, n), os.path.join(pil_dir, n))
            if d:
                errors.append(d)
    return errors


def run(cmd, env=None, cwd=None):
    t0 = time.monotonic()
    p = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=cwd)
    return p, time.monotonic() - t0


def fresh(path):
    shutil.rmtree(path, ignore_errors=True)
    return path


def board_args(a):
    """--board B for mcsim; none for --board motor (the motor file's own
    [board] table)."""
    return [] if a.board == "motor" else ["--board", a.board]


def same_run(a):
    base = [a.mcsim, "run", a.scenario, "--motor", a.motor] + board_args(a)
    if a.duration:
        base += ["--duration", repr(a.duration)]
    sim_s = a.duration or a.sim_s
    for kv in a.set or []:
        base += ["--set", kv]
    # Each run in its own working directory with the same relative --out, so
    # that paths a summary names (can-telemetry's can_log) are the same text.
    sil_cwd = fresh(os.path.join(a.work, "sil"))
    pil_cwd = fresh(os.path.join(a.work, "pil"))
    os.makedirs(sil_cwd)
    os.makedirs(pil_cwd)
    sil_dir, pil_dir = os.path.join(sil_cwd, "out"), os.path.join(pil_cwd, "out")
    errors = []
    flash = None
    if a.flash_prep:
        flash, prep_errors = prepare_flash(a)
        if prep_errors:
            return prep_errors
        for cwd in (sil_cwd, pil_cwd):
            shutil.copyfile(flash, os.path.join(cwd, "flash.bin"))
        base += ["--flash", "flash.bin"]
    ps, wall_s = run(base + ["--out", "out"], cwd=sil_cwd)
    pp, wall_p = run(base + ["--out", "out", "--pil"], cwd=pil_cwd)
    for tag, p in (("sil", ps), ("pil", pp)):
        print("[%s] exit %d\n%s%s" % (tag, p.returncode, p.stdout, p.stderr), end="")
    if flash:
        for tag, cwd in (("sil", sil_cwd), ("pil", pil_cwd)):
            if first_difference(flash, os.path.join(cwd, "flash.bin")):
                errors.append("the %s run wrote its copy of the flash file" % tag)
    # 0 (pass) or 1 (the verdict fails at this short duration): a run that
    # was refused (2) or crashed wrote nothing to compare.
    if ps.returncode not in (0, 1):
        errors.append("the SIL run exited %d" % ps.returncode)
    if pp.returncode != ps.returncode:
        errors.append("exit codes differ: sil %d, pil %d" % (ps.returncode, pp.returncode))
    if "target pil:" not in pp.stderr:
        errors.append("the --pil run did not name its target on stderr")
    if not errors:
        errors += compare_dirs(sil_dir, pil_dir)
    errors += expected(a, os.path.join(sil_dir, a.scenario + ".json"))
    print(
        "[pil-cost] "
        + json.dumps(
            {
                "benchmark": "pil_mcsim",
                "scenario": a.scenario,
                "set": a.set or [],
                "board": a.board,
                "motor": os.path.basename(a.motor),
                "duration_s": sim_s,
                "pil_wall_s": round(wall_p, 3),
                "sil_wall_s": round(wall_s, 3),
                "pil_wall_per_sim_s": round(wall_p / sim_s, 1),
            }
        )
    )
    return errors


def prepare_flash(a):
    """--flash-prep: the SIL run that writes the board's flash F (its full
    length: no --duration); F's path and the errors."""
    d = fresh(os.path.join(a.work, "prep"))
    os.makedirs(d)
    flash = os.path.join(d, "flash.bin")
    cmd = [a.mcsim, "run", a.scenario, "--motor", a.motor] + board_args(a) + ["--flash", flash]
    for kv in a.flash_prep:
        cmd += ["--set", kv]
    p, _ = run(cmd + ["--out", os.path.join(d, "out")])
    print("[prep] exit %d\n%s%s" % (p.returncode, p.stdout, p.stderr), end="")
    if p.returncode != 0:
        return flash, ["the SIL run that writes the flash exited %d" % p.returncode]
    if not os.path.exists(flash):
        return flash, ["the SIL run that writes the flash wrote no %s" % flash]
    return flash, []


def expected(a, summary_path):
    """The checks --expect KEY=VALUE asks of the summary (the runs being
    equal, the SIL's): what the run did, so that two equal runs that did
    nothing do not pass."""
    errors = []
    if not a.expect:
        return errors
    try:
        with open(summary_path) as f:
            s = json.load(f)
    except (OSError, ValueError) as e:
        return ["the summary %s cannot be read: %s" % (summary_path, e)]
    for kv in a.expect:
        key, _, want = kv.partition("=")
        if key not in s:
            errors.append("the summary has no %s" % key)
        elif want == "nonzero":
            if not (math.isfinite(float(s[key])) and float(s[key]) != 0.0):
                errors.append("%s = %r, expected a finite non-zero number" % (key, s[key]))
            else:
                print("[expect] %s = %r (non-zero)" % (key, s[key]))
        elif float(s[key]) != float(want):
            errors.append("%s = %r, expected %s" % (key, s[key], want))
        else:
            print("[expect] %s = %s" % (key, want))
    return errors


def self_test(a):
    errors = []
    d = fresh(os.path.join(a.work, "self"))
    os.makedirs(os.path.join(d, "a"))
    os.makedirs(os.path.join(d, "b"))
    rows = "t,x\n0,1.0\n1,2.0000000000000004\n2,3.0\n"
    for side, text in (("a", rows), ("b", rows.replace("2.0000000000000004", "2.0000000000000009"))):
        with open(os.path.join(d, side, "s.csv"), "w") as f:
            f.write(text)
    msg = first_difference(os.path.join(d, "a", "s.csv"), os.path.join(d, "b", "s.csv"))
    if not msg or "line 3" not in msg or "2.0000000000000009" not in msg:
        errors.append("a one-digit change was not reported at its line: %r" % msg)
    if compare_dirs(os.path.join(d, "a"), os.path.join(d, "a")):
        errors.append("a directory differs from itself")
    # A scenario that does not run the drive application refuses --pil.
    out = os.path.join(d, "refused")
    p, _ = run([a.mcsim, "run", "pmsm-open-loop-step", "--out", out, "--pil"])
    if p.returncode != 2 or "does not run the drive application" not in p.stderr or os.path.exists(out):
        errors.append("pmsm-open-loop-step --pil: exit %d, %r" % (p.returncode, p.stderr))
    # A missing image is named, and nothing is written.
    env = dict(os.environ, MCSIM_PIL_ELF=os.path.join(d, "no_such_image.elf"))
    p, _ = run(
        [
            a.mcsim,
            "run",
            "speed-step",
            "--motor",
            a.motor,
            "--board",
            "vesc6",
            "--duration",
            "0.01",
            "--out",
            out,
            "--pil",
        ],
        env,
    )
    if (
        p.returncode != 2
        or "no_such_image.elf" not in p.stderr
        or "MCSIM_PIL_ELF" not in p.stderr
        or os.path.exists(out)
    ):
        errors.append("a missing image: exit %d, %r" % (p.returncode, p.stderr))
    return errors


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mcsim", required=True)
    ap.add_argument("--motor", required=True)
    ap.add_argument("--board")
    ap.add_argument("--duration", type=float)
    ap.add_argument(
        "--sim-s",
        type=float,
        help="instead of --duration, for a scenario that takes none (its --set bounds the run): "
        "the simulated seconds of the run, for the cost line only",
    )
    ap.add_argument("--work", required=True)
    ap.add_argument("--set", action="append")
    ap.add_argument("--expect", action="append", help="KEY=VALUE the summary must hold (numbers, exact)")
    ap.add_argument(
        "--flash-prep",
        action="append",
        metavar="KEY=VALUE",
        help="first a SIL run with --flash F and these --set writes the board's flash F; both runs "
        "then boot a copy of F (see above)",
    )
    ap.add_argument("--self-test", action="store_true")
    ap.add_argument("scenario", nargs="?")
    a = ap.parse_args()
    if a.self_test:
        errors = self_test(a)
    else:
        if not (a.scenario and a.board and (a.duration or a.sim_s)):
            ap.error("SCENARIO, --board and --duration (or --sim-s) are required")
        errors = same_run(a)
    for e in errors:
        print("FAIL: " + e)
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
