#!/usr/bin/env python3
"""The documents' measured tables, generated from the tests' and benchmarks'
machine-readable output.

    gen_docs.py write --inputs FILE [--input NAME=PATH ...] [--only FIG ...] [--figures]
    gen_docs.py check --inputs FILE [--input NAME=PATH ...] [--jobs N]
    gen_docs.py links
    gen_docs.py list

Every measured table in a README.md sits in a marked region

    <!-- gen:NAME -->
    ...generated...
    <!-- /gen:NAME -->

and NAME is one of the FIGURES below: what it runs (an `mcsim run`, a
GoogleTest binary with --gtest_output=json whose tests record their measured
values with mc_record(), the instruction-count benchmarks under QEMU, or a
source file the table is derived from), how it renders, and the tolerance a
fresh run may differ by, with its reason.

`write` runs the sources and rewrites the regions (with --figures also the
committed PNGs; with --only only the PNGs of those names). `check` runs them afresh and fails when a region disagrees
with the fresh rendering beyond the figure's tolerance, when a region is
missing, unknown or duplicated, or when a relative link or a backquoted
source path in any README.md names nothing (`links` runs only that part).
The inputs (the build's binaries and QEMU) are listed by CMake in
build/host/tools/docs/inputs.txt: the `docs` target writes, the `docs.check`
test (label docs) checks; see tools/docs/CMakeLists.txt.
"""

import argparse
import concurrent.futures
import csv
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import threading
import tomllib

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
SKIP_DIRS = {".git", "build", ".venv", "out", ".cache", "node_modules", "__pycache__"}
GEN_RE = re.compile(r"<!-- gen:([a-z0-9-]+) -->\n(.*?)<!-- /gen:\1 -->", re.DOTALL)
GEN_OPEN_RE = re.compile(r"<!-- gen:([a-z0-9-]+) -->")
NUM_RE = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")
TOP_DIRS = ("firmware/", "hal/", "sim/", "tests/", "tools/", ".ci/")

# The tolerances, with their reasons (tools/docs/README.md says more).
EXACT = "exactly (deterministic runs)"
EXACT_QEMU = "exactly (QEMU -icount counts instructions deterministically)"


class DocError(Exception):
    pass


def read_text(path):
    with open(path, encoding="utf-8") as fh:
        return fh.read()


# ---------------------------------------------------------------------------
# Sources: the runs a table is made from, each run once and shared.

class Src:
    def __init__(self, key, label, fn):
        self.key, self.label, self.fn = key, label, fn

    def __hash__(self):
        return hash(self.key)

    def __eq__(self, other):
        return self.key == other.key


class Ctx:
    def __init__(self, inputs, jobs):
        self.inputs = inputs
        self.jobs = jobs
        self.cache = {}
        self.lock = threading.Lock()
        self.tmp = tempfile.TemporaryDirectory(prefix="gen_docs_")

    def input(self, name):
        p = self.inputs.get(name)
        if not p:
            raise DocError(f"input '{name}' not given (--input {name}=PATH)")
        if not os.path.exists(p):
            raise DocError(f"input '{name}': {p} does not exist (build first)")
        return p

    def workdir(self, key):
        d = os.path.join(self.tmp.name, re.sub(r"[^A-Za-z0-9_.-]+", "_", repr(key))[:120])
        os.makedirs(d, exist_ok=True)
        return d

    def get(self, src):
        with self.lock:
            if src.key in self.cache:
                return self.cache[src.key]
        val = src.fn(self)
        with self.lock:
            self.cache[src.key] = val
        return val

    def prefetch(self, srcs):
        todo = list(dict.fromkeys(srcs))
        with concurrent.futures.ThreadPoolExecutor(max_workers=self.jobs) as ex:
            futs = {ex.submit(self.get, s): s for s in todo}
            for f in concurrent.futures.as_completed(futs):
                f.result()


def run(cmd, cwd=ROOT, timeout=900, ok=(0,)):
    p = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=timeout, check=False)
    if p.returncode not in ok:
        raise DocError(f"{' '.join(cmd)} exited {p.returncode}:\n{p.stdout[-2000:]}{p.stderr[-2000:]}")
    return p.stdout


def mcsim_cmd(scenario, sets=(), motor=None, board=None):
    """The command as a reader types it."""
    c = f"mcsim run {scenario}"
    if motor:
        c += f" --motor sim/motors/{motor}.toml"
    if board:
        c += f" --board sim/motors/{board}.toml"
    for s in sets:
        c += f" --set {s}"
    return c


def mcsim(scenario, *sets, motor=None, board=None, judged=True):
    """`mcsim run`: its JSON summary and its CSV (a list of dicts of floats).
    judged=False: a run the table shows whatever its verdict (mcsim exits 1
    when it is not a pass, the rows then in <scenario>.partial.csv); the
    summary's verdict says which. Otherwise a failed verdict is an error."""
    def fn(ctx):
        out = ctx.workdir(("mcsim", scenario, sets, motor, board))
        cmd = [ctx.input("mcsim"), "run", scenario, "--out", out]
        if motor:
            cmd += ["--motor", os.path.join(ROOT, "sim", "motors", motor + ".toml")]
        if board:
            cmd += ["--board", os.path.join(ROOT, "sim", "motors", board + ".toml")]
        for s in sets:
            cmd += ["--set", s]
        run(cmd, ok=(0,) if judged else (0, 1))
        with open(os.path.join(out, scenario + ".json")) as f:
            summary = json.load(f)
        path = os.path.join(out, scenario + ".csv")
        if not os.path.exists(path):
            path = os.path.join(out, scenario + ".partial.csv")
        with open(path, newline="") as f:
            rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]
        return {"summary": summary, "rows": rows, "csv": path}
    return Src(("mcsim", scenario, sets, motor, board, judged), mcsim_cmd(scenario, sets, motor, board),
               fn)


def gtest(binary, filt="*"):
    """A GoogleTest binary with --gtest_output=json: per test, its result and
    the properties it recorded (mc_record: value, and `key.bound`)."""
    def fn(ctx):
        out = os.path.join(ctx.workdir(("gtest", binary, filt)), "out.json")
        exe = ctx.input(binary)
        p = subprocess.run([exe, f"--gtest_filter={filt}", f"--gtest_output=json:{out}"],
                           cwd=os.path.dirname(exe), capture_output=True, text=True, timeout=900,
                           check=False)
        if p.returncode != 0 or not os.path.exists(out):
            raise DocError(f"{binary} --gtest_filter={filt} failed (exit {p.returncode}): "
                           "a table is never made from a failing test\n" + p.stdout[-3000:])
        with open(out) as f:
            js = json.load(f)
        tests = {}
        meta = {"name", "status", "result", "timestamp", "time", "classname", "file", "line",
                "failures", "value_param", "type_param"}
        for suite in js["testsuites"]:
            for t in suite["testsuite"]:
                props = {}
                for k, v in t.items():
                    if k in meta:
                        continue
                    try:
                        props[k] = float(v)
                    except (TypeError, ValueError):
                        props[k] = v
                tests[suite["name"] + "." + t["name"]] = props
        return tests
    return Src(("gtest", binary, filt), f"{binary} --gtest_filter='{filt}'", fn)


def bench_m4f():
    def fn(ctx):
        out = os.path.join(ctx.workdir(("bench_m4f",)), "bench.json")
        run([sys.executable, os.path.join(ROOT, "tools", "bench", "run_bench.py"),
             "--qemu", ctx.input("qemu"), "--elf", ctx.input("bench_m4f_elf"), "--out", out])
        with open(out) as f:
            return json.load(f)
    return Src(("bench_m4f",), "ctest -R target.bench_m4f", fn)


ISR_BOARDS = ("example", "odrive36", "vesc6")


def isr_images(name, runner, extra_inputs=()):
    """A runner over the interrupt benchmark images of every ISR board
    (run_isr_bench.py, run_isr_profile.py): its JSON report."""
    def fn(ctx):
        out = os.path.join(ctx.workdir((name,)), name + ".json")
        cmd = [sys.executable, os.path.join(ROOT, "tools", "bench", runner),
               "--qemu", ctx.input("qemu"), "--out", out]
        for flag, key in extra_inputs:
            cmd += [flag, ctx.input(key)]
        for b in ISR_BOARDS:
            cmd += ["--elf", f"{b}={ctx.input(f'bench_isr_{b}_elf')}"]
        run(cmd)
        with open(out) as fh:
            return json.load(fh)
    return Src((name,), f"ctest -R target.{name}", fn)


def bench_isr():
    return isr_images("bench_isr", "run_isr_bench.py")


def isr_profile():
    return isr_images("isr_profile", "run_isr_profile.py",
                      (("--nm", "arm_nm"), ("--addr2line", "arm_addr2line")))


def bench_q31(cpu):
    machine = {"m3": "netduino2", "m4f": "netduinoplus2"}[cpu]

    def fn(ctx):
        out = os.path.join(ctx.workdir(("q31", cpu)), "q31.json")
        run([sys.executable, os.path.join(ROOT, "tests", "target", "q31", "run_q31_bench.py"),
             ctx.input("qemu"), machine, ctx.input(f"q31_bench_{cpu}_elf"), "--out", out])
        with open(out) as f:
            return json.load(f)
    return Src(("q31", cpu), f"ctest -R target.q31.bench_{cpu}", fn)


def mc_can(*args):
    def fn(_ctx):
        return run([sys.executable, os.path.join(ROOT, "tools", "can", "mc_can.py")] + list(args))
    return Src(("mc_can",) + args, "mc_can.py " + " ".join(args), fn)



# ---------------------------------------------------------------------------
# Formatting

def g(x, sig=3):
    """x to sig significant digits, plain ASCII (no thousands separator)."""
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    if x == 0:
        return "0"
    s = f"{x:.{sig}g}"
    if "e" in s:
        m, e = s.split("e")
        s = f"{m}e{int(e)}"
    return s


def f(x, nd):
    return "-" if x is None or math.isnan(x) else f"{x:.{nd}f}"


def table(head, rows, align=None):
    out = ["| " + " | ".join(head) + " |",
           "|" + "|".join(align or ["---"] * len(head)) + "|"]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(out)


def source_line(fig, labels):
    shown = ", ".join(f"`{lab}`" for lab in labels[:3 if len(labels) > 4 else 4]) or "source files only"
    if len(labels) > 4:
        shown += f" and {len(labels) - 3} more runs of the same kind"
    return (f"<sub>Generated by `tools/docs/gen_docs.py` ({fig.name}) from {shown}; "
            f"checked by `docs.check`, {fig.reason}.</sub>")


