#!/usr/bin/env python3
"""The PIL cost: wall seconds per simulated second of `mcsim run --pil`.

    run_pil_cost.py --mcsim PATH [--motor FILE] [--board NAME ...]
                    [--scenario NAME ...] [--durations D1,D2] [--out FILE]

For each board and scenario, runs the scenario on the board's whole image
under QEMU (`mcsim run SCENARIO --motor M --board B --pil`) for two simulated
durations D1 < D2, and on the SIL for D2, each `--repeats` times (the least
wall time kept). The cost of a simulated second
is the slope (wall(D2) - wall(D1)) / (D2 - D1): QEMU's start and the image's
boot (paid once per run) fall out of it and are reported apart as the
intercept, `pil_start_s`. Prints one JSON object (and writes it to --out):

    {"benchmark": "pil_cost", "machine": {...}, "runs": [
       {"board", "scenario", "motor", "durations_s", "pil_wall_s", "sil_wall_s",
        "pil_wall_per_sim_s", "pil_start_s", "sil_wall_per_sim_s", "pil_over_sil"}]}

Wall time depends on the machine and on what else runs on it: `machine`
records the processor count and the 1-minute load average at the start and
the end, and nothing asserts a figure (the test `pil.cost_bench` checks the
report's form on short runs). A run that fails (exit other than 0 or 1: 1 is
a verdict that fails at a short duration, still a run) stops the benchmark
with exit 2, its error printed.
"""

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
BOARDS = ["odrive36", "vesc6"]  # the boards of the pil.mcsim tests
SCENARIOS = ["current-step", "speed-step"]


class BenchError(Exception):
    pass


def timed_run(cmd):
    """Wall seconds of one mcsim run (0: pass, 1: its verdict failed)."""
    t0 = time.monotonic()
    p = subprocess.run(cmd, capture_output=True, text=True, check=False)
    wall = time.monotonic() - t0
    if p.returncode not in (0, 1):
        raise BenchError(f"{' '.join(cmd)} exited {p.returncode}:\n{p.stderr[-2000:]}")
    return wall


def measure(mcsim, motor, board, scenario, durations, repeats, work):
    """Each wall time the least of `repeats` runs: the one other processes
    disturbed least."""
    d1, d2 = durations
    base = [mcsim, "run", scenario, "--motor", motor, "--board", board]
    walls = []
    for i, d in enumerate((d1, d2)):
        walls.append(min(
            timed_run(base + ["--duration", repr(d), "--out",
                              os.path.join(work, f"{board}_{scenario}_pil{i}_{k}"), "--pil"])
            for k in range(repeats)))
    sil = min(timed_run(base + ["--duration", repr(d2), "--out",
                                os.path.join(work, f"{board}_{scenario}_sil{k}")])
              for k in range(repeats))
    slope = (walls[1] - walls[0]) / (d2 - d1)
    return {
        "board": board,
        "scenario": scenario,
        "motor": os.path.relpath(motor, ROOT) if motor.startswith(ROOT) else motor,
        "durations_s": [d1, d2],
        "pil_wall_s": [round(w, 3) for w in walls],
        "sil_wall_s": round(sil, 3),
        "pil_wall_per_sim_s": round(slope, 1),
        "pil_start_s": round(walls[0] - slope * d1, 2),
        "sil_wall_per_sim_s": round(sil / d2, 2),
        "pil_over_sil": round(walls[1] / sil, 1) if sil > 0 else None,
    }


def durations_arg(text):
    try:
        d = [float(x) for x in text.split(",")]
    except ValueError as e:
        raise argparse.ArgumentTypeError(f"'{text}': two numbers D1,D2") from e
    if len(d) != 2 or not 0 < d[0] < d[1] <= 10:
        raise argparse.ArgumentTypeError(f"'{text}': D1,D2 with 0 < D1 < D2 <= 10 s")
    return d


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mcsim", required=True)
    ap.add_argument("--motor", default=os.path.join(ROOT, "sim", "motors", "odrive-d5065.toml"))
    ap.add_argument("--board", action="append", help=f"board name (default {', '.join(BOARDS)})")
    ap.add_argument("--scenario", action="append",
                    help=f"scenario (default {', '.join(SCENARIOS)})")
    ap.add_argument("--durations", type=durations_arg, default=[0.01, 0.04],
                    help="two simulated durations D1,D2 [s] (default 0.01,0.04)")
    ap.add_argument("--repeats", type=int, choices=range(1, 11), default=2, metavar="N",
                    help="runs per measurement, the least wall time kept (default 2)")
    ap.add_argument("--out", help="also write the JSON here")
    a = ap.parse_args(argv)
    machine = {"nproc": os.cpu_count(), "machine": platform.machine(),
               "loadavg_1min_start": round(os.getloadavg()[0], 2)}
    runs = []
    try:
        with tempfile.TemporaryDirectory(prefix="pil_cost_") as work:
            for board in a.board or BOARDS:
                for scen in a.scenario or SCENARIOS:
                    runs.append(measure(a.mcsim, os.path.abspath(a.motor), board, scen,
                                        a.durations, a.repeats, work))
    except BenchError as e:
        print(f"run_pil_cost: {e}", file=sys.stderr)
        return 2
    machine["loadavg_1min_end"] = round(os.getloadavg()[0], 2)
    mc = os.path.abspath(a.mcsim)
    cmd = ["tools/bench/run_pil_cost.py", "--mcsim",
           os.path.relpath(mc, ROOT) if mc.startswith(ROOT + os.sep) else a.mcsim]
    for b in a.board or []:
        cmd += ["--board", b]
    for sc in a.scenario or []:
        cmd += ["--scenario", sc]
    cmd += ["--durations", ",".join(repr(d) for d in a.durations), "--repeats", str(a.repeats)]
    res = {"benchmark": "pil_cost", "command": " ".join(cmd), "machine": machine, "runs": runs}
    text = json.dumps(res, indent=1)
    print(text)
    if a.out:
        with open(a.out, "w") as fh:
            fh.write(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
