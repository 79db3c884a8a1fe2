#!/usr/bin/env python3
"""mdtool.sil against `mcsim run`, bit for bit (labels campaign, sil).

    test_sil_binding.py --mcsim PATH --root REPO --work DIR

The binding returns the doubles that mcsim prints: formatted as mcsim
formats them (%.9g per CSV cell, 10 significant digits in the JSON, "null"
for non-finite), they give mcsim's files byte for byte. Errors: the
exception's text is what mcsim prints after "mcsim: ", and its class
follows mcsim's exit code (2: UsageError, 1: RunFailed).
"""
import argparse
import math
import os
import subprocess
import sys
import unittest

import numpy as np

from mdtool import sil

ARGS = None
M = "sim/motors/odrive-d5065.toml"
B = "sim/motors/odrive-v36-24v.toml"


def c_g(v, digits):
    """printf("%.<digits>g") as glibc prints it (NaN keeps its sign)."""
    if math.isnan(v):
        return "-nan" if math.copysign(1.0, v) < 0 else "nan"
    return "%.*g" % (digits, v)


def csv_text(r):
    lines = [",".join(r.columns)]
    lines += [",".join(c_g(float(v), 9) for v in row) for row in r.data]
    return "\n".join(lines) + "\n"


def json_text(summary, objects=None):
    """mcsim::Summary::to_json: texts, then numbers, each sorted by key, then
    the nested objects by name (their numbers are also in `summary` as
    "OBJECT.KEY": those are left out of the numbers)."""
    def s(x):
        return '"' + x.replace("\\", "\\\\").replace('"', '\\"') + '"'

    def num(v):
        return c_g(v, 10) if math.isfinite(v) else "null"
    objects = objects or {}
    flat = {f"{o}.{k}" for o, kv in objects.items() for k in kv}
    texts = sorted((k, v) for k, v in summary.items() if isinstance(v, str))
    nums = sorted((k, v) for k, v in summary.items() if not isinstance(v, str) and k not in flat)
    items = [f"{s(k)}: {s(v)}" for k, v in texts]
    items += [f"{s(k)}: {num(v)}" for k, v in nums]
    items += [f"{s(o)}: {{" + ", ".join(f"{s(k)}: {num(v)}" for k, v in sorted(kv.items())) + "}"
              for o, kv in sorted(objects.items())]
    return "{" + ",".join("\n  " + i for i in items) + "\n}\n"


def mcsim(scenario, out, motor=None, board=None, params=None, duration=None):
    argv = [ARGS.mcsim, "run", scenario, "--out", out]
    if motor:
        argv += ["--motor", motor]
    if board:
        argv += ["--board", board]
    for k, v in (params or {}).items():
        argv += ["--set", f"{k}={sil._value(v)}"]
    if duration is not None:
        argv += ["--duration", repr(duration)]
    return subprocess.run(argv, capture_output=True, text=True, timeout=300, cwd=ARGS.root)


class BitForBit(unittest.TestCase):
    n = 0

    def same(self, scenario, motor=None, board=None, params=None, duration=None):
        BitForBit.n += 1
        out = os.path.join(ARGS.work, f"run{BitForBit.n}")
        p = mcsim(scenario, out, motor, board, params, duration)
        # A run that fails its verdict (a short one: exit 1) is compared too:
        # the binding returns the same rows and summary with the same error.
        self.assertIn(p.returncode, (0, 1), p.stderr)
        r = sil.run_raw(scenario, motor=motor, board=board, params=params, duration=duration)
        self.assertEqual(r.error_kind is None, p.returncode == 0, p.stderr)
        if r.error:
            self.assertEqual(p.stderr, f"mcsim: {r.error}\n")
        ext = ".csv" if p.returncode == 0 else ".partial.csv"
        with open(os.path.join(out, scenario + ext)) as f:
            self.assertEqual(csv_text(r), f.read())
        with open(os.path.join(out, scenario + ".json")) as f:
            self.assertEqual(json_text(r.summary, r.objects), f.read())
        df = r.trajectory
        self.assertEqual(list(df.columns), r.columns)
        self.assertEqual(df.shape, r.data.shape)
        self.assertEqual(r.summary["rows"], len(df))
        return r

    def test_current_step_defaults(self):
        r = self.same("current-step", M, B)
        self.assertGreater(len(r.data), 100)

    def test_current_step_params(self):
        self.same("current-step", M, B, {"iq_step_a": 3.3, "id_step_a": -1.1, "csv_every": 2,
                                          "current_bw_rad_s": 1234.5678})

    def test_sensorless_short(self):
        self.same("sensorless-speed-step", M, B, {"load_frac": 0.1}, duration=0.05)

    def test_own_motor_scenario(self):
        self.same("foc-current-step", duration=0.01)

    def test_commission_objects(self):
        # The nested objects ("identified", "true", "error") byte for byte,
        # and as dotted keys in the summary (what campaigns read).
        m = "sim/motors/paper002-40kw.toml"
        r = self.same("commission", m, m, {"encoder_direction": -1, "seed": 7, "verify": 1})
        self.assertEqual(set(r.objects), {"identified", "true", "error"})
        for name, kv in r.objects.items():
            for k, v in kv.items():
                self.assertEqual(r.summary[f"{name}.{k}"], v)
        # The error object is the identified against the true value.
        self.assertEqual(r.summary["error.r_frac"],
                         r.summary["identified.r_ohm"] / r.summary["true.r_ohm"] - 1)
        self.assertEqual(r.summary["error.pole_pairs_diff"],
                         r.summary["identified.pole_pairs"] - r.summary["true.pole_pairs"])
        self.assertEqual(r.summary["error.direction_wrong"], 0.0)
        self.assertEqual(r.summary["true.encoder_direction"], -1.0)
        # verify=1 ran both laws on the identified values (this non-salient
        # motor is one the sensorless law takes).
        self.assertTrue(math.isfinite(r.summary["verify.sensorless_speed_err_frac"]))
        self.assertEqual(r.summary["verify.sensorless_faulted"], 0.0)
        self.assertEqual(r.summary["verify.sensored_faulted"], 0.0)

    def test_commission_seed_changes_noise(self):
        m = "sim/motors/paper002-40kw.toml"
        a = sil.run("commission", m, m, {"seed": 1})
        b = sil.run("commission", m, m, seed=2)
        self.assertEqual(b.summary["param.seed"], 2.0)
        self.assertNotEqual(a.summary["identified.r_ohm"], b.summary["identified.r_ohm"])
        self.assertEqual(a.summary["true.r_ohm"], b.summary["true.r_ohm"])

    def test_build_type_named(self):
        # bench-sil records it: a Debug build runs several times slower.
        self.assertIn(sil.BUILD_TYPE, ("Debug", "Release", "RelWithDebInfo", "MinSizeRel"))

    def test_deterministic_in_process(self):
        # (a 4 A step on the D5065 fails its verdict: the board's dead time
        # slows it past 25 % of the design; the runs are the same anyway)
        a = sil.run_raw("current-step", M, B, {"iq_step_a": 4.0})
        b = sil.run_raw("current-step", M, B, {"iq_step_a": 4.0})
        self.assertTrue(np.array_equal(a.data, b.data))
        self.assertEqual(a.summary, b.summary)