def prop(tests, test, key):
    t = tests.get(test)
    if t is None:
        raise DocError(f"test {test} did not run")
    if key not in t:
        raise DocError(f"test {test} recorded no '{key}' (mc_record)")
    return t[key]


# ---------------------------------------------------------------------------
# Figures

FIGURES = {}


class Figure:
    """A table: its sources, its renderer, and the tolerance (absolute,
    relative) a fresh run may differ by, number by number, with the reason."""

    def __init__(self, name, needs, render, reason, tol):
        self.name, self.needs, self.render = name, needs, render
        self.reason, self.tol = reason, tol


def figure(name, needs, reason=EXACT, tol=(0.0, 0.0)):
    def deco(fn):
        FIGURES[name] = Figure(name, needs, fn, reason, tol)
        return fn
    return deco


def _run_figure(fig, ctx):
    srcs = fig.needs() if callable(fig.needs) else fig.needs
    body = fig.render(ctx, *[ctx.get(s) for s in srcs])
    return body.rstrip("\n") + "\n\n" + source_line(fig, [s.label for s in srcs]) + "\n"


# --- FOC current loop --------------------------------------------------------

FOC_RISE = [("200", "0"), ("200", "1"), ("500", "1")]


def _foc_rise_srcs():
    return [mcsim("foc-current-step", f"bw_hz={bw}", f"delay_periods={d}") for bw, d in FOC_RISE]


@figure("foc-rise", _foc_rise_srcs)
def _foc_rise(ctx, *runs):
    rows = []
    for r in runs:
        s = r["summary"]
        bw, d, pwm = s["param.bw_hz"], s["param.delay_periods"], s["param.pwm_hz"]
        rows.append([f"{bw:g} Hz", f(2 * math.pi * bw / pwm, 3), f"{d:g}",
                     f(s["iq_rise_time_ratio"], 2), f(s["id_rise_time_ratio"], 2)])
    return table(["bw", "bw·T", "delay [periods]", "q rise / ln(9)/bw", "d rise / ln(9)/bw"], rows)


# --- MCU instruction counts ------------------------------------------------

@figure("mcu-targets", [bench_m4f()], reason=EXACT_QEMU)
def _mcu_targets(ctx, b):
    rows = []
    cases = {(c["name"], c["format"]): c for c in b["cases"]}
    for t in b["targets"]:
        c = cases.get((t["name"], t["format"]))
        rows.append([t["what"], f"{t['instr_mean']:g}", f"{t['instr_min']} / {t['instr_max']}",
                     f"{c['time_us_at_168mhz']:g}", f"{c['cpu_load_pct_at_20khz']:g} %",
                     str(t["target_instr"]),
                     "met" if t["met"] else f"**not met** (max {t['instr_max']})"])
    return table(["step (f32, -O2)", "instructions, mean", "min / max", "µs @168 MHz",
                  "load @20 kHz", "target (max)", "target"], rows,
                 ["---", "---:", "---:", "---:", "---:", "---:", "---"])


@figure("mcu-kernels", [bench_m4f()], reason=EXACT_QEMU)
def _mcu_kernels(ctx, b):
    rows = []
    for c in b["cases"]:
        rows.append([f"`{c['name']}`", c["format"], f"{c['instr_mean']:g}",
                     f"{c['instr_min']} / {c['instr_max']}", f"{c['time_us_at_168mhz']:g}",
                     f"{c['cpu_load_pct_at_20khz']:g} %"])
    return table(["case", "format", "instructions, mean", "min / max", "µs @168 MHz",
                  "load @20 kHz"], rows, ["---", "---", "---:", "---:", "---:", "---:"])


@figure("mcu-isr", [bench_isr()], reason=EXACT_QEMU)
def _mcu_isr(ctx, b):
    rows = []
    for bd in b["boards"]:
        for run, r in bd["runs"].items():
            isr, sd = r["isr"], r["isr_slow_due"]
            l20, l40 = r["load_pct"]["20khz"], r["load_pct"]["40khz"]
            rows.append([bd["board"], run, f"{isr['mean']:g}", str(isr["max"]), str(sd["max"]),
                         f"{l20['cpi1_mean']:g} % / {l20['est_max']:g} %",
                         f"{l40['cpi1_mean']:g} % / {l40['est_max']:g} %",
                         str(r["target_instr"]),
                         "met" if r["met"] else f"**not met** (max {isr['max']})"])
    return table(["board", "run", "instructions, mean", "max", "max, slow loop pended",
                  "load @20 kHz (mean, 1 cyc/instr / max, est.)",
                  "load @40 kHz (mean, 1 cyc/instr / max, est.)", "target (max)", "target"],
                 rows, ["---", "---", "---:", "---:", "---:", "---:", "---:", "---:", "---"])


@figure("mcu-isr-parts", [bench_isr()], reason=EXACT_QEMU)
def _mcu_isr_parts(ctx, b):
    rows = []
    for bd in b["boards"]:
        for run, r in bd["runs"].items():
            p = r["parts"]
            rows.append([bd["board"], run, f"{p['adc_read']['mean']:g}",
                         f"{p['encoder_read']['mean']:g}", f"{p['law']['mean']:g}",
                         f"{p['foc']['mean']:g}",
                         f"{p['duties_write']['mean']:g}", f"{p['app_mark']['mean']:g}",
                         f"{r['drive_rest_mean']:g}", f"{r['isr']['mean']:g}",
                         "—" if r.get("brake_write") is None else f"{r['brake_write']['mean']:g}",
                         "—" if r.get("cog_lookup") is None else
                         f"{r['cog_lookup']['mean']:g} / {r['cog_series']['mean']:g} / "
                         f"{r['isr_anticogging']['mean']:g} / {r['cog_series_init']['mean']:g}"])
    return table(["board", "run", "ADC read", "encoder read", "speed law", "FOC step",
                  "duties write", "app mark",
                  "drive rest (checks, encoder tracking, reference shaping, dead-time "
                  "compensation, supervision, hooks)", "whole interrupt",
                  "brake write (brake_enable 1 adds it; not in this run)",
                  "anticogging: feed-forward from the bins / from the series (8 terms) / "
                  "whole interrupt with the series on (the interrupt before: off) / the "
                  "series' derivation when a map is attached (slow context, once)"], rows,
                 ["---", "---", "---:", "---:", "---:", "---:", "---:", "---:", "---:", "---:",
                  "---:", "---:"])


ISR_PROFILE_BOARD = "odrive36"
ISR_PROFILE_MIN = 8  # functions below this in both runs are summed in one row


@figure("mcu-isr-profile", [isr_profile()], reason=EXACT_QEMU)
def _mcu_isr_profile(ctx, p):
    bd = next(b for b in p["boards"] if b["board"] == ISR_PROFILE_BOARD)
    runs = list(bd["runs"])
    per = {}
    for run in runs:
        for x in bd["runs"][run]["self"]:
            per.setdefault((x["function"], x["file"]), {})[run] = x["instr"]
    order = sorted(per, key=lambda k: (-sum(per[k].values()), k))
    rows, rest, n_rest = [], dict.fromkeys(runs, 0), 0
    for k in order:
        if max(per[k].values()) >= ISR_PROFILE_MIN:
            rows.append([f"`{k[0]}`", f"`{k[1]}`"] + [str(per[k].get(r, 0)) for r in runs])
        else:
            n_rest += 1
            for r in runs:
                rest[r] += per[k].get(r, 0)
    rows.append([f"the other {n_rest} functions (under {ISR_PROFILE_MIN} each)", ""] +
                [str(rest[r]) for r in runs])
    rows.append(["**whole interrupt** (one period, stepped)", ""] +
                [f"**{bd['runs'][r]['instructions']}**" for r in runs])
    return table(["function (its own instructions, with the header helpers inlined into it)",
                  "file"] + runs, rows, ["---", "---"] + ["---:"] * len(runs))


@figure("mcu-cpu-budget", [bench_isr()], reason=EXACT_QEMU)
def _mcu_cpu_budget(ctx, b):
    rows = []
    for bd in b["boards"]:
        for run, x in bd["budget"].items():
            r = bd["runs"][run]
            ld, rt, dl = x["load_pct"], x["response_us"], x["deadline_us"]
            rows.append([bd["board"], run,
                         f"{r['isr']['max']} → {ld['fast']:g} % · {rt['fast']:g} / {dl['fast']:g} µs",
                         f"{r['can_rx']['max']} → {ld['can_rx']:g} % · {rt['can_rx']:g} / "
                         f"{dl['can_rx']:g} µs",
                         f"{r['slow_full_ring']['max']} → {ld['slow']:g} % · {rt['slow']:g} / "
                         f"{dl['slow']:g} µs",
                         f"{x['total_pct']:g} %", "all met" if x["deadlines_met"] else "**missed**",
                         f"{bd['filter']['filter_pass_ids']} ({bd['filter']['filter_pass_own_ids']})"])
    return table(["board", "run",
                  "fast interrupt, 40 kHz: max instr → load · response / deadline",
                  f"CAN rx interrupt per frame, {b['boards'][0]['budget']['sensored']['can_frame_hz']:g}"
                  " frames/s: max instr → load · response / deadline",
                  "slow loop, 1 kHz, 16 frames + telemetry: max instr → load · response / deadline",
                  "total load", "deadlines", "ids of 2048 the node filter passes (this node's)"],
                 rows, ["---", "---", "---:", "---:", "---:", "---:", "---", "---:"])


IMAGE_BOARDS = ("example", "odrive36", "odrive36_24v", "vesc6")


def f405_flash_max():
    """The drive image's flash budget, from the CMakeLists that enforces it."""
    text = read_text(os.path.join(ROOT, "firmware", "targets", "stm32f405", "CMakeLists.txt"))
    m = re.search(r"set\(MC_F405_FLASH_MAX (\d+)\)", text)
    if not m:
        raise DocError("firmware/targets/stm32f405/CMakeLists.txt: no MC_F405_FLASH_MAX")
    return int(m.group(1))


def image_flash():
    """Each board's drive image (its preset's build, tests/target): flash
    bytes as size_report.cmake counts them (sections in flash, plus the
    .data initialisers)."""
    def fn(ctx):
        res = {}
        for b in IMAGE_BOARDS:
            out = run([ctx.input("arm_size"), "-A", "-d", ctx.input(f"image_{b}_elf")])
            flash = 0
            for line in out.splitlines():
                m = re.match(r"^([.A-Za-z_]\S*)\s+(\d+)\s+(\d+)", line)
                if not m:
                    continue
                sec, size, addr = m.group(1), int(m.group(2)), int(m.group(3))
                if 0x08000000 <= addr < 0x08100000 or (sec == ".data" and
                                                         0x20000000 <= addr < 0x20020000):
                    flash += size
            res[b] = flash
        return res
    return Src(("image_flash",), "cmake --build --preset stm32f405[-<board>]", fn)


