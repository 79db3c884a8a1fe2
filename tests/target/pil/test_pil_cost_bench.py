#!/usr/bin/env python3
"""The PIL cost benchmark's report (tools/bench/run_pil_cost.py), on short
runs: its form and units, never a wall-clock figure (the machine's load
decides those).

    test_pil_cost_bench.py --mcsim M --bench tools/bench/run_pil_cost.py --work DIR
"""

import argparse
import json
import os
import subprocess
import sys
import unittest

ARGS = None
KEYS = {"board", "scenario", "motor", "durations_s", "pil_wall_s", "sil_wall_s",
        "pil_wall_per_sim_s", "pil_start_s", "sil_wall_per_sim_s", "pil_over_sil"}


def bench(*argv):
    return subprocess.run([sys.executable, ARGS.bench, "--mcsim", ARGS.mcsim, *argv],
                          capture_output=True, text=True, timeout=600, check=False)


class PilCostBench(unittest.TestCase):
    def test_report(self):
        out = os.path.join(ARGS.work, "pil_cost.json")
        p = bench("--board", "odrive36", "--scenario", "current-step", "--durations",
                  "0.002,0.004", "--repeats", "1", "--out", out)
        self.assertEqual(p.returncode, 0, p.stderr)
        r = json.loads(p.stdout)
        with open(out) as fh:
            self.assertEqual(json.load(fh), r, "--out holds what was printed")
        self.assertEqual(r["benchmark"], "pil_cost")
        self.assertEqual(r["machine"]["nproc"], os.cpu_count())
        self.assertEqual(len(r["runs"]), 1)
        run = r["runs"][0]
        self.assertEqual(set(run), KEYS)
        self.assertEqual((run["board"], run["scenario"]), ("odrive36", "current-step"))
        self.assertEqual(run["durations_s"], [0.002, 0.004])
        # wall times of runs that happened: positive; a PIL run (QEMU started,
        # the image booted) costs more than the SIL run of the same length
        self.assertTrue(all(w > 0 for w in run["pil_wall_s"]), run)
        self.assertGreater(run["sil_wall_s"], 0)
        self.assertGreater(run["pil_wall_s"][1], run["sil_wall_s"])

    def test_failed_run_is_named_exit_2(self):
        p = bench("--board", "no_such_board", "--scenario", "current-step", "--durations",
                  "0.002,0.004")
        self.assertEqual(p.returncode, 2)
        self.assertIn("no board of that name", p.stderr)
        self.assertEqual(p.stdout, "")

    def test_bad_durations_refused(self):
        for d in ("0.004,0.002", "0.01", "x,y", "0,1"):
            p = bench("--durations", d)
            self.assertEqual(p.returncode, 2, d)
            self.assertIn("--durations", p.stderr)


def main():
    global ARGS
    ap = argparse.ArgumentParser()
    ap.add_argument("--mcsim", required=True)
    ap.add_argument("--bench", required=True)
    ap.add_argument("--work", required=True)
    ARGS, rest = ap.parse_known_args()
    os.makedirs(ARGS.work, exist_ok=True)
    unittest.main(argv=[sys.argv[0]] + rest, verbosity=2)


if __name__ == "__main__":
    main()