class Errors(unittest.TestCase):
    def same_error(self, scenario, motor=None, board=None, params=None, duration=None):
        out = os.path.join(ARGS.work, "err")
        p = mcsim(scenario, out, motor, board, params, duration)
        self.assertIn(p.returncode, (1, 2), p.stderr)
        with self.assertRaises(sil.UsageError if p.returncode == 2 else sil.RunFailed) as cm:
            sil.run(scenario, motor=motor, board=board, params=params, duration=duration)
        self.assertEqual(p.stderr, f"mcsim: {cm.exception}\n")
        return cm.exception

    def test_unknown_scenario(self):
        self.same_error("no-such-scenario")

    def test_unknown_key(self):
        self.same_error("current-step", M, B, {"no_such_key": 1})

    def test_malformed_value(self):
        self.same_error("current-step", M, B, {"iq_step_a": "abc"})

    def test_out_of_range(self):
        self.same_error("current-step", M, B, {"iq_step_a": 1e9})

    def test_missing_motor(self):
        self.same_error("current-step")

    def test_own_motor_refuses_motor(self):
        self.same_error("foc-current-step", M, B)

    def test_bad_motor_file(self):
        bad = os.path.join(ARGS.work, "bad.toml")
        with open(bad, "w") as f:
            f.write('[motor]\nname = "x"\nr_ohm = "one"\n')
        e = self.same_error("current-step", bad, B)
        self.assertIn("bad.toml:3:", str(e))

    def test_refused_at_run_time(self):
        e = self.same_error("sensorless-speed-step", M, B, {"obs_omega_crit_m_rad_s": 1000})
        self.assertIsNotNone(e.summary)

    def test_verdict_not_a_pass(self):
        # 30 ms of a speed step: cut before the slew ends. mcsim exits 1
        # with its verdict; the binding raises RunFailed with the same
        # message, and run_raw returns it as error_kind "verdict".
        e = self.same_error("speed-step", M, B, duration=0.03)
        self.assertIsInstance(e, sil.RunFailed)
        self.assertEqual(e.summary["verdict"], "target not reached")
        r = sil.run_raw("speed-step", M, B, duration=0.03)
        self.assertEqual(r.error_kind, "verdict")
        self.assertIn("the end of the speed slew", r.summary["verdict_detail"])
        self.assertEqual(sil.run("speed-step", M, B).summary["verdict"], "pass")

    def test_duration_bounded(self):
        self.same_error("speed-step", M, B, duration=1e300)
        self.same_error("commission", M, B, duration=1.0)

    def test_drive_fault(self):
        # a current-loop bandwidth the parameter table does not allow (at
        # most 0.3 pwm_hz: 7.2 kHz on this 24 kHz board) is refused before
        # the run, the reason named
        e = self.same_error("current-step", M, B, {"iq_step_a": 50, "current_bw_rad_s": 15000},
                            duration=0.01)
        self.assertIsInstance(e, sil.UsageError)
        self.assertIn("MC_PARAMS_ERR BANDWIDTH", str(e))
        # the drive told 20 times the motor's inductance: its current loop's
        # gain 20 times too high, the q step trips the drive
        e = self.same_error("current-step", M, B, {"iq_step_a": 50, "model_l_scale": 20},
                            duration=0.01)
        self.assertIsInstance(e, sil.RunFailed)
        self.assertIn("OVERCURRENT", str(e))
        self.assertEqual(e.summary["verdict"], "faulted: OVERCURRENT")
        self.assertEqual(e.summary["faults"] > 0, True)
        self.assertGreater(len(e.trajectory), 0)


def main():
    global ARGS
    ap = argparse.ArgumentParser()
    ap.add_argument("--mcsim", required=True)
    ap.add_argument("--root", required=True)
    ap.add_argument("--work", required=True)
    ARGS, rest = ap.parse_known_args()
    ARGS.mcsim = os.path.abspath(ARGS.mcsim)
    ARGS.work = os.path.abspath(ARGS.work)
    os.makedirs(ARGS.work, exist_ok=True)
    os.chdir(ARGS.root)  # relative motor paths, as in mcsim's messages
    unittest.main(argv=[sys.argv[0], *rest], verbosity=2)


if __name__ == "__main__":
    main()