@figure("mcu-flash", [image_flash()])
def _mcu_flash(ctx, sizes):
    cap = f405_flash_max()
    rows = [[b, str(n), str(cap - n), f"{(cap - n) / 1024:.1f} KiB"] for b, n in sizes.items()]
    return table(["board", "flash, bytes", f"headroom to {cap} B", "headroom"],
                 rows, ["---", "---:", "---:", "---:"])


# --- PI2D ----------------------------------------------------------------------

@figure("pi2d-sampled", [gtest("test_pi2d_sil", "Pi2dPaper.SampledFirmwareLawMatchesContinuousClosedLoop")])
def _pi2d_sampled(ctx, t):
    n = "Pi2dPaper.SampledFirmwareLawMatchesContinuousClosedLoop"
    x3, x2 = prop(t, n, "x3_err_10khz"), prop(t, n, "x2_err_10khz")
    return table(["max \\|SIL − continuous\\| at 10 kHz", "measured", "test bound"], [
        ["speed x3", g(x3, 2), g(prop(t, n, "x3_err_10khz.bound"), 2)],
        ["current x2 (at the reference's corners)", g(x2, 2), g(prop(t, n, "x2_err_10khz.bound"), 2)],
        ["speed error at 10 kHz / at 20 kHz", g(prop(t, n, "x3_err_ratio_10_over_20khz"), 3),
         "1.6 … 2.4"]])


@figure("pi2d-certificate", [mcsim("pi2d-certificate")])
def _pi2d_cert(ctx, r):
    names = {"34": "(34), re-derived", "34.1": "(34), as printed",
             "38": "(38), re-derived", "38.1": "(38), as printed"}
    rows = []
    for row in r["rows"]:
        c = f"{row['condition']:g}"
        rows.append([names.get(c, c), g(row["lhs"], 4), g(row["rhs"], 4), g(row["margin"], 4),
                     "holds" if row["margin"] >= 0 else "fails"])
    return table(["condition", "left side", "right side", "margin", ""], rows)


@figure("pi2d-motor", [mcsim("pi2d-motor")])
def _pi2d_motor(ctx, r):
    s = r["summary"]
    m = [("RMS speed error [rad/s]", "rms_speed_error_rad_s", 3),
         ("peak speed error [rad/s]", "peak_speed_error_rad_s", 4),
         ("peak current [A]", "peak_current_a", 3),
         ("settling after the load step (1 %) [s]", "settling_after_load_s", 3),
         ("faults", "faults", 1)]
    return table(["metric", "PI²D", "PI cascade"],
                 [[lab, g(s["pi2d." + k], sg), g(s["cascade." + k], sg)] for lab, k, sg in m])


# --- Sensorless (observer) -------------------------------------------------------

@figure("obs-tuning", [mcsim("observer-test-motor"), mcsim("observer-table1")])
def _obs_tuning(ctx, a, b):
    rows = []
    for lab, r in (("0.3 kW test motor (`observer-test-motor`)", a),
                   ("40 kW machine (`observer-table1`)", b)):
        s = r["summary"]
        rows.append([lab, g(s["param.crit_frac"] * 100, 2) + " %", g(s["obs_omega_crit_rpm"], 3),
                     g(s["obs_gamma_per_wb2_s"], 4), g(s["obs_time_scale_s"] * 1e3, 3)])
    return table(["machine", "ω_crit / rated", "ω_crit [r/min]", "γ [1/(Wb²·s)]", "T_obs [ms]"], rows)


@figure("obs-loadstep", [mcsim("observer-test-motor", "profile=0")])
def _obs_loadstep(ctx, r):
    s = r["summary"]
    return table(["full-load step at 200 r/min (test motor, exact model)", "measured"], [
        ["speed dip [r/min]", g(s["speed_err_max_load_step_rpm"], 3)],
        ["mean speed error over the last 0.3 s of the load [rad/s]",
         g(s["speed_err_mean_last_0.3s_of_load_rad_s"], 2)],
        ["max angle error after the hand-over [rad]", g(s["angle_err_max_after_handover_rad"], 3)],
        ["hand-over: torque step per PWM period [N·m]", g(s["handover_torque_step_per_period_nm"], 2)],
        ["hand-over: i_q step per PWM period [A]", g(s["handover_iq_step_per_period_a"], 2)],
        ["I-f ramp: torque step per PWM period [N·m]", g(s["if_torque_step_per_period_nm"], 2)],
        ["fault bits", f"{s['fault_bits']:g}"]])


def _sweep_rows(r):
    out = []
    for row in r["rows"]:
        fault = int(row["fault_1"])
        out.append([f"{row['speed_ref_rpm']:g}", "yes" if row["works_1"] else "no",
                    f(row["speed_mean_rpm"], 1), g(row["speed_ripple_rms_rpm"], 3),
                    g(row["angle_err_mean_rad"], 2), g(row["angle_err_max_rad"], 2),
                    "none" if fault == 0 else f"0x{fault:x} at {row['fault_time_s']:.2f} s"])
    return out


@figure("obs-lowspeed", [mcsim("observer-lowspeed-sweep")])
def _obs_lowspeed(ctx, r):
    return table(["speed reference [r/min]", "works", "mean speed [r/min]",
                  "speed ripple rms [r/min]", "angle error mean [rad]", "angle error max [rad]",
                  "drive fault (bits)"], _sweep_rows(r))


@figure("obs-lowspeed-exact",
        [mcsim("observer-lowspeed-sweep", "dead_time_s=0", "noise_rms_a=0", "r_error=0")])
def _obs_lowspeed_exact(ctx, r):
    return table(["speed reference [r/min]", "works", "mean speed [r/min]",
                  "speed ripple rms [r/min]", "angle error mean [rad]", "angle error max [rad]",
                  "drive fault (bits)"], _sweep_rows(r))


DT_LOADS = ["0", "0.05", "0.1", "0.2", "0.5"]
DT_CASES = [("observer, 80 % of t_dead", ["dead_time_s=2e-6", "dead_comp_frac=0.8"]),
            ("observer, 100 %", ["dead_time_s=2e-6", "dead_comp_frac=1"]),
            ("duties, 100 %", ["dead_time_s=2e-6", "dead_comp_frac=1", "dead_comp_duty=on"]),
            ("duties, 80 %", ["dead_time_s=2e-6", "dead_comp_frac=0.8", "dead_comp_duty=on"]),
            ("no dead time", ["dead_time_s=0"])]


def _dt_src(load, sets):
    # With the dead time the speed ripples by tens of r/min and may keep an
    # offset of a few: several of these runs fail observer-test-motor's
    # verdict (load not held, not settled). The table shows by how much.
    return mcsim("observer-test-motor", "t_load_s=0.5", f"load_frac={load}", *sets,
                 judged=False)


def _dt_srcs():
    return [_dt_src(load, s) for load in DT_LOADS for _, s in DT_CASES]


@figure("obs-deadtime", _dt_srcs)
def _obs_deadtime(ctx, *runs):
    rows, i = [], 0
    for load in DT_LOADS:
        row = [load]
        for _ in DT_CASES:
            rws = runs[i]["rows"]
            i += 1
            w = [x["omega_m_rad_s"] for x in rws if 0.8 <= x["t"] <= 1.3]
            mu = sum(w) / len(w)
            sd = math.sqrt(sum((v - mu) ** 2 for v in w) / len(w)) * 60.0 / (2 * math.pi)
            row.append(g(sd, 2))
        rows.append(row)
    return table(["load (fraction of rated)"] + [c for c, _ in DT_CASES], rows)


# --- CSMC --------------------------------------------------------------------------

@figure("csmc-sampled", [mcsim("csmc-sampled")])
def _csmc_sampled(ctx, r):
    s = r["summary"]
    return table(["", "steady-state \\|e2\\| max [rad]", "e2 mean [rad]", "v_q sign changes [1/s]",
                  "v_q peak-to-peak [V]"], [
        ["CSMC + conditional integrators", g(s["csmc_e2_ss_max_abs_rad"]),
         g(s["csmc_e2_ss_mean_rad"]), g(s["csmc_vq_sign_changes_per_s"]),
         g(s["csmc_vq_peak_to_peak_v"], 2)],
        ["ideal SMC, u = −M·sgn(s)", g(s["smc_e2_ss_max_abs_rad"]), g(s["smc_e2_ss_mean_rad"]),
         g(s["smc_vq_sign_changes_per_s"], 4), g(s["smc_vq_peak_to_peak_v"])]])


CSMC_FLOOR = [("pi_2_w2", "π/2, 2 rad/s"), ("pi_10_w5", "π/10, 5 rad/s")]


@figure("csmc-floor", [gtest("test_csmc_sil", "*ServocompensatorFloor*")])
def _csmc_floor(ctx, t):
    rows = []
    for (tag, label), test in zip(CSMC_FLOOR, ("CsmcSil.ServocompensatorFloorLargeSetting",
                                               "CsmcSil.ServocompensatorFloorFastSetting"),
                                  strict=True):
        rows.append([label, g(prop(t, test, "nosvc_e2_max_abs_rad." + tag)),
                     g(prop(t, test, "svc_e2_max_abs_rad." + tag)),
                     f"{g(prop(t, test, 'ratio.' + tag), 4)}x",
                     g(prop(t, test, "double_ref_e2_max_abs_rad." + tag)),
                     g(prop(t, test, "svc_over_double_ref." + tag), 3)])
    return table(["(r0, ω0)", "\\|e2\\| max without [rad]", "\\|e2\\| max with [rad]",
                  "factor", "double-precision reference [rad]", "with / reference"], rows)


@figure("csmc-results", [mcsim("csmc-state-feedback"), mcsim("csmc-output-feedback-eps"),
                         mcsim("csmc-sinusoid"), mcsim("csmc-drive")])
