#!/usr/bin/env python3
"""Campaigns (labels campaign, sil): `mdtool sweep` on a two-process local
Dask cluster gives the rows of the serial runs bit for bit; an interrupted
campaign resumes without redoing finished runs; a row reruns to itself; a
malformed campaign file is refused with its line and the reason.

    test_campaign.py --mcsim PATH --root REPO --work DIR
"""
import argparse
import os
import shutil
import signal
import subprocess
import sys
import time
import unittest

import pandas as pd

ARGS = None

CAMPAIGN = """\
[campaign]
name = "tiny"
scenario = "current-step"
motor = "{root}/sim/motors/odrive-d5065.toml"
board = "{root}/sim/motors/odrive-v36-24v.toml"
duration_s = 0.004
seed = 11
samples = 2

[fixed]
csv_every = 10

[sweep]
iq_step_a = [3.0, 60.0]
cur_bw_rad_s = {{ start = 1000.0, stop = 100000.0, num = 3, log = true }}
id_step_a = {{ dist = "uniform", low = -2.0, high = 0.0 }}

[pass]
fast = "iq_rise_time_ratio < 1.25 and abs(iq_final_a - param.iq_step_a) < 0.1 * abs(param.iq_step_a)"
"""
NRUNS = 12


def mdtool(*argv, check=True, timeout=240):
    p = subprocess.run([sys.executable, "-m", "mdtool.cli", *argv], capture_output=True,
                       text=True, timeout=timeout)
    if check and p.returncode != 0:
        raise AssertionError(f"mdtool {' '.join(argv)}: exit {p.returncode}\n{p.stderr}")
    return p


def results(out, drop=("wall_s",)):
    return pd.read_parquet(os.path.join(out, "results.parquet")).drop(columns=list(drop))


def parts(out):
    d = os.path.join(out, "parts")
    return {f: os.stat(os.path.join(d, f)).st_mtime_ns for f in os.listdir(d)
            if f.endswith(".parquet")}


