#!/usr/bin/env python3
"""Campaigns (labels campaign, sil): `mdtool sweep` on a two-process local
Dask cluster gives the rows of the serial runs bit for bit; an interrupted
campaign resumes without redoing finished runs; a row reruns to itself; a
malformed campaign file is refused with its line and the reason.

    test_campaign.py --mcsim PATH --root REPO --work DIR
"""
import argparse
import json
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
seed = 11
samples = 2

[fixed]
csv_every = 10

[sweep]
iq_step_a = [3.0, 50.0]
current_bw_rad_s = {{ start = 1000.0, stop = 7000.0, num = 3, log = true }}
id_step_a = {{ dist = "uniform", low = -2.0, high = 0.0 }}

[derived]
# the fastest loop on a drive told 20 times the motor's inductance (its
# current loop's gain 20 times too high): the drive trips, a drive fault in
# the campaign (a bandwidth above the parameter table's 0.3 pwm_hz, 7.2 kHz
# here, would be refused before the run)
model_l_scale = "1.0 + 19.0 * (current_bw_rad_s > 5000.0)"

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


def results(out, drop=("wall_s", "worker")):
    # mdtool's reader (pyarrow from the path): pandas' read_parquet can abort
    # this process at exit (mdtool/parquet.py)
    from mdtool.parquet import read_parquet
    return read_parquet(os.path.join(out, "results.parquet")).drop(columns=list(drop))


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
        for col in ("seed", "in.iq_step_a", "in.current_bw_rad_s", "in.id_step_a", "in.csv_every",
                    "out.iq_rise_time_s", "firmware_git", "motor_sha256", "pass.fast"):
            self.assertIn(col, df.columns)

    def test_two_process_cluster_equals_serial(self):
        out = os.path.join(ARGS.work, "dask2")
        shutil.rmtree(out, ignore_errors=True)
        p = mdtool("sweep", self.file, "--out", out, "--workers", "2", "--chunk", "2")
        self.assertIn('"ran": 12', p.stdout)
        pd.testing.assert_frame_equal(results(out), results(self.serial), check_exact=True)
        # Two worker processes ran them, neither of them the serial one.
        workers = set(results(out, drop=())["worker"])
        self.assertEqual(len(workers), 2, workers)
        self.assertFalse(workers & set(results(self.serial, drop=())["worker"]))

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

    def test_damaged_part_named_then_run_again(self):
        out = os.path.join(ARGS.work, "damaged")
        shutil.rmtree(out, ignore_errors=True)
        mdtool("sweep", self.file, "--out", out, "--serial", "--max-runs", "4", "--chunk", "1",
               "--quiet", check=False)
        part = os.path.join(out, "parts", "part-000000001.parquet")
        with open(part, "rb") as f:
            data = f.read()
        with open(part, "wb") as f:  # a truncated file (a full disk, a copy cut short)
            f.write(data[: len(data) // 2])
        p = mdtool("report", out, check=False)
        self.assertEqual(p.returncode, 2, p.stderr)
        self.assertIn(f"mdtool: {part}: damaged part (", p.stderr)
        self.assertNotIn("Traceback", p.stderr)
        p = mdtool("sweep", self.file, "--out", out, "--serial", "--quiet")
        self.assertIn(f"{part}: damaged part (", p.stderr)
        self.assertIn("set aside as part-000000001.parquet.damaged; its runs run again", p.stderr)
        self.assertIn('"already": 3, "ran": 9, "remaining": 0', p.stdout)
        self.assertTrue(os.path.exists(part + ".damaged"))
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


DERIVED = """\
[campaign]
name = "derived"
scenario = "current-step"
motor = "{root}/sim/motors/odrive-d5065.toml"
board = "{root}/sim/motors/odrive-v36-24v.toml"
seed = 5
samples = 3

[fixed]  # the board's 120 ns dead time slows a 2 A step on an 0.02 ohm winding
"board.dead_time_s" = 0.0  # past the 25 % the current-step verdict allows

[sweep]
"motor.r_ohm" = {{ dist = "loguniform", low = 0.02, high = 0.2 }}
"motor.pole_pairs" = [4, 7]

[vars]
tau_s = {{ dist = "uniform", low = 3.0e-4, high = 1.0e-3 }}
shift = [0.0, -1.0]

[derived]
"motor.ld_h" = "motor.r_ohm * tau_s"
"motor.lq_h" = "motor.ld_h"
iq_step_a = "log10(1.0 + shift) + 2.0"   # log10(0): the runs of shift = -1 are refused
"""


class VarsAndDerived(unittest.TestCase):
    """[vars] are drawn but not given to the scenario; [derived] parameters
    are computed from the others; a derivation that fails refuses its run."""

    def test_rows(self):
        path = os.path.join(ARGS.work, "derived.toml")
        with open(path, "w") as f:
            f.write(DERIVED.format(root=ARGS.root))
        out = os.path.join(ARGS.work, "derived")
        shutil.rmtree(out, ignore_errors=True)
        mdtool("sweep", path, "--out", out, "--serial", "--quiet")
        df = results(out)
        self.assertEqual(len(df), 2 * 2 * 3)  # pole pairs x shift x samples
        ok = df[df["var.shift"] == 0.0]
        bad = df[df["var.shift"] == -1.0]
        self.assertEqual(len(ok), 6)
        # The derived values are the expressions of the drawn ones, exactly,
        # and the run used them (the summary echoes the motor's values).
        self.assertTrue(((ok["in.motor.ld_h"] == ok["in.motor.r_ohm"] * ok["var.tau_s"])).all())
        self.assertTrue((ok["in.motor.lq_h"] == ok["in.motor.ld_h"]).all())
        self.assertTrue((ok["in.iq_step_a"] == 2.0).all())
        self.assertTrue((ok["out.param.iq_step_a"] == 2.0).all())
        self.assertEqual(set(ok["status"]), {"pass"})
        self.assertNotIn("out.param.tau_s", df.columns)  # a var is not a parameter
        self.assertNotIn("in.tau_s", df.columns)
        # Integer grid values reach the motor file as integers.
        self.assertEqual(sorted(set(df["in.motor.pole_pairs"])), [4, 7])
        self.assertEqual(set(bad["status"]), {"refused"})
        for e in bad["error"]:
            self.assertIn("derived iq_step_a = 'log10(1.0 + shift) + 2.0': math domain error", e)
        # A row reruns to itself from the row alone (derived values included).
        for rid in (int(ok["run_id"].iloc[0]), int(bad["run_id"].iloc[0])):
            p = mdtool("rerun", out, str(rid))
            self.assertIn('"same": true', p.stdout)


class Verdicts(unittest.TestCase):
    """A run that does not pass its own verdict is not a pass, whatever the
    criteria: 4 ms of a current step end before the d step (mcsim exits 1,
    "target not reached"); a campaign's duration_s is bounded like mcsim's
    --duration."""

    def test_short_runs_fail_by_their_verdict(self):
        path = os.path.join(ARGS.work, "short.toml")
        with open(path, "w") as f:
            f.write(CAMPAIGN.format(root=ARGS.root).replace("seed = 11", "duration_s = 0.004\nseed = 11")
                    .replace('fast = "', 'ran = "rows > 0"\nfast = "'))
        out = os.path.join(ARGS.work, "short")
        shutil.rmtree(out, ignore_errors=True)
        mdtool("sweep", path, "--out", out, "--serial", "--quiet")
        df = results(out)
        self.assertNotIn("pass", set(df["status"]), df["status"].tolist())
        fail = df[df["status"] == "fail"]
        self.assertGreater(len(fail), 0)
        # the d step after the run's end, or (the fastest loops: it comes
        # within 4 ms) its current not settled by then
        self.assertIn("target not reached", set(fail["out.verdict"]))
        self.assertLessEqual(set(fail["out.verdict"]), {"target not reached", "not settled"})
        self.assertTrue(fail["pass.ran"].all())  # the criteria still hold: the verdict fails it
        # the error is the named reason (the report groups runs by it), its
        # figures in verdict_detail
        for e, v, d in zip(fail["error"], fail["out.verdict"], fail["verdict_detail"],
                           strict=True):
            self.assertEqual(e, f"run failed: {v}")
            self.assertIn(" FAILED", d)  # each failed check with its figure and bound
        # a drive fault is a fault, by name
        fault = df[df["status"] == "fault"]
        self.assertGreater(len(fault), 0)
        for e, v in zip(fault["error"], fault["out.verdict"], strict=True):
            self.assertTrue(v.startswith("faulted: "), v)
            self.assertEqual(e, f"run failed: {v}")

    def test_duration_bounds(self):
        head = ("[campaign]\nname = 'd'\nscenario = '{s}'\n"
                f"motor = '{ARGS.root}/sim/motors/odrive-d5065.toml'\n"
                f"board = '{ARGS.root}/sim/motors/odrive-v36-24v.toml'\n"
                "duration_s = {d}\n[pass]\nok = 'rows > 0'\n")
        for scen, dur, reason in (("current-step", "1e300", "(0, 3600] s"),
                                  ("current-step", "3601.0", "(0, 3600] s"),
                                  ("commission", "1.0", "takes no duration_s")):
            with self.subTest(scen=scen, dur=dur):
                path = os.path.join(ARGS.work, "dur.toml")
                with open(path, "w") as f:
                    f.write(head.format(s=scen, d=dur))
                p = mdtool("sweep", path, "--out", os.path.join(ARGS.work, "dur"), "--serial",
                           check=False)
                self.assertEqual(p.returncode, 2, p.stderr)
                self.assertTrue(p.stderr.startswith(f"mdtool: {path}:6: "), p.stderr)
                self.assertIn(reason, p.stderr)


class ShippedCampaigns(unittest.TestCase):
    def test_they_load(self):
        from mdtool import campaign
        d = os.path.join(ARGS.root, "tools/mdtool/campaigns")
        names = sorted(f for f in os.listdir(d) if f.endswith(".toml"))
        self.assertIn("commissioning-accuracy.toml", names)
        for f in names:
            with self.subTest(f=f):
                c = campaign.load(os.path.join(d, f))
                self.assertGreater(c.n_runs(), 0)
                self.assertTrue(c.criteria)
        c = campaign.load(os.path.join(d, "commissioning-accuracy.toml"))
        # Issue 18's bounds are the criteria.
        crit = {k.name: k.text for k in c.criteria}
        self.assertEqual(crit["r_2pct"], "abs(error.r_frac) < 0.02")
        self.assertEqual(crit["ld_5pct"], "abs(error.ld_frac) < 0.05")
        self.assertEqual(crit["lq_5pct"], "abs(error.lq_frac) < 0.05")
        self.assertEqual(crit["flux_3pct"], "abs(error.flux_frac) < 0.03")
        self.assertEqual(crit["offset_1deg"], "abs(error.encoder_offset_deg) < 1.0")
        self.assertEqual(crit["pole_pairs_exact"], "error.pole_pairs_diff == 0")
        self.assertEqual(crit["direction_right"], "error.direction_wrong == 0")
        # Every drawn motor is a valid motor file: the first runs' inputs.
        for i in range(3):
            r = c.run_inputs(i)
            self.assertIsNone(r["refuse"])
            p = r["params"]
            self.assertLessEqual(p["motor.ld_h"], p["motor.lq_h"])
            self.assertIsInstance(p["motor.pole_pairs"], int)


class Report(unittest.TestCase):
    def test_histograms_and_tables(self):
        path = os.path.join(ARGS.work, "tiny-report.toml")
        with open(path, "w") as f:
            f.write(CAMPAIGN.format(root=ARGS.root))
        serial = os.path.join(ARGS.work, "serial-report")
        shutil.rmtree(serial, ignore_errors=True)
        mdtool("sweep", path, "--out", serial, "--serial", "--quiet")
        rep = os.path.join(ARGS.work, "report")
        shutil.rmtree(rep, ignore_errors=True)
        mdtool("report", serial, "--x", "iq_step_a", "--y", "id_step_a", "--metric",
               "pass_rate", "--hist", "iq_rise_time_ratio=1.25", "--report-dir", rep,
               "--with-results")
        for f in ("envelope.png", "histograms.png", "summary.md", "envelope.csv",
                  "results.parquet"):
            self.assertTrue(os.path.exists(os.path.join(rep, f)), f)
        df = results(serial)
        v = df["out.iq_rise_time_ratio"].dropna().abs()
        with open(os.path.join(rep, "summary.md")) as f:
            md = f.read()
        self.assertIn(f"| iq_rise_time_ratio | 1.25 | {len(v)} | {int((v < 1.25).sum())} |", md)
        st = df["status"].value_counts()
        self.assertIn(f"| **all** | {len(df)} | {st.get('pass', 0)} | {st.get('fail', 0)} | "
                      f"{st.get('refused', 0)} | {st.get('fault', 0)} |", md)
        # The copy holds the same rows, with paths relative to the directory it was made in.
        copy = results(rep, drop=("wall_s",))
        self.assertNotIn("worker", copy.columns)
        self.assertEqual(list(copy["run_id"]), list(df["run_id"]))
        self.assertFalse(copy["motor"].iloc[0].startswith("/"))
        p = mdtool("report", serial, "--hist", "iq_rise_time_ratio=-1", "--report-dir", rep,
                   check=False)
        self.assertEqual(p.returncode, 2)
        self.assertIn("positive BOUND", p.stderr)


class BenchPage(unittest.TestCase):
    """The benchmark's page is arithmetic on its JSON (not a timing test)."""

    def test_sizing_arithmetic(self):
        res = {"scenario": "current-step", "duration_s": 1.0, "runs": 20, "firmware_git": "x",
               "build_type": "Release", "dask_runs_per_task": 37,
               "cpu": "cpu", "nproc": 2, "cores_usable": 2, "python": "3",
               "load_avg_before": [0.1, 0.1, 0.1], "load_avg_after": [0.2, 0.1, 0.1],
               "bench_wall_s": 60.0, "inprocess_runs_per_s": 4.0,
               "inprocess_cpu_s_per_run": 0.25, "inprocess_realtime_factor": 4.0,
               "mcsim_subprocess_runs_per_s": 2.0, "mcsim_subprocess_cpu_s_per_run": 0.5,
               "inprocess_over_subprocess": 2.0, "fault_run_error": "run failed: OVERCURRENT",
               "fault_run_sim_s": 0.001, "fault_run_s": 0.0025, "fault_run_cpu_s": 0.0025,
               "pass_run_s": 0.25, "fault_cost_ratio": 0.01, "dask_1_worker_runs_per_s": 3.6,
               "dask_1_worker_cpu_s_per_run": 0.25, "dask_2_workers_runs_per_s": 6.0,
               "dask_2_workers_cpu_s_per_run": 0.3, "dask_scaling_efficiency": 6.0 / 7.2,
               "dask_cpu_efficiency": 0.25 / 0.3, "dask_task_latency_s": 0.002,
               "dask_task_overhead_s": 0.01, "parquet_bytes_per_row": 200.0}
        js = os.path.join(ARGS.work, "bench.json")
        md = os.path.join(ARGS.work, "bench.md")
        with open(js, "w") as f:
            json.dump(res, f)
        mdtool("bench-sil", "--from-json", js, "--md", md)
        with open(md) as f:
            text = f.read()
        # 100,000 runs x 0.3 CPU s = 30,000 core-seconds = 8.33 core-hours;
        # on 32 cores: 937.5 s = 16 min at E = 1, 1125 s = 19 min at E = 0.83.
        self.assertIn("100,000 x c = 8.33 core-hours", text)
        self.assertIn("Dask: 4 tasks of 37 runs per worker.", text)
        self.assertIn("| 32 | 16 min | 19 min |", text)
        self.assertIn("tasks of at least 4 runs", text)  # 100 x 10 ms / 0.3 s = 3.3, up to 4
        self.assertIn("(this scenario's 100,000 rows: 20 MB)", text)
        self.assertNotIn("machine was busy", text)
        self.assertNotIn("build**", text)
        res["load_avg_before"] = [5.0, 4.0, 3.0]
        with open(js, "w") as f:
            json.dump(res, f)
        mdtool("bench-sil", "--from-json", js, "--md", md)
        with open(md) as f:
            self.assertIn("**The machine was busy** (load average up to 5 on 2 cores", f.read())


LIMITS = """\
[campaign]
name = "limits"
scenario = "current-step"
motor = "{root}/sim/motors/odrive-d5065.toml"
board = "{root}/sim/motors/odrive-v36-24v.toml"
duration_s = 0.004

[vars]
n = [2, 9]

[derived]
iq_step_a = "3.0 + n ** n ** n / 1e300"    # n = 9: 9 ** 387420489, refused by the evaluator

[pass]
big = "(round(abs(iq_final_a)) + 2) ** 10**9 > 0"   # an integer power of 1e9: refused too
"""


class ExpressionLimits(unittest.TestCase):
    """An expression reading a run's values is bounded when it is evaluated:
    the run's row names the limit instead of hanging the run or the sweep."""

    def test_in_rows(self):
        path = os.path.join(ARGS.work, "limits.toml")
        with open(path, "w") as f:
            f.write(LIMITS.format(root=ARGS.root))
        out = os.path.join(ARGS.work, "limits")
        shutil.rmtree(out, ignore_errors=True)
        mdtool("sweep", path, "--out", out, "--serial", "--quiet", timeout=120)
        df = results(out).set_index("var.n")
        self.assertEqual(df.loc[9, "status"], "refused")
        self.assertIn("derived iq_step_a = '3.0 + n ** n ** n / 1e300': expression limit: 9 ** "
                      "387420489 would have more than 4096 bits", df.loc[9, "error"])
        self.assertEqual(df.loc[2, "status"], "fail")
        self.assertEqual(df.loc[2, "in.iq_step_a"], 3.0)
        # after the run's own verdict (4 ms end before the d step)
        self.assertRegex(df.loc[2, "error"], r"^run failed: target not reached; pass criterion "
                         r"'big': expression limit: \d+ \*\* 1000000000 would have more than "
                         r"4096 bits$")

    def test_evaluator(self):
        from mdtool.expr import Criterion, Expr, ExprLimit
        cases = [  # (text, values, the refusal)
            ("x ** y", {"x": 9, "y": 9 ** 9}, "9 ** 387420489 would have more than 4096 bits"),
            ("s * n", {"s": "a", "n": 10 ** 10}, "str * int: arithmetic takes numbers only"),
            ("s + s", {"s": "a"}, "str + str: arithmetic takes numbers only"),
            ("-s", {"s": "a"}, "a sign on str"),
            ("x * x", {"x": 2 ** 3000}, "an integer of more than 4096 bits"),
            ("round(x, n)", {"x": 5, "n": -10 ** 10}, "round's digits -10000000000"),
            ("floor(x) ** 5", {"x": 1e300}, "would have more than 4096 bits"),
        ]
        for text, env, why in cases:
            with self.subTest(text=text):
                with self.assertRaises(ExprLimit) as cm:
                    Expr("e", text).value(env)
                self.assertIn(why, str(cm.exception))
        # within the limits, the language is Python's
        self.assertEqual(Expr("e", "x ** 100 % 7").value({"x": 3}), 3 ** 100 % 7)
        self.assertEqual(Expr("e", "2 ** 4095 > x").value({"x": 1.0}), True)
        self.assertEqual(Expr("e", "law == 'pi2d'").value({"law": "pi2d"}), True)
        self.assertEqual(Expr("e", "round(x, 2)").value({"x": 1.2345}), 1.23)
        # a criterion the evaluator refuses fails, with the reason
        self.assertEqual(Criterion("c", "x ** y > 0").judge({"x": 3, "y": 10 ** 9}),
                         (False, "pass criterion 'c': expression limit: 3 ** 1000000000 would have "
                          "more than 4096 bits"))
        self.assertEqual(Criterion("c", "x > 0").judge({}), (False, None))  # a missing key
        # nesting is bounded when the expression is read, whatever the caller's stack
        self.assertEqual(Expr("e", "-" * 98 + "x").value({"x": 1}), 1)
        with self.assertRaises(ValueError) as cm:
            Expr("e", "-" * 101 + "x")
        self.assertIn("expression limit: nested deeper than 100", str(cm.exception))


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
    ("{head}\n[vars]\nx = [1.0]\n[derived]\niq_step_a = 'x + y'\n", 9,
     "derived iq_step_a reads y: not fixed, swept, a var or derived above it"),
    ("{head}\n[vars]\niq_step_a = [1.0]\n", 7, "var 'iq_step_a' is also a parameter"),
    ("{head}\n[vars]\nabs = [1.0]\n", 7, "var name 'abs'"),
    ("{head}\n[sweep]\niq_step_a = [1.0]\n[derived]\niq_step_a = '2.0'\n", 9,
     "'iq_step_a' is derived and also fixed, swept or a var"),
    ("{head}\n[derived]\niq_step_a = 2.0\n", 7, "must be an expression in a string"),
    ("{head}\n[derived]\nnot_a_key = '2.0'\n", 7, "unknown key 'not_a_key'"),
    ("{head}\n[derived]\niq_step_a = 'open(1)'\n", 7, "only calls to"),
    # the evaluator's limits (mdtool/expr.py): refused when the file is loaded
    ("{head}\n[pass]\nok = 'iq_rise_time_s < 9**9**9'\n", 7,
     "pass criterion 'ok': `9 ** 9 ** 9` fails: expression limit: 9 ** 387420489 would have "
     "more than 4096 bits"),
    ("{head}\n[derived]\niq_step_a = \"'a' * 10**10\"\n", 7,
     "derived iq_step_a: `'a' * 10 ** 10` fails: expression limit: str * int: arithmetic takes "
     "numbers only"),
    ("{head}\n[pass]\nok = '" + "1 + " * 300 + "1'\n", 7,
     "pass criterion 'ok': expression limit: longer than 1000 characters"),
    ("{head}\n[pass]\nok = 'iq_rise_time_s < 1 / 0'\n", 7, "`1 / 0` fails: division by zero"),
    # a range is bounded before it is expanded
    ("{head}\n[sweep]\niq_step_a = {{ start = 1.0, stop = 2.0, num = 4611686018427387904 }}\n", 7,
     "range for iq_step_a: num = 4611686018427387904: at most 1000000 points in a range"),
    ("{head}\n[sweep]\niq_step_a = {{ start = 1.0, stop = 2.0, num = 1000 }}\n"
     "current_bw_rad_s = {{ start = 1000.0, stop = 2000.0, num = 1000 }}\n"
     "id_step_a = {{ start = -1.0, stop = 0.0, num = 1000 }}\n", 6,
     "1000000000 runs: more than 100000000"),
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
                p = mdtool("sweep", path, "--out", out, "--serial", check=False, timeout=120)
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