def _csmc_results(ctx, sf, eps, sin, drv):
    s, e, n, d = sf["summary"], eps["summary"], sin["summary"], drv["summary"]
    pre = "max_abs_e2_of_minus_sf_rad.eps_"
    ev = sorted(((float(k[len(pre):]), v) for k, v in e.items() if k.startswith(pre)), reverse=True)
    return table(["scenario", "result"], [
        ["`csmc-state-feedback` (Fig. 2)",
         (f"overshoot {g(s['step1_overshoot_pct'])} % / {g(s['step2_overshoot_pct'])} %, "
         f"2 % settling {g(s['step1_settling_2pct_s'] * 1e3)} ms / "
         f"{g(s['step2_settling_2pct_s'] * 1e3)} ms (first / second step)")],
        ["`csmc-output-feedback-eps` (Fig. 3b)",
         "max \\|e2 − e2 of state feedback\\|: " + ", ".join(
             f"{g(v * 1e3, 2)} mrad (ε = {g(k)})" for k, v in ev)],
        ["`csmc-sinusoid` (Fig. 5)",
         (f"steady \\|e2\\| max {g(n['svc_e2_ss_max_abs_rad'])} rad with the servocompensators, "
         f"{g(n['nosvc_e2_ss_max_abs_rad'])} rad without: {g(n['ratio_nosvc_over_svc'])}x")],
        ["`csmc-drive` (drive + plug-in, 10 kHz, one-period delay)",
         (f"steady \\|e2\\| max {g(d['e2_ss_max_abs_rad'])} rad, overshoot "
         f"{g(d['overshoot_pct'])} %, settling {g(d['settling_2pct_s'] * 1e3)} ms, "
         f"{g(d['vq_sign_changes_per_s'])} v_q sign changes per s, faults {g(d['faults'])}")]])


# --- q31 twins -------------------------------------------------------------------

Q31_KERNELS = [
    # row label, unit-test name, recorded key, bench case name
    ("dirty derivative", "DdiffQ31.MatchesF32OnRandomInputs", "ddiff |theta_f32 - theta_q31|", "ddiff_step"),
    ("PLL", "SpdpllQ31.MatchesF32OnNoisyRamps", "spdpll |w_f32 - w_q31|", "spdpll_step"),
    ("flux observer + θ̂", "FluxobsQ31.MatchesF32FromAWrongStartOnANoisyRun",
     "fluxobs |theta_f32 - theta_q31|", "fluxobs_step"),
    ("FOC dq step", "FocQ31.DqStepMatchesF32OnRandomWalks", "foc |v_f32 - v_q31| (linear + circle)", "foc_step_dq"),
    ("FOC whole step, duties", "FocQ31.FullStepDutiesMatchF32", "foc full step |duty_f32 - duty_q31|", "foc_step"),
    ("PI²D", "Pi2dQ31.MatchesF32OnRandomTrajectories", "pi2d |v_f32 - v_q31|", "pi2d_step"),
    ("CSMC, model law + integrators", "CsmcQ31.ModelAndConstLawsMatchF32OnRandomStates",
     "csmc model |u f32 - q31|", "csmc_model_step"),
    ("high-gain observer, ε = 1e-4 (z3)", "HgoQ31.MatchesF32AtEps1e4", "hgo |z3 f32 - q31|", "hgo_step"),
    ("servocompensator, order 5", "CsvcQ31.ServocompensatorMatchesF32", "csvc servo |K0 sigma f32 - q31|", None),
]


def _bench_mean(b, name, fmt):
    for c in b["cases"]:
        if c["name"] == name and c["format"] == fmt:
            return c["instr_mean"]
    return None


def _instr(x):
    return "–" if x is None else f"{x:.0f}"


@figure("q31-kernels", [gtest("test_q31_twins"), bench_q31("m4f"), bench_q31("m3")],
        reason=EXACT + "; instruction counts " + EXACT_QEMU)
def _q31_kernels(ctx, t, m4, m3):
    def unit(test, key):
        u = t.get(test, {}).get(key + ".unit", "")
        return "" if u == "1" else u

    rows = []
    for lab, test, key, case in Q31_KERNELS:
        u = unit(test, key)
        rows.append([lab, (f"{_with_unit(prop(t, test, key), u, 2)} "
                          f"({_with_unit(prop(t, test, key + '.bound'), u, 2)})"),
                     (f"{_instr(_bench_mean(m4, case, 'f32') if case else None)} / "
                     f"{_instr(_bench_mean(m4, case, 'q31') if case else None)}"),
                     (f"{_instr(_bench_mean(m3, case, 'f32') if case else None)} / "
                     f"{_instr(_bench_mean(m3, case, 'q31') if case else None)}")])
    hgo = "HgoQ31.MatchesF32AtEps1e4"
    kq, kf = "hgo |z3 q31 - true y''| after 10 ms", "hgo |z3 f32 - true y''| after 10 ms"
    rows.append(["high-gain observer: \\|z3 − true y''\\| after 10 ms",
                 (f"q31 {_with_unit(prop(t, hgo, kq), unit(hgo, kq), 2)}, "
                 f"f32 {_with_unit(prop(t, hgo, kf), unit(hgo, kf), 2)}"), "", ""])
    return table(["kernel", "\\|f32 − q31\\| max (test bound)", "instructions M4F f32 / q31",
                  "instructions M3 f32 (soft float) / q31"], rows)


def _md(text):
    return str(text).replace("|", "\\|")


def _recorded(t, test):
    """(key, value, unit, bound or None) of every value a test recorded."""
    props = t.get(test)
    if props is None:
        raise DocError(f"{test} did not run")
    out = []
    for k, v in props.items():
        if k.endswith((".bound", ".unit")) or not isinstance(v, float):
            continue
        out.append((k, v, props.get(k + ".unit", ""), props.get(k + ".bound")))
    return out


def _with_unit(v, unit, sig):
    return f"{g(v, sig)} {unit}".strip()


def _recorded_table(t, tests, head, sig=2):
    rows = []
    for test, lab in tests:
        for k, v, unit, bound in _recorded(t, test):
            rows.append([lab, _md(k), _with_unit(v, unit, sig),
                         "–" if bound is None else _with_unit(bound, unit, 2)])
    return table(head, rows)


@figure("q31-loops", [gtest("test_q31_loops")])
def _q31_loops(ctx, t):
    return _recorded_table(t, [("Q31Loops.Pi2dPaperTracksTheF32Loop", "`pi2d-paper-q31`"),
                               ("Q31Loops.Pi2dMotorTracksTheF32Loop", "`pi2d-motor-q31`"),
                               ("Q31Loops.CsmcStateFeedbackTracksTheF32Loop", "`csmc-state-feedback-q31`")],
                           ["closed loop", "quantity", "measured", "test bound"])


@figure("q31-sensorless", [gtest("test_q31_sensorless")])
def _q31_sensorless(ctx, t):
    return _recorded_table(t, [("Q31Sensorless.TestMotorLoadStepTracksTheF32Loop",
                                "200 r/min, full-load step (profile 0)"),
                               ("Q31Sensorless.StartStopFallsBackAndHoldsLikeTheF32Loop",
                                "start-stop 0 → 300 → 0 r/min, 30 % load (profile 3)"),
                               ("Q31Sensorless.LowSpeedWithDeadTimeAndNoiseLikeTheF32Loop",
                                "100 r/min, 2 µs dead time (80 % compensated), noise, R + 10 %")],
                           ["run", "quantity", "measured", "test bound"], sig=3)


@figure("dead-time", [gtest("test_dead_time_sil")])
def _dead_time(ctx, t):
    """The drive's dead-time compensation at 5 % of rated speed, with
    (dead_time_comp 1) and without (0): tests/sil/foc/test_dead_time_sil.cpp's
    records."""
    r = {k: v for k, v, _u, _b in
         _recorded(t, "DeadTimeCompSil.LowSpeedCurrentDistortionFallsWithTheCompensation")}
    rows = [
        ["phase current THD (harmonics 2-25) [%]", g(100 * r["off.thd"], 3),
         g(100 * r["on.thd"], 3)],
        ["i_q ripple, RMS / mean [%]", g(100 * r["off.iq_ripple"], 3),
         g(100 * r["on.iq_ripple"], 3)],
    ]
    return table(["D5065, VESC 6 (360 ns, 30 kHz, 48 V), 25 rad/s, i_q 3 A",
                  "dead_time_comp 0", "dead_time_comp 1"], rows)


@figure("r-follow", [gtest("test_r_follow_sil")])
def _r_follow(ctx, t):
    """The drive's R following its winding estimate on a 120 C winding,
    with (winding_r_follow 1) and without (0): tests/sil/motors/
    test_r_follow_sil.cpp's records."""
    sls = {k: v for k, v, _u, _b in _recorded(t, "RFollow.SensorlessAngleOnAHotWinding")}
    cur = {k: v for k, v, _u, _b in _recorded(t, "RFollow.CurrentStepOnAHotWinding")}
    rows = [
        ["sensorless, 100 rad/s, 0.3 → 0.9 rated torque", "angle error max [rad]",
         g(sls["sls.off.angle_err_max_rad"], 3), g(sls["sls.on.angle_err_max_rad"], 3)],
        ["", "angle error rms [rad]", g(sls["sls.off.angle_err_rms_rad"], 3),
         g(sls["sls.on.angle_err_rms_rad"], 3)],
        ["", "speed error max, end [rad/s]", g(sls["sls.off.omega_err_max_end_rad_s"], 2),
         g(sls["sls.on.omega_err_max_end_rad_s"], 2)],
        ["current step (q)", "10-90 % rise / design", g(cur["cur.off.iq_rise_time_ratio"], 3),
         g(cur["cur.on.iq_rise_time_ratio"], 3)],
        ["", "settling time [ms]", g(1e3 * cur["cur.off.iq_settle_time_s"], 3),
         g(1e3 * cur["cur.on.iq_settle_time_s"], 3)],
    ]
    return table(["run (D5065, ODrive v3.6 24 V, winding 120 °C)", "quantity",
                  "R = r_ohm (cold)", "R follows the estimate"], rows)


# --- drive: faults, position, stop --------------------------------------------------

def _fault_defs():
    """MC_DRIVE_FAULT_* bits and their comments, from the drive's header."""
    hdr = None
    for dp, _dn, fn in os.walk(os.path.join(ROOT, "firmware", "app")):
        if "mc_drive.h" in fn:
            hdr = os.path.join(dp, "mc_drive.h")
    if hdr is None:
        raise DocError("firmware/app/**/mc_drive.h not found")
    text = read_text(hdr)
    out = []
    for m in re.finditer(r"#define MC_DRIVE_FAULT_(\w+)\s+\(1u << (\d+)\)\s*/\*\*<(.*?)\*/", text, re.DOTALL):
        desc = " ".join(m.group(3).split())
        out.append((m.group(1), int(m.group(2)), desc))
    if not out:
        raise DocError(f"no MC_DRIVE_FAULT_* in {hdr}")
    return os.path.relpath(hdr, ROOT), out