class Campaigns(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.file = os.path.join(ARGS.work, "tiny.toml")
        with open(cls.file, "w") as f:
            f.write(CAMPAIGN.format(root=ARGS.root))
        cls.serial = os.path.join(ARGS.work, "serial")
        shutil.rmtree(cls.serial, ignore_errors=True)
        mdtool("sweep", cls.file, "--out", cls.serial, "--serial", "--quiet")

    def test_serial_rows(self):
        df = results(self.serial)
        self.assertEqual(list(df["run_id"]), list(range(NRUNS)))
        self.assertEqual(df["run_id"].is_unique, True)
        # The runs of the file: pass, fail and fault all occur.
        self.assertTrue({"pass", "fault"} <= set(df["status"]), df["status"].tolist())
        for col in ("seed", "in.iq_step_a", "in.cur_bw_rad_s", "in.id_step_a", "in.csv_every",
                    "out.iq_rise_time_s", "firmware_git", "motor_sha256", "pass.fast"):
            self.assertIn(col, df.columns)

    def test_two_process_cluster_equals_serial(self):
        out = os.path.join(ARGS.work, "dask2")
        shutil.rmtree(out, ignore_errors=True)
        p = mdtool("sweep", self.file, "--out", out, "--workers", "2", "--chunk", "2")
        self.assertIn('"ran": 12', p.stdout)
        pd.testing.assert_frame_equal(results(out), results(self.serial), check_exact=True)

    def test_resume_after_max_runs(self):
        out = os.path.join(ARGS.work, "resume")
        shutil.rmtree(out, ignore_errors=True)
        p = mdtool("sweep", self.file, "--out", out, "--serial", "--max-runs", "5", "--chunk",
                   "1", "--quiet", check=False)
        self.assertEqual(p.returncode, 3, p.stderr)
        first = parts(out)
        self.assertEqual(len(first), 5)
        self.assertFalse(os.path.exists(os.path.join(out, "results.parquet")))
        p = mdtool("sweep", self.file, "--out", out, "--workers", "2", "--quiet")
        self.assertIn('"already": 5, "ran": 7, "remaining": 0', p.stdout)
        after = parts(out)
        for f, mtime in first.items():
            self.assertEqual(after[f], mtime, f"{f} was rewritten")
        pd.testing.assert_frame_equal(results(out), results(self.serial), check_exact=True)
        # Nothing left: a third invocation runs nothing.
        p = mdtool("sweep", self.file, "--out", out, "--serial", "--quiet")
        self.assertIn('"already": 12, "ran": 0', p.stdout)

    def test_resume_after_kill(self):
        out = os.path.join(ARGS.work, "killed")
        shutil.rmtree(out, ignore_errors=True)
        proc = subprocess.Popen([sys.executable, "-m", "mdtool.cli", "sweep", self.file, "--out",
                                 out, "--serial", "--chunk", "1", "--quiet"],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and proc.poll() is None:
            if os.path.isdir(os.path.join(out, "parts")) and len(parts(out)) >= 3:
                break
            time.sleep(0.01)
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        first = parts(out)
        self.assertGreaterEqual(len(first), 3)
        p = mdtool("sweep", self.file, "--out", out, "--serial", "--quiet")
        self.assertIn(f'"already": {len(first)}, "ran": {NRUNS - len(first)}', p.stdout)
        pd.testing.assert_frame_equal(results(out), results(self.serial), check_exact=True)

    def test_changed_file_refused_on_resume(self):
        out = os.path.join(ARGS.work, "changed")
        shutil.rmtree(out, ignore_errors=True)
        mdtool("sweep", self.file, "--out", out, "--serial", "--max-runs", "1", "--quiet",
               check=False)
        other = os.path.join(ARGS.work, "tiny2.toml")
        with open(other, "w") as f:
            f.write(CAMPAIGN.format(root=ARGS.root).replace("seed = 11", "seed = 12"))
        p = mdtool("sweep", other, "--out", out, "--serial", check=False)
        self.assertEqual(p.returncode, 2)
        self.assertIn("holds runs of a different campaign (campaign_sha256 changed", p.stderr)

    def test_rerun_from_row(self):
        for rid in (0, 11):
            p = mdtool("rerun", self.serial, str(rid))
            self.assertIn('"same": true', p.stdout)


BAD = [
    # (text, line, reason fragment)
    ("[campaign\nname = 'x'\n", 1, "malformed TOML"),
    ("[campaign]\nname = 'x'\n", 1, "[campaign] needs scenario"),
    ("[campaign]\nname = 'x'\nscenario = 'nope'\n", 3, "unknown scenario 'nope'"),
    ("[campaign]\nname = 'x'\nscenario = 'current-step'\nmotr = 'm.toml'\n", 4,
     "unknown key 'motr' in [campaign]"),
    ("[campaign]\nname = 'x'\nscenario = 'current-step'\n", 3, "needs --motor FILE"),
    ("[campaign]\nname = 'x'\nscenario = 'current-step'\nmotor = 'missing.toml'\n", 4,
     "missing.toml:1: cannot read the file"),
    ("{head}\n[sweep]\niq_step_a = [1.0, 1e9]\n", 7, "value 1000000000.0 for iq_step_a is out "
     "of range"),
    ("{head}\n[sweep]\nno_such = [1.0]\n", 7, "unknown key 'no_such' (scenario current-step "
     "takes: iq_step_a"),
    ("{head}\n[sweep]\n\niq_step_a = {{ dist = 'gauss', mean = 1, sd = 2 }}\n", 8,
     "unknown dist 'gauss'"),
    ("{head}\n[sweep]\niq_step_a = {{ start = 1.0, stop = 2.0 }}\n", 7, "a range for iq_step_a"),
    ("{head}\n[sweep]\niq_step_a = []\n", 7, "empty grid"),
    ("{head}\n[pass]\nok = 'iq_rise_time_s <'\n", 7, "pass criterion 'ok'"),
    ("{head}\n[pass]\nok = '__import__(\"os\")'\n", 7, "only calls to"),
    ("{head}\nsamples = 3\n", 6, "samples > 1 needs a distribution"),
    ("{head}\n[fixed]\niq_step_a = 'big'\n", 7, "value 'big' for iq_step_a"),
    ("{head}\n[sweeps]\n", 6, "unknown table [sweeps]"),
]


class Malformed(unittest.TestCase):
    def test_refused_with_line_and_reason(self):
        head = ("[campaign]\nname = 'bad'\nscenario = 'current-step'\n"
                f"motor = '{ARGS.root}/sim/motors/odrive-d5065.toml'\n"
                f"board = '{ARGS.root}/sim/motors/odrive-v36-24v.toml'\n")
        for i, (text, line, reason) in enumerate(BAD):
            with self.subTest(i=i, reason=reason):
                path = os.path.join(ARGS.work, f"bad{i}.toml")
                with open(path, "w") as f:
                    f.write(text.format(head=head.rstrip("\n")))
                out = os.path.join(ARGS.work, f"bad{i}.out")
                p = mdtool("sweep", path, "--out", out, "--serial", check=False)
                self.assertEqual(p.returncode, 2, p.stderr)
                self.assertTrue(p.stderr.startswith(f"mdtool: {path}:{line}: "), p.stderr)
                self.assertIn(reason, p.stderr)
                self.assertFalse(os.path.exists(out), "a refused campaign wrote results")


def main():
    global ARGS
    ap = argparse.ArgumentParser()
    ap.add_argument("--mcsim", required=True)
    ap.add_argument("--root", required=True)
    ap.add_argument("--work", required=True)
    ARGS, rest = ap.parse_known_args()
    ARGS.work = os.path.abspath(ARGS.work)
    os.makedirs(ARGS.work, exist_ok=True)
    unittest.main(argv=[sys.argv[0], *rest], verbosity=2)


if __name__ == "__main__":
    main()
