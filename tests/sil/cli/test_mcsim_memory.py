#!/usr/bin/env python3
"""mcsim keeps bounded memory in every scenario (label sil).

    test_mcsim_memory.py --mcsim PATH --peak-rss PATH --motors DIR

For every scenario of `mcsim list` (a scenario missing from RUNS below fails
the test, so a new one cannot be forgotten): the peak resident set of a
short run and of a run 10x longer, measured by peak_rss (a small C program:
a child forked from this Python process would carry the parent's 10 MB in
its peak and hide mcsim's). Summaries are computed on the fly, traces are
decimated or kept in temporary files (sim/README.md, "Memory"), so the
longer run may not need more memory.

Bound: 1 MiB. What varies between two runs of one binary is the allocator's
and stdio's pages (a few hundred kB measured); the long runs take 4e4 to 4e5
periods, so a leak of 24 to 240 bytes per period (three doubles to a
30-value row, what the issue found: 4.7 MB per simulated second in
pi2d-motor, 235 bytes per 20 kHz period) fails the bound.
"""
import argparse
import os
import subprocess
import sys
import tempfile
import unittest

ARGS = None
BOUND_KB = 1024

D5065 = ["--motor", "odrive-d5065.toml", "--board", "odrive-v36-24v.toml"]

# scenario: (arguments of both runs, the short run's extra arguments, the
# long run's). The long run is 10x the short one in its length: --duration,
# or for the scenarios whose length is set by what they do, the parameter
# that sets it (or, where nothing does, the reason in a comment). The
# observer scenarios run at 8 kHz: 10 s for 8e4 periods.
RUNS = {
    "can-telemetry": ([], ["--duration", "0.3"], ["--duration", "3"]),
    "csmc-drive": ([], ["--duration", "0.2"], ["--duration", "2"]),
    "csmc-state-feedback": ([], ["--duration", "0.05"], ["--duration", "0.5"]),
    "csmc-output-feedback": ([], ["--duration", "0.05"], ["--duration", "0.5"]),
    "csmc-output-feedback-eps": ([], ["--duration", "0.02"], ["--duration", "0.2"]),
    # 1e-4 s periods: 1e4 per simulated second
    "csmc-sampled": ([], ["--duration", "0.5"], ["--duration", "5"]),
    "csmc-sinusoid": (["--set", "dt_s=1e-4"], ["--duration", "0.5"], ["--duration", "5"]),
    "field-weakening": (D5065, ["--duration", "0.2"], ["--duration", "2"]),
    # Commissioning's length is the sequence's (about 6 s simulated on any
    # motor), not a setting: --duration is refused. It keeps nothing per
    # period (the firmware's fixed-size state, one CSV row); the comparison
    # is with verify=1, which adds two speed steps on the identified values.
    "commission": (D5065, [], ["--set", "verify=1"]),
    "current-step": (D5065, ["--duration", "0.2"], ["--duration", "2"]),
    # thermal times divided by 100 (tests/sil/motors/test_thermal_duty_sil.cpp)
    "thermal-duty": (D5065 + ["--set", "tau_w_s=0.3", "--set", "tau_h_s=9", "--set", "on_s=0.6",
                              "--set", "off_s=0.3"], ["--duration", "0.2"], ["--duration", "2"]),
    "speed-step": (D5065, ["--duration", "0.2"], ["--duration", "2"]),
    "load-step": (D5065, ["--duration", "0.2"], ["--duration", "2"]),
    "sensorless-speed-step": (D5065, ["--duration", "0.2"], ["--duration", "2"]),
    "position-move": (D5065, ["--duration", "0.2"], ["--duration", "2"]),
    "observer-error-phase": ([], ["--duration", "1.2"], ["--duration", "12"]),
    "observer-table1": ([], ["--duration", "1"], ["--duration", "10"]),
    "observer-test-motor": ([], ["--duration", "1"], ["--duration", "10"]),
    # Its length is ten speeds times hold_s (--duration is refused).
    "observer-lowspeed-sweep": ([], ["--set", "hold_s=0.2"], ["--set", "hold_s=2"]),
    "ii-observer": ([], ["--duration", "1"], ["--duration", "10"]),
    "pi2d-paper": ([], ["--duration", "1.4"], ["--duration", "14"]),
    "pi2d-motor": ([], ["--duration", "0.22"], ["--duration", "2.2"]),
    # No time at all: the proof's conditions for two sets of gains.
    "pi2d-certificate": ([], [], ["--set", "motor=1"]),
    "pmsm-open-loop-step": ([], ["--duration", "0.2"], ["--duration", "2"]),
    "foc-current-step": ([], ["--duration", "0.2"], ["--duration", "2"]),
    "stepper-constant-voltage": ([], ["--duration", "0.1"], ["--duration", "1"]),
    "pi2d-paper-q31": ([], ["--duration", "1.4"], ["--duration", "14"]),
    "pi2d-motor-q31": ([], ["--duration", "0.22"], ["--duration", "2.2"]),
    "csmc-state-feedback-q31": ([], ["--duration", "0.05"], ["--duration", "0.5"]),
    "regen-stop": (D5065, ["--duration", "0.2"], ["--duration", "2"]),
    "bus-limits": (D5065, ["--duration", "0.2"], ["--duration", "2"]),
    # The D5065 with cogging (its file has none); at speed_frac 0.001 the
    # speed phase's window (20 cogging periods) outlasts both runs, so
    # --duration (the cap of its phases) sets the length.
    "cogging": (D5065 + ["--set", "motor.slots=12", "--set", "motor.cogging_nm=0.018",
                         "--set", "speed_frac=0.001"], ["--duration", "0.2"], ["--duration", "2"]),
}


def peak_kb(out, scenario, args):
    argv = [ARGS.peak_rss, ARGS.mcsim, "run", scenario, "--out", out]
    argv += [os.path.join(ARGS.motors, a) if a.endswith(".toml") else a for a in args]
    p = subprocess.run(argv, capture_output=True, text=True, timeout=600)
    # a short run may fail its verdict (exit 1: too short to judge); it ran.
    if p.returncode not in (0, 1):
        raise AssertionError(f"{' '.join(argv)}: exit {p.returncode}\n{p.stderr}")
    for line in p.stderr.splitlines():
        if line.startswith("peak_rss_kb "):
            return int(line.split()[1])
    raise AssertionError(f"no peak_rss_kb line: {p.stderr}")


class Memory(unittest.TestCase):
    def test_every_scenario_is_listed(self):
        names = [ln.split()[0] for ln in subprocess.run(
            [ARGS.mcsim, "list"], capture_output=True, text=True, check=True).stdout.splitlines()]
        self.assertEqual(sorted(names), sorted(RUNS), "RUNS must name every scenario")

    def test_longer_run_needs_no_more_memory(self):
        with tempfile.TemporaryDirectory() as tmp:
            for scenario, (common, short, long) in RUNS.items():
                with self.subTest(scenario=scenario):
                    a = peak_kb(os.path.join(tmp, scenario, "short"), scenario, common + short)
                    b = peak_kb(os.path.join(tmp, scenario, "long"), scenario, common + long)
                    print(f"{scenario}: {a} kB -> {b} kB", flush=True)
                    self.assertLess(b - a, BOUND_KB, f"{scenario}: {a} kB short, {b} kB long")


if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("--mcsim", required=True)
    ap.add_argument("--peak-rss", required=True)
    ap.add_argument("--motors", required=True)
    ARGS, rest = ap.parse_known_args()
    unittest.main(argv=[sys.argv[0], "-v", *rest])