def _tests_asserting(dirs, const):
    """TEST blocks under dirs with an assertion (EXPECT_/ASSERT_, or a helper
    whose name contains Expect) that names `const`: Suite.Name list."""
    found = []
    pat = re.compile(r"^TEST(?:_F|_P)?\((\w+),\s*(\w+)\)", re.MULTILINE)
    for d in dirs:
        for dp, _dn, fn in os.walk(os.path.join(ROOT, d)):
            for n in sorted(fn):
                if not n.endswith(".cpp"):
                    continue
                text = read_text(os.path.join(dp, n))
                heads = list(pat.finditer(text))
                for i, h in enumerate(heads):
                    body = text[h.end():heads[i + 1].start() if i + 1 < len(heads) else len(text)]
                    for line in body.split(";"):
                        if re.search(r"\b" + const + r"\b", line) and \
                                re.search(r"\b(EXPECT|ASSERT)_\w+\(|\w*[Ee]xpect\w*\(", line):
                            found.append(f"{h.group(1)}.{h.group(2)}")
                            break
    return sorted(set(found))


@figure("drive-faults", [gtest("test_fault_injection"),
                         gtest("test_app", "AppDriveSupervision.OverSpeedTripsOnTheSpeedEstimate")])
def _drive_faults(ctx, sil, unit):
    hdr, defs = _fault_defs()
    measured = {}
    for where, tests in (("SIL", sil), ("unit", unit)):
        for name, p in tests.items():
            if "fault_bits" in p and "latency_s" in p:
                measured.setdefault(int(p["fault_bits"]), []).append((where, name, p))
    rows = []
    for fname, bit, desc in defs:
        const = "MC_DRIVE_FAULT_" + fname
        u = _tests_asserting(["tests/unit"], const)
        s = _tests_asserting(["tests/sil"], const)
        lat = []
        for where, name, p in measured.get(1 << bit, []):
            per = p["period_s"]

            def t(x, per=per):  # periods, or seconds where that is clearer
                n = x / per
                if n >= 1000:
                    return f"{g(x, 4)} s"
                return f"{g(n, 3)} period" + ("" if g(n, 3) == "1" else "s")
            if "latency_max_s" in p:
                v = (f"{t(p['latency_min_s'])} … {t(p['latency_max_s'])} "
                     f"(≤ {t(p['latency_max_s.bound'])})")
            else:
                v = f"{t(p['latency_s'])} (≤ {t(p['latency_s.bound'])})"
            lat.append(f"{v} in `{name.split('.')[-1]}` ({where})")
        rows.append([f"`{fname}`", desc.replace("|", "\\|"),
                     ", ".join(f"`{x.split('.')[-1]}`" for x in u) or "**none**",
                     ", ".join(f"`{x.split('.')[-1]}`" for x in s) or "–",
                     "; ".join(lat) or "–"])
    return (f"From `{hdr}` (the bits and their comments) and the tests: a test covers a fault "
            "when one of its assertions (or an assertion helper) names the bit. Latency from "
            "the injection to the sample in which the drive detects the fault (0 periods: the "
            "first sample after it), measured in the test named, with the bound it asserts.\n\n"
            + table(["fault", "detection (header)", "unit tests (`tests/unit`)",
                     "SIL tests (`tests/sil`)", "latency, measured (bound)"], rows))


# The sensored speed law's step on motors from the heaviest rotor to the
# lightest (sim/motors): its own derived gains, ramp and reference lag.
SPEED_MOTORS = [("odrive-d5065", "odrive-v36-24v"), ("turnigy-sk3-6374-149kv", "vesc6-48v"),
                ("paper002-test-motor", "paper002-200v"), ("u8-class-kv100", "odrive-v36-56v"),
                ("hub-6p5in-15pp", "odrive-v36-56v"), ("gimbal-gm4108", "gimbal-24v"),
                ("maxon-ec45flat-class-24v", "odrive-v36-24v")]


@figure("speed-step", [mcsim("speed-step", motor=m, board=b) for m, b in SPEED_MOTORS])
def _speed_step(ctx, *runs):
    rows = []
    for (m, _b), r in zip(SPEED_MOTORS, runs, strict=True):
        s = r["summary"]
        w = s["omega_final_rad_s"]
        rows.append([f"`{m}`", g(s["gain.speed_wc_rad_s"], 3), g(s["gain.speed_accel_rad_s2"], 3),
                     g(w / s["gain.speed_accel_rad_s2"] * 1e3, 2), g(s["overshoot_frac"] * 100, 2),
                     g(s["settle_2pct_s"] * 1e3, 3), g(s["omega_pp_steady_rad_s"] / w * 100, 2),
                     g(s["omega_err_mean_steady_rad_s"] / w * 100, 2), s["verdict"]])
    return table(["motor", "crossover [rad/s]", "ramp [rad/s²]", "ramp time [ms]", "overshoot [%]",
                  "settling 2 % [ms]", "steady peak-to-peak [% of target]",
                  "steady mean error [% of target]", "verdict"], rows)


POS_MOTORS = [("odrive-d5065", "odrive-v36-24v", "D5065"),
              ("paper002-test-motor", "paper002-200v", "paper-002 test motor")]


@figure("drive-position", [mcsim("position-move", motor=m, board=b) for m, b, _ in POS_MOTORS])
def _drive_position(ctx, *runs):
    rows = []
    for (_m, _b, lab), r in zip(POS_MOTORS, runs, strict=False):
        s = r["summary"]
        rows.append([lab, f"{g(s['final_err_counts'])} counts", g(s["reach_time_ratio"], 5),
                     f"{g(s['overshoot_counts'], 2)} counts", g(s["move_time_ratio"], 3),
                     g(s["faults"])])
    return table(["motor", "final error", "reach time / trapezoid", "overshoot",
                  "settle time / trapezoid", "faults"], rows)


@figure("drive-stop", [gtest("test_stop_sil")])
def _drive_stop(ctx, t):
    rows = []
    for test, mode, motor in (("StopSil.PositionModeStopD5065", "position", "D5065"),
                              ("StopSil.PositionModeStopPaperMotor", "position", "paper-002 test motor"),
                              ("StopSil.SpeedModeTimeoutStopD5065", "speed (command timeout)", "D5065"),
                              ("StopSil.SpeedModeTimeoutStopPaperMotor", "speed (command timeout)",
                               "paper-002 test motor")):
        rows.append([mode, motor, g(prop(t, test, "stop_time_ratio"), 4),
                     f"0.95 … {g(prop(t, test, 'stop_time_ratio.bound'), 3)}",
                     g(prop(t, test, "reverse_speed_rad_s"), 3),
                     g(prop(t, test, "reverse_speed_rad_s.bound"), 3)])
    return table(["mode", "motor", "stop time / (ω₀ / decel)", "test bounds",
                  "largest backward speed [rad/s]", "bound (2 decel T; speed mode: + stop_rest)"], rows)


ASC_RUNS = [("off", ()), ("on", ("fault_i_sense_max_a=250",)), ("on", ())]


@figure("drive-asc", [mcsim("field-weakening", "fault=1", f"asc={a}", *x,
                            motor="ipm-representative-48v") for a, x in ASC_RUNS])
def _drive_asc(ctx, *runs):
    rows = []
    for (a, x), r in zip(ASC_RUNS, runs, strict=True):
        s = r["summary"]
        board = "250 A sensing" if x else "board file (125 A sensing)"
        rows.append([a, board, g(s["fault_emf_over_vbus"], 3),
                     f"{g(s['fault_vbus_peak_v'], 3)} / {g(s['fault_vbus_trip_v'], 3)}",
                     f"{g(s['fault_i_phase_peak_a'], 3)} / {g(s['fault_i_trip_a'], 4)}",
                     g(s["fault_torque_min_nm"], 3), g(s["fault_asc_time_s"] * 1e3, 3)])
    return table(["short", "board", "back-EMF / bus at the fault", "bus peak / trip [V]",
                  "phase current peak / trip [A]", "torque min [N m]", "time shorted [ms]"], rows)


# --- field weakening, regen ---------------------------------------------------------

FW_MOTORS = [("ipm-representative-48v", None), ("odrive-d5065", "odrive-v36-24v")]


@figure("fw-results", [mcsim("field-weakening", motor=m, board=b) for m, b in FW_MOTORS])
def _fw_results(ctx, *runs):
    rows = []
    for (m, _b), r in zip(FW_MOTORS, runs, strict=False):
        s = r["summary"]
        rows.append([f"`{m}`", g(s["mtpa_rel_err_max"], 2), g(s["mtpa_t_per_a_over_kt_max"], 4),
                     g(s["target_over_base"], 3), f"{g(s['i_peak_a'], 3)} / {g(s['i_limit_a'], 3)}",
                     f"{g(s['id_min_a'], 3)} / {g(s['id_demag_bound_a'], 3)}",
                     g(s["v_mag_minus_v_max_hold_max_v"], 2), g(s["faults"])])
    return table(["motor", "MTPA torque/A, max rel. error", "MTPA torque/A over kt, max",
                  "final speed / base", "\\|i\\| peak / limit [A]", "i_d min / demag bound [A]",
                  "\\|v\\| − v_max at the top [V]", "faults"], rows)


# (label, motor, board, sets, judged): the D5065 on the 24 V ODrive with and
# without its resistor (without it, at the derived ramp the board's 25.68 V
# trip is reached: shown, not judged), at a quarter of that ramp, and the
# SK3 on the VESC 6 (no chopper; 57 V limit).
REGEN = [("D5065, ODrive 24 V", "odrive-d5065", "odrive-v36-24v", ("brake=on",), True),
         ("D5065, ODrive 24 V", "odrive-d5065", "odrive-v36-24v", ("brake=off",), False),
         ("D5065, ODrive 24 V, ramp 1380 rad/s²", "odrive-d5065", "odrive-v36-24v",
          ("brake=off", "speed_ramp_rad_s2=1380"), True),
         ("SK3 6374, VESC 6", "turnigy-sk3-6374-149kv", "vesc6-48v", ("brake=off",), True)]


@figure("regen-stop", [mcsim("regen-stop", *x, motor=m, board=b, judged=j) for _l, m, b, x, j in REGEN])
def _regen(ctx, *runs):
    rows = []
    for (lab, _m, _b, x, _j), r in zip(REGEN, runs, strict=True):
        s = r["summary"]
        brake = x[0].split("=")[1]
        if "vbus_peak_v" not in s:  # stopped by a fault: the verdict says which
            rows.append([lab, brake, f"– / {g(s['vbus_trip_v'], 4)}", "–", "–", "–", "–",
                         s.get("fault_names", g(s["faults"]))])
            continue
        rows.append([lab, brake, f"{g(s['vbus_peak_v'], 3)} / {g(s['vbus_trip_v'], 4)}",
                     g(s["brake_energy_j"], 3), g(s["kinetic_j"], 3),
                     f"{g(s['stop_time_s'] * 1e3, 3)} / {g(s['stop_time_ramp_s'] * 1e3, 3)}",
                     g(s["energy_balance_rel_err"], 2), g(s["faults"])])
    return table(["motor, board", "brake resistor", "vbus peak / trip [V]", "brake energy [J]",
                  "kinetic energy [J]", "stop time / ramp [ms]", "energy balance rel. error",
                  "faults"], rows)



