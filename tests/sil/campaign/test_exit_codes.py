#!/usr/bin/env python3
"""mdtool's campaign commands exit with their documented code every time
(labels campaign, sil), also at interpreter exit on a busy machine:

- `mdtool report` runs 50 times while a busy loop runs on each core: 25
  reports (exit 0) and 25 refused ones (an unknown --x: exit 2, right after
  the parts were read, when an Arrow thread would still be releasing them),
  on a campaign folder of 8 parts of 64 rows (the shipped
  commissioning-accuracy rows). Each exit code must be the documented one:
  before mdtool/parquet.py, pandas' reader made about 1 run in 20 of these
  abort at exit (134, "terminate called without an active exception");
- the cause, checked directly: in `mdtool sweep`, `report --with-results`
  and `rerun`, no Parquet read or write hands pyarrow anything but a path
  (a Python file object is what lets an Arrow thread need the interpreter
  at exit; apache/arrow#34314).

    test_exit_codes.py --mcsim PATH --root REPO --work DIR
"""
import argparse
import collections
import os
import shutil
import subprocess
import sys
import unittest

ARGS = None
RUNS = 50

# A busy loop that ends when this test process does: a test killed by
# ctest's timeout (SIGKILL, no finally) must not leave cores busy.
BUSY_WHILE_PARENT_LIVES = "import os\nparent = os.getppid()\nwhile os.getppid() == parent:\n    pass\n"

# Run in the subprocess before mdtool: every Parquet read and write must get
# a path; anything else (a Python file object) stops the command (exit 97).
GUARD = """\
import os, sys
import pyarrow.parquet as pq
def guarded(fn, pos, name):
    def call(*a, **kw):
        src = a[pos] if len(a) > pos else kw.get(name)
        if not isinstance(src, (str, os.PathLike)):
            sys.stderr.write(f"GUARD: pyarrow.parquet.{fn.__name__} got {type(src).__name__}\\n")
            sys.stderr.flush()
            os._exit(97)
        return fn(*a, **kw)
    return call
pq.read_table = guarded(pq.read_table, 0, "source")
pq.write_table = guarded(pq.write_table, 1, "where")
from mdtool.cli import main
sys.exit(main(sys.argv[1:]))
"""

TINY = """\
[campaign]
name = "exit-codes"
scenario = "current-step"
motor = "{root}/sim/motors/odrive-d5065.toml"
board = "{root}/sim/motors/odrive-v36-24v.toml"
duration_s = 0.004

[sweep]
iq_step_a = [2.0, 3.0, 4.0]

[pass]
fast = "iq_rise_time_ratio < 1.25"
"""


def mdtool(*argv, guard=False):
    pre = ["-c", GUARD] if guard else ["-m", "mdtool.cli"]
    return subprocess.run([sys.executable, *pre, *argv], capture_output=True, text=True,
                          timeout=300)


class ReportUnderLoad(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        import pyarrow.parquet as pq
        cls.out = os.path.join(ARGS.work, "campaign")
        shutil.rmtree(cls.out, ignore_errors=True)
        os.makedirs(os.path.join(cls.out, "parts"))
        rows = pq.read_table(os.path.join(ARGS.root, "tools/mdtool/campaigns/results/"
                                          "commissioning-accuracy/results.parquet"))
        for i in range(0, rows.num_rows, 64):
            pq.write_table(rows.slice(i, 64), os.path.join(cls.out, "parts", f"part-{i:09d}.parquet"))

    def test_report_50_times_both_cores_busy(self):
        rep = os.path.join(ARGS.work, "report")
        good = ["report", self.out, "--x", "in.motor.pole_pairs", "--y", "in.motor.flux_wb",
                "--metric", "pass_rate", "--report-dir", rep]
        refused = ["report", self.out, "--x", "no_such", "--report-dir", rep]
        busy = [subprocess.Popen([sys.executable, "-c", BUSY_WHILE_PARENT_LIVES])
                for _ in range(os.cpu_count() or 2)]
        got = collections.Counter()
        bad = []
        try:
            for i in range(RUNS):
                argv, want = (good, 0) if i % 2 == 0 else (refused, 2)
                p = mdtool(*argv)
                got[(want, p.returncode)] += 1
                if p.returncode != want:
                    bad.append(f"run {i}: exit {p.returncode}, not {want}: {p.stderr.strip()[-200:]}")
        finally:
            for b in busy:
                b.kill()
                b.wait()
        print(f"report x {RUNS}, {len(busy)} busy loops: (wanted, got) -> runs {dict(got)}")
        self.assertEqual(bad, [])
        self.assertTrue(os.path.exists(os.path.join(rep, "envelope.png")))


class OnlyPathsReachPyarrow(unittest.TestCase):
    def test_sweep_report_rerun(self):
        path = os.path.join(ARGS.work, "tiny.toml")
        with open(path, "w") as f:
            f.write(TINY.format(root=ARGS.root))
        out = os.path.join(ARGS.work, "tiny")
        shutil.rmtree(out, ignore_errors=True)
        for argv in (["sweep", path, "--out", out, "--serial", "--chunk", "1", "--quiet"],
                     ["sweep", path, "--out", out, "--serial", "--quiet"],  # resume: reads parts
                     ["report", out, "--with-results", "--report-dir", os.path.join(out, "rep")],
                     ["rerun", out, "1"]):
            with self.subTest(argv=argv[0]):
                p = mdtool(*argv, guard=True)
                self.assertNotIn("GUARD", p.stderr)
                self.assertEqual(p.returncode, 0, p.stderr[-400:])


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