# Thermal derating and the DC-bus limits (issue 33): thermal-duty with the
# drive's R 10 % off (model_r_scale 1.1), derating on and off; bus-limits
# with the drive's limits on and off (off fails its verdict by design: it
# is judged against the same limits), on two motors and boards.
THERMAL = [("D5065, ODrive 24 V", "odrive-d5065", "odrive-v36-24v")]
THERMAL_RUNS = [(lab, m, b, d) for lab, m, b in THERMAL for d in ("1", "0")]
BUS = [("D5065, ODrive 24 V", "odrive-d5065", "odrive-v36-24v"),
       ("SK3 6374, VESC 6", "turnigy-sk3-6374-149kv", "vesc6-48v")]
BUS_RUNS = [(lab, m, b, lim) for lab, m, b in BUS for lim in ("on", "off")]


def thermal_src(m, b, derate):
    return mcsim("thermal-duty", "model_r_scale=1.1", f"derate={derate}", motor=m, board=b)


def bus_src(m, b, limits):
    return mcsim("bus-limits", f"limits={limits}", motor=m, board=b, judged=limits == "on")


@figure("power-limits", [thermal_src(m, b, d) for _l, m, b, d in THERMAL_RUNS] +
        [bus_src(m, b, x) for _l, m, b, x in BUS_RUNS])
def _power_limits(ctx, *runs):
    th, bu = runs[:len(THERMAL_RUNS)], runs[len(THERMAL_RUNS):]
    t_rows = []
    for (lab, _m, _b, d), r in zip(THERMAL_RUNS, th, strict=True):
        s = r["summary"]
        t_rows.append([lab, "on" if d == "1" else "off", g(s["t_winding_max_c"], 4),
                       g(s["t_winding_limit_c"], 4), g(s["t_est_err_max_k"], 2),
                       g(s["i_limit_min_a"], 3), s["verdict"]])
    b_rows = []
    for (lab, _m, _b, x), r in zip(BUS_RUNS, bu, strict=True):
        s = r["summary"]
        b_rows.append([lab, x, g(s["i_bus_peak_a"], 3), g(s["i_bus_max_a"], 3),
                       g(s["i_bus_min_a"], 3), g(-s["i_bus_regen_max_a"], 3),
                       g(s["omega_peak_rad_s"], 3), s["verdict"]])
    return (table(["thermal-duty: motor, board", "derating", "winding max [°C]", "limit [°C]",
                   "estimate error max [K]", "current limit min [A]", "verdict"], t_rows) +
            "\n\n" +
            table(["bus-limits: motor, board", "limits", "supply current peak [A]",
                   "motoring limit [A]", "supply current min [A]", "regenerating limit [A]",
                   "peak speed [rad/s]", "verdict"], b_rows))


# --- anticogging (issue 35) ------------------------------------------------------------
# The cogging scenario's speed ripple without the map and with the map the
# drive calibrates first, on the library's motors with cogging, at 2 % and
# 10 % of rated speed; the calibration's constants from the firmware's headers.
COG_MOTORS = [("SK3 6374, VESC 6", "turnigy-sk3-6374-149kv", "vesc6-48v"),
              ("GM4108, gimbal 24 V", "gimbal-gm4108", "gimbal-24v")]
COG_FRACS = ("0.02", "0.10")
COG_RUNS = [(lab, m, b, fr, ac) for lab, m, b in COG_MOTORS for fr in COG_FRACS for ac in ("0", "1")]
COG_PNG = "cogging-ripple.png"


def cog_src(m, b, frac, ac):
    return mcsim("cogging", f"anticogging={ac}", f"speed_frac={frac}", motor=m, board=b)


def cog_srcs():
    return [cog_src(m, b, fr, ac) for _l, m, b, fr, ac in COG_RUNS]


@figure("cogging-ripple", cog_srcs)
def _cogging_ripple(ctx, *runs):
    rows = []
    for i in range(0, len(runs), 2):
        lab, _m, _b, fr, _ac = COG_RUNS[i]
        s0, s1 = runs[i]["summary"], runs[i + 1]["summary"]
        r0, r1 = s0["speed_ripple_pp_rad_s"], s1["speed_ripple_pp_rad_s"]
        rows.append([lab, f"{100 * float(fr):g} % ({g(s0['speed_target_rad_s'])} rad/s)", g(r0), g(r1),
                     g(r0 / r1, 2), g(s1["cog_cal_s"], 4)])
    return (table(["motor, board", "speed (of rated)", "ripple without map [rad/s p-p]",
                   "with the calibrated map [rad/s p-p]", "without / with", "calibration [s]"], rows) +
            f"\n\n![cogging-ripple: the peak-to-peak speed ripple without and with the map, per motor "
            f"and speed](../../../tools/plot/figures/{COG_PNG})")


COG_HDRS = {"app": "firmware/app/app/mc_app.h", "comm": "firmware/app/commission/mc_comm_cog.h",
            "drive": "firmware/app/drive/mc_drive_cog.h"}
COG_DEFS = {"app": ["MC_APP_COG_CAL_SPEED_RAD_S", "MC_APP_COG_CAL_RAMP_S", "MC_APP_COG_CAL_SETTLE_S",
                    "MC_APP_COG_BOUND_FRAC", "MC_APP_COG_CAL_AGREE", "MC_APP_COG_CAL_FLOOR_FRAC",
                    "MC_APP_COG_CAL_PASSES"],
            "comm": ["MC_COMM_COG_TIME_FACTOR", "MC_COMM_COG_MARGIN_BINS"], "drive": ["MC_COG_N"]}


def c_defines(key):
    """The numeric #defines COG_DEFS[key] of the header COG_HDRS[key]."""
    path = COG_HDRS[key]

    def fn(_ctx):
        text = read_text(os.path.join(ROOT, path))
        out = {}
        for n in COG_DEFS[key]:
            m = re.search(r"#define " + n + r"\s+\(?([0-9.]+(?:[eE][-+]?[0-9]+)?)[uUfF]?", text)
            if m is None:
                raise DocError(f"#define {n} not found in {path}")
            out[n] = float(m.group(1))
        return out
    return Src(("defines", path), path, fn)


@figure("cogging-cal", [c_defines(k) for k in COG_HDRS], reason="exactly (derived from the headers)")
def _cogging_cal(ctx, app, comm, drv):
    w, n, margin = app["MC_APP_COG_CAL_SPEED_RAD_S"], drv["MC_COG_N"], comm["MC_COMM_COG_MARGIN_BINS"]
    ramp, settle, factor = app["MC_APP_COG_CAL_RAMP_S"], app["MC_APP_COG_CAL_SETTLE_S"], \
        comm["MC_COMM_COG_TIME_FACTOR"]
    passes = app["MC_APP_COG_CAL_PASSES"]
    turn = 2.0 * math.pi * (1.0 + margin / n)
    nominal = passes * (3.0 * (ramp + settle) + 2.0 * turn / w)
    bound = passes * (3.0 * (ramp + settle) + 2.0 * factor * turn / w)
    sys.path.insert(0, os.path.join(ROOT, "tools", "mdtool", "src"))
    from mdtool.can import cogging as mdcog
    if abs(mdcog.BOUND_S - bound) > 1e-9 * bound:
        raise DocError(f"mdtool's calibration bound {mdcog.BOUND_S} s is not the headers' {bound} s: "
                       "update tools/mdtool/src/mdtool/can/cogging.py")
    rows = [["speed of the turns (mechanical)", f"{g(w)} rad/s", "`MC_APP_COG_CAL_SPEED_RAD_S`"],
            ["angle points (map entries) per turn", f"{n:.0f}, each recording {margin:.0f} more",
             "`MC_COG_N`, `MC_COMM_COG_MARGIN_BINS`"],
            ["ramp, then settle, before each turn and after the last", f"{g(ramp)} s + {g(settle)} s",
             "`MC_APP_COG_CAL_RAMP_S`, `MC_APP_COG_CAL_SETTLE_S`"],
            ["passes (each after the first on the map of the one before)", f"{passes:.0f}",
             "`MC_APP_COG_CAL_PASSES`"],
            ["time, nominal (a turn each way per pass)", f"{g(nominal, 4)} s", ""],
            ["time bound (each turn within its time times the factor, else ROTOR_BLOCKED)",
             f"factor {g(factor)}: {g(bound, 4)} s", "`MC_COMM_COG_TIME_FACTOR`"],
            ["mdtool's longest wait (`--cal-timeout`, default and most)", f"{g(mdcog.DEFAULT_TIMEOUT_S, 4)} s",
             "the bound plus 10 %"],
            ["current", "the speed loop's, limited to `i_max_a`", ""],
            ["largest map entry (else MAP_IMPLAUSIBLE_AMPLITUDE)", f"{g(app['MC_APP_COG_BOUND_FRAC'])} i_max_a",
             "`MC_APP_COG_BOUND_FRAC`"],
            ["directions' disagreement (else MAP_IMPLAUSIBLE_DISAGREE)",
             f"{g(app['MC_APP_COG_CAL_AGREE'])} rms(map) + {g(app['MC_APP_COG_CAL_FLOOR_FRAC'])} i_max_a",
             "`MC_APP_COG_CAL_AGREE`, `MC_APP_COG_CAL_FLOOR_FRAC`"]]
    return table(["the calibration", "value", "constant"], rows)


# --- static sources: DBC, motor files ---------------------------------------------

@figure("can-protocol", [mc_can("table")], reason="exactly (derived from the DBC)")
def _can_protocol(ctx, text):
    return text.strip()


CANSEND = [("select current mode", "SET_CONTROL_MODE", ["control_mode=1"]),
           ("select speed mode", "SET_CONTROL_MODE", ["control_mode=2"]),
           ("select position mode", "SET_CONTROL_MODE", ["control_mode=3"]),
           ("enable", "SET_ENABLE", ["enable=1"]),
           ("disable / e-stop (the node's lowest id)", "DISABLE", []),
           ("i_d = 0 A, i_q = 1.5 A", "SET_CURRENT_REF", ["i_d_ref_a=0", "i_q_ref_a=1.5"]),
           ("speed 50 rad/s", "SET_SPEED_REF", ["omega_ref_rad_s=50"]),
           ("position 10 turns (62.8319 rad)", "SET_POSITION_REF", ["theta_ref_rad=62.8319"]),
           ("clear faults", "CLEAR_FAULTS", []),
           ("CURRENTS at 500 Hz", "SET_TM_RATE", ["tm_cmd=2", "rate_hz=500"]),
           ("heartbeat (keep-alive; the counter must advance)", "HOST_HEARTBEAT", ["counter=0"]),
           ("next heartbeat", "HOST_HEARTBEAT", ["counter=1"]),
           ("node id 5: WRITE (answered NEEDS_CONFIRM)", "PARAM_REQ",
            ["opcode=1", "param_id=110", "value=5"]),
           ("... its CONFIRM, the very next request", "PARAM_REQ",
            ["opcode=5", "param_id=110", "value=5"])]


@figure("can-cansend", [mc_can("encode", m, *a) for _, m, a in CANSEND],
        reason="exactly (derived from the DBC)")
def _can_cansend(ctx, *outs):
    rows = []
    for (lab, m, a), o in zip(CANSEND, outs, strict=False):
        rows.append([lab, f"`mc_can.py encode {' '.join([m] + a)}`", f"`cansend vcan0 {o.strip()}`"])
    return table(["command", "encoded by", "frame (node 1)"], rows)


@figure("can-reply-flood", [gtest("test_mc_app", "McApp.AFloodOfRequests*")])
def _can_reply_flood(ctx, t):
    k = "McApp.AFloodOfRequestsCostsTheBusAtMostTheRepliesShare"
    bus = prop(t, k, "bitrate_bps")
    rows = [["requests per second", g(prop(t, k, "flood_requests_per_s"), 5), "-"],
            ["their replies' load, were each one answered",
             f"{g(100 * prop(t, k, 'unanswered_load_would_be'), 3)} % of {g(bus / 1e3, 3)} kbit/s", "-"],
            ["replies in the busiest second", g(prop(t, k, "replies_max_in_1s"), 3),
             f"≤ {g(prop(t, k, 'replies_max_in_1s.bound'), 3)}"],
            ["their load", f"{g(100 * prop(t, k, 'reply_load_max_1s'), 3)} %",
             f"≤ {g(100 * prop(t, k, 'reply_load_max_1s.bound'), 3)} % (the budget's reserve)"],
            ["replies per second, mean of 10 s", g(prop(t, k, "replies_per_s_mean"), 3),
             f"≤ {g(prop(t, k, 'replies_per_s_mean.bound'), 3)}"],
            ["requests not answered (counted, `reply_limited`)",
             f"{g(100 * prop(t, k, 'requests_unanswered'), 4)} %", "-"]]
    return table(["", "measured", "test bound"], rows)


@figure("config-flash-wear", [gtest("test_mc_app", "McApp.FlashWear*")])
def _config_flash_wear(ctx, t):
    k = "McApp.FlashWearUnderTheSaveRateLimitOnTheF405Sectors"
    rows = [["record", f"{g(prop(t, k, 'record_bytes'), 4)} bytes"],
            ["records per 128 KiB sector (counted between two erases)",
             g(prop(t, k, "records_per_sector"), 4)],
            ["SAVE rate limit", f"{g(prop(t, k, 'save_burst'))}, then one per "
                                f"{g(prop(t, k, 'save_period_s'))} s"],
            ["saves written in the first hour of nonstop changed SAVEs",
             g(prop(t, k, "saves_first_hour"), 3)],
            ["worst case: erases per sector per year", g(prop(t, k, "erases_per_sector_per_year"), 3)],
            ["the F405's 10 000 cycles last",
             f"{g(prop(t, k, 'years_to_10k_cycles'), 3)} years (test bound ≥ "
             f"{g(prop(t, k, 'years_to_10k_cycles.bound'))})"]]
    return table(["", ""], rows)


def _motor_library_pairs():
    p = os.path.join(ROOT, "tests", "sil", "motors", "motor_library.hpp")
    text = read_text(p)
    return dict(re.findall(r'\{"([\w.-]+)",\s*"([\w.-]*)"\}', text))


def _motor_files(table):
    """(file name, its [table]) for each sim/motors/*.toml that has one, by name."""
    d = os.path.join(ROOT, "sim", "motors")
    for n in sorted(os.listdir(d)):
        if not n.endswith(".toml"):
            continue
        with open(os.path.join(d, n), "rb") as fh:
            t = tomllib.load(fh)
        if table in t:
            yield n, t[table]


@figure("motor-library", [], reason="exactly (derived from sim/motors/*.toml and "
                                   "tests/sil/motors/motor_library.hpp)")
def _motor_library(ctx):
    pairs = _motor_library_pairs()
    rows = []
    for n, m in _motor_files("motor"):
        stem = n[:-5]
        board = pairs.get(stem)
        if board is None:
            bcell = "– (not in the library tests)"
        else:
            bcell = "the same file" if board == "" else f"`{board}.toml`"
        big = max(m["ld_h"], m["lq_h"]) >= 1e-3
        k, u = (1e3, "mH") if big else (1e6, "µH")
        q, a = m.get("slots", 0), m.get("cogging_nm", 0.0)
        # cogging: slots / poles, the order lcm(slots, 2 p) and the fundamental's peak
        cog = (f"{q} / {2 * m['pole_pairs']}: {math.lcm(q, 2 * m['pole_pairs'])} per turn, "
               f"{g(a * 1e3, 3)} mN m") if q > 0 and a > 0 else "none"
        rows.append([f"`{n}`", f"{g(m['r_ohm'], 3)} Ω", f"{g(m['ld_h'] * k, 3)} / {g(m['lq_h'] * k, 3)} {u}",
                     f"{g(m['flux_wb'] * 1e3, 3)} mWb", f"{m['pole_pairs']}", f"{g(m['i_max_a'], 3)} A",
                     cog, bcell])
    return table(["motor file", "R", "L_d / L_q", "flux", "pole pairs", "i_max",
                  "cogging: slots / poles, order, peak", "board file in the tests"], rows)


@figure("stepper-library", [], reason="exactly (derived from the [stepper] tables of "
                                     "sim/motors/*.toml)")
def _stepper_library(ctx):
    rows = []
    for n, m in _motor_files("stepper"):
        # Km as sim/cli/motor_file.cpp derives it from the holding torque
        if "km_nm_a" in m:
            km, how = m["km_nm_a"], "given"
        else:
            k = math.sqrt(2.0) if m["holding_excitation"] == "two_phase_on" else 1.0
            km = m["holding_torque_nm"] / (k * m["i_rated_a"])
            how = f"{g(m['holding_torque_nm'], 3)} N m, {m['holding_excitation']}"
        rows.append([f"`{n}`", f"{g(m['r_ohm'], 3)} Ω", f"{g(m['l_h'] * 1e3, 3)} mH",
                     f"{g(m['i_rated_a'], 3)} A", f"{g(km, 3)} N m/A ({how})",
                     f"{m['rotor_teeth']}", f"{g(m['j_kgm2'] * 1e7, 3)} g cm²",
                     f"{g(m['detent_nm'] * 1e2, 3)} N cm"])
    return table(["stepper file", "R", "L", "i_rated", "K_m (from)", "rotor teeth", "J",
                  "detent"], rows)


PIL_COST_JSON = os.path.join("tools", "bench", "results", "pil_cost.json")


@figure("pil-cost", [], reason=f"exactly (quoted from {PIL_COST_JSON}, the stored report of "
                               "tools/bench/run_pil_cost.py; wall time is the machine's and its "
                               "load's, so the check does not re-measure it)")
def _pil_cost(ctx):
    with open(os.path.join(ROOT, PIL_COST_JSON), encoding="utf-8") as fh:
        r = json.load(fh)
    if r.get("benchmark") != "pil_cost":
        raise DocError(f"{PIL_COST_JSON}: not a run_pil_cost.py report")
    rows = [[f"`{x['board']}`", f"`{x['scenario']}`", g(x["pil_wall_per_sim_s"], 3),
             g(x["pil_wall_s"][1] / x["durations_s"][1], 3), g(x["sil_wall_per_sim_s"], 2),
             g(x["pil_over_sil"], 3)]
            for x in r["runs"]]
    m = r["machine"]
    d = r["runs"][0]["durations_s"] if r["runs"] else ["-", "-"]
    head = ["board", "scenario", "PIL wall s per simulated s (slope)",
            f"PIL wall s per simulated s ({g(d[1], 2)} s run, start included)",
            "SIL wall s per simulated s", "PIL / SIL wall"]
    return (table(head, rows) + "\n\n"
            f"Measured with `{r['command']}` (runs of {g(d[0], 2)} s and {g(d[1], 2)} s simulated; "
            f"the motor `{r['runs'][0]['motor'] if r['runs'] else '-'}`) on {m['nproc']} "
            f"{m['machine']} cores, 1-minute load average {g(m['loadavg_1min_start'], 2)} at the "
            f"start and {g(m['loadavg_1min_end'], 2)} at the end: re-run it on your machine.\n")


# ---------------------------------------------------------------------------
# Documents

def docs(root=ROOT):
    out = []
    for dp, dn, fn in os.walk(root):
        dn[:] = sorted(d for d in dn if d not in SKIP_DIRS)
        for n in sorted(fn):
            if n.endswith(".md"):
                out.append(os.path.join(dp, n))
    return out


def regions(root=ROOT):
    """NAME -> (path, body); errors for unknown or duplicated regions."""
    found, errors = {}, []
    for p in docs(root):
        text = read_text(p)
        opened = GEN_OPEN_RE.findall(text)
        closed = GEN_RE.findall(text)
        if len(opened) != len(closed):
            errors.append(f"{os.path.relpath(p, root)}: a gen region is not closed")
        for name, body in closed:
            if name in found:
                errors.append(f"gen:{name} appears twice ({os.path.relpath(found[name][0], root)}, "
                              f"{os.path.relpath(p, root)})")
            elif name not in FIGURES:
                errors.append(f"{os.path.relpath(p, root)}: unknown region gen:{name}")
            found[name] = (p, body)
    return found, errors


def rewrite(path, name, body):
    text = read_text(path)
    new = re.sub(r"(<!-- gen:" + re.escape(name) + r" -->\n).*?(<!-- /gen:" + re.escape(name) + r" -->)",
                 lambda m: m.group(1) + body + m.group(2), text, count=1, flags=re.DOTALL)
    if new != text:
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(new)
        return True
    return False


def compare(doc, fresh, tol):
    """None if equal within tol (abs, rel) number by number and exactly
    elsewhere; else a description of the first difference."""
    dl, fl = doc.rstrip("\n").split("\n"), fresh.rstrip("\n").split("\n")
    if len(dl) != len(fl):
        return f"{len(dl)} lines in the document, {len(fl)} in the fresh rendering"
    a_tol, r_tol = tol
    for i, (a, b) in enumerate(zip(dl, fl, strict=False)):
        if a == b:
            continue
        ta, tb = NUM_RE.split(a), NUM_RE.split(b)
        na, nb = NUM_RE.findall(a), NUM_RE.findall(b)
        bad = ta != tb or len(na) != len(nb)
        if not bad:
            for xs, ys in zip(na, nb, strict=False):
                x, y = float(xs), float(ys)
                if abs(x - y) > a_tol + r_tol * abs(y):
                    bad = True
                    break
        if bad:
            return f"line {i + 1}:\n    document: {a}\n    fresh:    {b}"
    return None


# ---------------------------------------------------------------------------
# Links

LINK_RE = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
CODE_RE = re.compile(r"`([^`\s]+)`")
FENCE_RE = re.compile(r"^```.*?^```", re.DOTALL | re.MULTILINE)


def _expand(p):
    m = re.search(r"\{([^{}]*)\}", p)
    if not m:
        return [p]
    out = []
    for alt in m.group(1).split(","):
        out += _expand(p[:m.start()] + alt + p[m.end():])
    return out


def check_links(root=ROOT):
    errors = []
    for p in docs(root):
        text = read_text(p)
        rel = os.path.relpath(p, root)
        prose = FENCE_RE.sub("", text)
        for m in LINK_RE.finditer(prose):
            target = m.group(1)
            if re.match(r"^[a-z][a-z0-9+.-]*:", target) or target.startswith("#"):
                continue
            path = target.split("#")[0]
            if not os.path.exists(os.path.normpath(os.path.join(os.path.dirname(p), path))):
                errors.append(f"{rel}: link ({target}) names nothing")
        for m in CODE_RE.finditer(prose):
            c = m.group(1).rstrip(".,;:")
            if not c.startswith(TOP_DIRS) or re.search(r"[<>*$…|]|\.\.\.", c):
                continue
            for q in _expand(c.split(":")[0]):
                if not os.path.exists(os.path.join(root, q)):
                    errors.append(f"{rel}: `{c}` names nothing")
    return errors


# ---------------------------------------------------------------------------

def parse_inputs(items):
    out = {}
    for it in items or []:
        k, sep, v = it.partition("=")
        if not sep:
            raise DocError(f"--input {it}: expected NAME=PATH")
        out[k] = v
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mode", choices=["write", "check", "links", "list", "selftest"])
    ap.add_argument("--input", action="append", help="NAME=PATH of a binary the figures run")
    ap.add_argument("--inputs", help="a file of NAME=PATH lines (build/host/tools/docs/inputs.txt)")
    ap.add_argument("--only", action="append", help="only these figures (write)")
    ap.add_argument("--figures", action="store_true", help="write: also regenerate the PNGs")
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args(argv)
    try:
        return _main(a)
    except DocError as e:
        print(f"gen_docs: {e}", file=sys.stderr)
        return 1


def selftest():
    """The checks themselves must be able to fail: each planted defect is
    caught, and what is right passes."""
    bad = []
    t = "| a | 1.23 |\n| b | 4e-5 |\n"
    if compare(t, t, (0.0, 0.0)) is not None:
        bad.append("compare: an identical rendering differs")
    if compare(t, t.replace("1.23", "1.24"), (0.0, 0.0)) is None:
        bad.append("compare: a changed number passes at tolerance 0")
    if compare(t, t.replace("1.23", "1.24"), (0.02, 0.0)) is not None:
        bad.append("compare: a number within the tolerance fails")
    if compare(t, t.replace("1.23", "1.3"), (0.02, 0.0)) is None:
        bad.append("compare: a number beyond the tolerance passes")
    if compare(t, t.replace("| b", "| c"), (1.0, 1.0)) is None:
        bad.append("compare: changed text passes")
    if compare(t, t + "| c | 1 |\n", (1.0, 1.0)) is None:
        bad.append("compare: an added line passes")
    with tempfile.TemporaryDirectory() as root:
        os.makedirs(os.path.join(root, "tools", "x"))
        open(os.path.join(root, "tools", "x", "here.py"), "w").close()
        with open(os.path.join(root, "tools", "x", "README.md"), "w") as fh:
            fh.write("[ok](here.py) [gone](gone.md) `tools/x/here.py` `tools/x/{here,nope}.py`\n"
                     "[web](https://example.org) `build/host/x` `tools/x/<cap>/`\n"
                     "```\n[in a fence](nothing.md) `tools/none`\n```\n"
                     "<!-- gen:no-such-figure -->\n<!-- /gen:no-such-figure -->\n"
                     "<!-- gen:foc-rise -->\n")
        errs = check_links(root)
        want = ["(gone.md)", "`tools/x/{here,nope}.py`"]
        for w in want:
            if not any(w in e for e in errs):
                bad.append(f"links: {w} not reported")
        if len(errs) != len(want):
            bad.append(f"links: expected {len(want)} errors, got {errs}")
        _, rerr = regions(root)
        if not any("unknown region gen:no-such-figure" in e for e in rerr):
            bad.append("regions: an unknown region passes")
        if not any("not closed" in e for e in rerr):
            bad.append("regions: an unclosed region passes")
    for b in bad:
        print("FAIL " + b)
    print(f"selftest: {len(bad)} failures")
    return 1 if bad else 0


def _main(a):
    if a.mode == "selftest":
        return selftest()
    if a.mode == "list":
        for n, fig in FIGURES.items():
            print(f"{n:22s} checked {fig.reason}")
        return 0
    link_errors = check_links()
    if a.mode == "links":
        for e in link_errors:
            print(e)
        print(f"links: {len(link_errors)} broken")
        return 1 if link_errors else 0
    items = list(a.input or [])
    if a.inputs:
        with open(a.inputs) as fh:
            items = [line.strip() for line in fh if line.strip()] + items
    inputs = parse_inputs(items)
    ctx = Ctx(inputs, a.jobs)
    found, errors = regions()
    missing = [n for n in FIGURES if n not in found]
    if a.mode == "write":
        names = a.only or [n for n in FIGURES if n in found]
        for n in names:
            if n not in found:
                raise DocError(f"no region gen:{n} in any README.md")
        figs = [FIGURES[n] for n in names]
        ctx.prefetch([s for fig in figs for s in (fig.needs() if callable(fig.needs) else fig.needs)])
        changed = 0
        for fig in figs:
            if rewrite(found[fig.name][0], fig.name, _run_figure(fig, ctx)):
                changed += 1
                print(f"wrote gen:{fig.name} in {os.path.relpath(found[fig.name][0], ROOT)}")
        if a.figures:
            write_figures(ctx, a.only)
        for e in errors + [f"no region for figure {n}" for n in missing] + link_errors:
            print("warning: " + e, file=sys.stderr)
        print(f"{len(figs)} figures, {changed} regions changed")
        return 0
    # check
    errors += [f"figure {n} has no region in any README.md" for n in missing]
    figs = [FIGURES[n] for n in found if n in FIGURES]
    ctx.prefetch([s for fig in figs for s in (fig.needs() if callable(fig.needs) else fig.needs)])
    for fig in figs:
        path, body = found[fig.name]
        diff = compare(body, _run_figure(fig, ctx), fig.tol)
        if diff:
            errors.append(f"{os.path.relpath(path, ROOT)}: gen:{fig.name} disagrees with a fresh "
                          f"run ({fig.reason}); {diff}")
        else:
            print(f"ok  gen:{fig.name} ({os.path.relpath(path, ROOT)})")
    errors += link_errors
    for e in errors:
        print("FAIL " + e)
    print(f"docs: {len(figs)} figures checked, {len(link_errors)} broken links, {len(errors)} errors")
    if errors:
        print("To regenerate: cmake --build --preset host --target docs")
    return 1 if errors else 0


# ---------------------------------------------------------------------------
# The committed PNGs (write --figures): the plot scripts on fresh runs. Not
# compared by `check`: matplotlib's output differs between versions; the
# numbers they show are in the checked tables.

PNGS = [("pi2d-paper.png", mcsim("pi2d-paper"), ["tools/plot/pi2d_figs.py", "paper"]),
        ("pi2d-motor.png", mcsim("pi2d-motor"), ["tools/plot/pi2d_figs.py", "motor"]),
        ("csmc-sampled.png", mcsim("csmc-sampled"), None),
        ("thermal-duty.png", [thermal_src("odrive-d5065", "odrive-v36-24v", "1"),
                              thermal_src("odrive-d5065", "odrive-v36-24v", "0")],
         ["tools/plot/power_figs.py", "thermal"]),
        ("bus-limits.png", [bus_src("odrive-d5065", "odrive-v36-24v", "on"),
                            bus_src("odrive-d5065", "odrive-v36-24v", "off")],
         ["tools/plot/power_figs.py", "bus"]),
        (COG_PNG, cog_srcs(), ["tools/plot/cogging_figs.py", "ripple"])]


def write_figures(ctx, only=None):
    """Every PNG, or with --only those whose name (without .png) is listed."""
    dst = os.path.join(ROOT, "tools", "plot", "figures")
    for png, src, cmd in PNGS:
        if only and png[:-4] not in only:
            continue
        if cmd and cmd[1] == "ripple":  # cogging_figs.py: LABEL OFF.json ON.json ... PNG
            rs = [ctx.get(x) for x in src]
            args = []
            for i in range(0, len(rs), 2):
                lab, _m, _b, fr, _ac = COG_RUNS[i]
                args += [f"{lab}\n{100 * float(fr):g} % rated",
                         *[os.path.join(os.path.dirname(r["csv"]), "cogging.json") for r in rs[i:i + 2]]]
            run([sys.executable, os.path.join(ROOT, cmd[0]), *args, os.path.join(dst, png)])
        elif isinstance(src, list):  # several runs, one figure (power_figs.py)
            rs = [ctx.get(x) for x in src]
            extra = [g(rs[0]["summary"]["t_winding_limit_c"], 6)] if cmd[1] == "thermal" else []
            run([sys.executable, os.path.join(ROOT, cmd[0]), cmd[1], *[r["csv"] for r in rs],
                 *extra, os.path.join(dst, png)])
        elif cmd:
            r = ctx.get(src)
            run([sys.executable, os.path.join(ROOT, cmd[0]), cmd[1], r["csv"], os.path.join(dst, png)])
        else:
            r = ctx.get(src)
            tmp = ctx.workdir(("png", png))
            run([sys.executable, os.path.join(ROOT, "tools", "plot", "csmc_figs.py"),
                 os.path.dirname(r["csv"]), tmp])
            os.replace(os.path.join(tmp, png), os.path.join(dst, png))
        print(f"wrote tools/plot/figures/{png}")


if __name__ == "__main__":
    sys.exit(main())
