"""Campaigns: many SIL runs of one scenario over swept parameters, on Dask.

A campaign file (TOML; format in tools/mdtool/README.md):

    [campaign]
    name = "current-loop-rise"
    scenario = "current-step"
    motor = "../../sim/motors/odrive-d5065.toml"   # relative to this file
    board = "../../sim/motors/odrive-v36-24v.toml"
    duration_s = 0.02        # optional: the scenario's own otherwise
    seed = 1                 # seeds the draws and each run's own seed
    samples = 1              # draws per grid point of the [sweep] distributions

    [fixed]                  # --set in every run
    csv_every = 100

    [sweep]                  # grids (product) and distributions (sampled)
    iq_step_a = [2.0, 5.0]
    current_bw_rad_s = { start = 500.0, stop = 2000.0, num = 4 }
    r_scale = { dist = "uniform", low = 0.8, high = 1.2 }

    [pass]                   # every criterion must hold; expressions over the summary
    fast = "iq_rise_time_ratio < 1.25"

Runs are numbered (run_id) in a fixed order: the grid in file order, the
last key fastest, `samples` draws per grid point. Each run's draws and its
seed come from numpy's default_rng([seed, run_id]), so a run depends on its
row alone, not on which worker ran it or in which order.

Results: OUT/parts/part-NNNNNNNN.parquet, one per finished chunk of runs
(written atomically: an interrupted campaign resumes from them and redoes
no finished run), merged into OUT/results.parquet at the end. One row per
run: run_id, seed, status (pass, fail, fault, refused), error, pass.<name>,
in.<key> (every parameter set), out.<key> (the summary), the scenario, the
motor and board files (paths and SHA-256) and the firmware's git hash.
"""
from __future__ import annotations

import hashlib
import json
import math
import os
import re
import socket
import sys
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .expr import CONSTS, FUNCS, Criterion, Expr, ExprLimit  # noqa: F401 (Expr, ExprLimit: the API)
from .parquet import read_parquet, write_parquet

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib  # type: ignore


class CampaignError(ValueError):
    """A malformed campaign file: "FILE:LINE: reason"."""


MAX_RUNS = 100_000_000          # runs of one campaign
MAX_RANGE_POINTS = 1_000_000    # values of one {start, stop, num} range
MAX_FILE_BYTES = 16 << 20       # a campaign file (the shipped ones: < 10 kB)


# ------------------------------------------------------------ file locations
class _Lines:
    """Line numbers of tables and keys in a TOML text (for error messages)."""

    def __init__(self, text: str):
        self.tables: dict[str, int] = {}
        self.keys: dict[tuple[str, str], int] = {}
        table = ""
        for n, line in enumerate(text.splitlines(), 1):
            s = line.strip()
            m = re.match(r"^\[\s*([A-Za-z0-9_.\-\"' ]+?)\s*\]", s)
            if m and not s.startswith("[["):
                table = m.group(1).replace('"', "").replace("'", "")
                self.tables.setdefault(table, n)
                continue
            m = re.match(r"^([A-Za-z0-9_\-\"'.]+)\s*=", s)
            if m:
                self.keys.setdefault((table, m.group(1).strip("\"'")), n)

    def of(self, table: str, key: str | None = None) -> int:
        if key is not None and (table, key) in self.keys:
            return self.keys[(table, key)]
        return self.tables.get(table, 1)


# ----------------------------------------- pass criteria and derived values
# the language and its limits: mdtool/expr.py
_FUNCS, _CONSTS = FUNCS, CONSTS


# ------------------------------------------------------------------ the file
@dataclass
class Axis:
    key: str
    values: list | None = None      # a grid
    dist: dict | None = None        # a distribution
    var: bool = False               # [vars]: a helper value, not given to the scenario


@dataclass
class Campaign:
    path: str
    name: str
    scenario: str
    motor: str | None
    board: str | None
    duration_s: float | None
    seed: int
    samples: int
    fixed: dict[str, Any]
    axes: list[Axis]
    criteria: list[Criterion]
    sha256: str
    has_seed_param: bool = False
    param_specs: dict[str, dict] = field(default_factory=dict)
    derived: list[tuple[str, Expr]] = field(default_factory=list)  # [derived], in file order

    @property
    def grid(self) -> list[Axis]:
        return [a for a in self.axes if a.values is not None]

    @property
    def dists(self) -> list[Axis]:
        return [a for a in self.axes if a.dist is not None]

    def n_runs(self) -> int:
        n = 1
        for a in self.grid:
            n *= len(a.values)
        return n * self.samples

    def run_inputs(self, run_id: int) -> dict[str, Any]:
        """The run's parameters, helper values ([vars]) and seed, from run_id
        alone. "refuse" names a derived value that could not be computed."""
        if not 0 <= run_id < self.n_runs():
            raise IndexError(run_id)
        rng = np.random.default_rng([self.seed, run_id])
        seed = int(rng.integers(1, 2**31 - 1))
        g, _ = divmod(run_id, self.samples)
        drawn: dict[str, Any] = {}
        idx = []
        for a in reversed(self.grid):
            g, i = divmod(g, len(a.values))
            idx.append(i)
        for a, i in zip(self.grid, reversed(idx)):
            drawn[a.key] = a.values[i]
        for a in self.dists:
            drawn[a.key] = _draw(rng, a.dist)
        var_keys = {a.key for a in self.axes if a.var}
        params = dict(self.fixed)
        params.update({k: v for k, v in drawn.items() if k not in var_keys})
        variables = {k: v for k, v in drawn.items() if k in var_keys}
        refuse = None
        env = {**params, **variables}
        for key, expr in self.derived:
            try:
                v = expr.value(env)
                if isinstance(v, bool) or not isinstance(v, (int, float)) or (
                        isinstance(v, float) and not math.isfinite(v)):
                    raise ValueError(f"{v!r} is not a finite number")
            except (KeyError, TypeError, ValueError, ArithmeticError) as e:
                refuse = refuse or f"derived {key} = {expr.text!r}: {e}"
                continue
            params[key] = env[key] = v
        return {"run_id": run_id, "seed": seed, "params": params, "vars": variables,
                "refuse": refuse}


_DISTS = {"uniform": ("low", "high"), "loguniform": ("low", "high"), "normal": ("mean", "sd"),
          "choice": ("values",)}


def _draw(rng: np.random.Generator, d: dict) -> Any:
    kind = d["dist"]
    if kind == "uniform":
        return float(rng.uniform(d["low"], d["high"]))
    if kind == "loguniform":
        return float(math.exp(rng.uniform(math.log(d["low"]), math.log(d["high"]))))
    if kind == "normal":
        return float(rng.normal(d["mean"], d["sd"]))
    vals = d["values"]
    return vals[int(rng.integers(0, len(vals)))]


def _number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def load(path: str) -> Campaign:
    """Parse and check a campaign file; CampaignError("FILE:LINE: reason")."""
    from . import sil

    try:
        with open(path, "rb") as f:
            raw = f.read(MAX_FILE_BYTES + 1)
    except OSError as e:
        raise CampaignError(f"{path}:1: cannot read the file: {e.strerror}") from None
    if len(raw) > MAX_FILE_BYTES:
        raise CampaignError(f"{path}:1: more than {MAX_FILE_BYTES} bytes: not a campaign file")
    text = raw.decode("utf-8", errors="replace")
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        m = re.search(r"\(at line (\d+), column \d+\)", str(e))
        line = m.group(1) if m else "1"
        msg = re.sub(r"\s*\(at line \d+, column \d+\)", "", str(e))
        raise CampaignError(f"{path}:{line}: malformed TOML: {msg}") from None
    lines = _Lines(text)

    def err(table: str, key: str | None, reason: str):
        return CampaignError(f"{path}:{lines.of(table, key)}: {reason}")

    known = {"campaign", "fixed", "sweep", "vars", "derived", "pass"}
    for t in doc:
        if t not in known:
            raise err(t, None, f"unknown table [{t}] (a campaign file has: "
                      f"{', '.join(sorted(known))})")
    c = doc.get("campaign")
    if not isinstance(c, dict):
        raise err("campaign", None, "missing [campaign] table")
    ckeys = {"name", "scenario", "motor", "board", "duration_s", "seed", "samples", "description"}
    for k in c:
        if k not in ckeys:
            raise err("campaign", k, f"unknown key '{k}' in [campaign] (known: "
                      f"{', '.join(sorted(ckeys))})")
    for k in ("name", "scenario"):
        if not isinstance(c.get(k), str) or not c[k]:
            raise err("campaign", k, f"[campaign] needs {k} = \"...\" (a non-empty string)")
    if not re.fullmatch(r"[A-Za-z0-9_.\-]+", c["name"]):
        raise err("campaign", "name", "name may hold letters, digits, '_', '-' and '.' only")
    base = os.path.dirname(os.path.abspath(path))

    def file_key(k):
        v = c.get(k)
        if v is None:
            return None
        if not isinstance(v, str) or not v:
            raise err("campaign", k, f"{k} must be a path (a string)")
        return os.path.normpath(os.path.join(base, v))

    motor, board = file_key("motor"), file_key("board")
    dur = c.get("duration_s")
    if dur is not None and not (_number(dur) and 0 < dur <= sil.MAX_DURATION_S):
        raise err("campaign", "duration_s",
                  f"duration_s must be a number in (0, {sil.MAX_DURATION_S:g}] s (one simulated "
                  "hour: the longest run mcsim takes)")
    seed = c.get("seed", 1)
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        raise err("campaign", "seed", "seed must be a non-negative integer")
    fixed = doc.get("fixed", {})
    sweep = doc.get("sweep", {})
    variables = doc.get("vars", {})
    derived = doc.get("derived", {})
    passes = doc.get("pass", {})
    for t, v in (("fixed", fixed), ("sweep", sweep), ("vars", variables), ("derived", derived),
                 ("pass", passes)):
        if not isinstance(v, dict):
            raise err(t, None, f"[{t}] must be a table")

    # The scenario, its files and its parameters, as mcsim checks them.
    scen = {s["name"]: s for s in sil.scenarios()}
    if c["scenario"] not in scen:
        raise err("campaign", "scenario", f"unknown scenario '{c['scenario']}' (see 'mcsim list')")
    if dur is not None and not scen[c["scenario"]]["takes_duration"]:
        raise err("campaign", "duration_s",
                  f"scenario '{c['scenario']}' takes no duration_s: its length is set by what it "
                  "does")
    try:
        specs = {p["key"]: p for p in sil.params(c["scenario"], motor, board)}
    except sil.UsageError as e:
        raise err("campaign", "motor" if motor else "scenario", str(e)) from None

    def edits_file(key):  # motor.KEY / board.KEY: the run edits its files (mcsim --set)
        return bool(motor) and key.split(".", 1)[0] in ("motor", "board") and "." in key

    def check_value(table, key, v):
        if edits_file(key):  # checked by mcsim's file rules when the run starts
            if isinstance(v, bool) or not (_number(v) or isinstance(v, str)):
                raise err(table, key, f"value {v!r} for {key}: a number or a string is expected")
            return
        spec = specs[key]
        if isinstance(v, str):
            if v not in spec["choices"]:
                names = ", ".join(spec["choices"]) or "none"
                raise err(table, key, f"value '{v}' for {key}: a number or one of: {names}")
            return
        if not _number(v):
            raise err(table, key, f"value {v!r} for {key}: a finite number is expected")
        if not spec["min"] <= v <= spec["max"]:
            raise err(table, key, f"value {v} for {key} is out of range "
                      f"[{spec['min']:g}, {spec['max']:g}] {spec['unit']}")

    def check_key(table, key):
        if key not in specs and not edits_file(key):
            raise err(table, key, f"unknown key '{key}' (scenario {c['scenario']} takes: "
                      f"{', '.join(specs) or 'none'})")

    for k, v in fixed.items():
        check_key("fixed", k)
        check_value("fixed", k, v)
    def parse_axis(table, k, v, is_var):
        """A grid, a range or a distribution of [sweep] or [vars]."""
        def check_var(t, key, x):
            if not _number(x):
                raise err(t, key, f"value {x!r} for {key}: a finite number is expected")

        check = check_var if is_var else check_value
        if isinstance(v, list):
            if not v:
                raise err(table, k, f"empty grid for {k}")
            if len({type(x) is str for x in v}) > 1:
                raise err(table, k, f"grid for {k} mixes names and numbers")
            for x in v:
                check(table, k, x)
            return Axis(k, values=list(v), var=is_var)
        if isinstance(v, dict) and "dist" not in v:
            want = {"start", "stop", "num"}
            if set(v) - (want | {"log"}) or not want <= set(v):
                raise err(table, k, f"a range for {k} is {{ start = A, stop = B, num = N "
                          f"[, log = true] }}")
            if not (_number(v["start"]) and _number(v["stop"]) and isinstance(v["num"], int)
                    and not isinstance(v["num"], bool) and v["num"] >= 1):
                raise err(table, k, f"range for {k}: start and stop numbers, num an integer >= 1")
            if v["num"] > MAX_RANGE_POINTS:  # refused before a value is made
                raise err(table, k, f"range for {k}: num = {v['num']}: at most "
                          f"{MAX_RANGE_POINTS} points in a range (a campaign: at most "
                          f"{MAX_RUNS} runs)")
            if v.get("log", False):
                if v["start"] <= 0 or v["stop"] <= 0:
                    raise err(table, k, f"log range for {k} needs positive start and stop")
                vals = np.geomspace(v["start"], v["stop"], v["num"]).tolist()
            else:
                vals = np.linspace(v["start"], v["stop"], v["num"]).tolist()
            for x in vals:
                check(table, k, x)
            return Axis(k, values=vals, var=is_var)
        if isinstance(v, dict):
            kind = v.get("dist")
            if kind not in _DISTS:
                raise err(table, k, f"unknown dist '{kind}' for {k} (known: "
                          f"{', '.join(_DISTS)})")
            need = set(_DISTS[kind]) | {"dist"}
            if set(v) != need:
                raise err(table, k, f"dist '{kind}' for {k} takes exactly: "
                          f"{', '.join(_DISTS[kind])}")
            if kind == "choice":
                if not isinstance(v["values"], list) or not v["values"]:
                    raise err(table, k, f"choice for {k} needs a non-empty list of values")
                for x in v["values"]:
                    check(table, k, x)
            else:
                a, b = (v[n] for n in _DISTS[kind])
                if not (_number(a) and _number(b)):
                    raise err(table, k, f"dist '{kind}' for {k}: numbers expected")
                if kind in ("uniform", "loguniform"):
                    if not a < b or (kind == "loguniform" and a <= 0):
                        raise err(table, k, f"dist '{kind}' for {k} needs "
                                  f"{'0 < ' if kind == 'loguniform' else ''}low < high")
                    check(table, k, a)
                    check(table, k, b)
                elif b < 0:
                    raise err(table, k, f"normal for {k} needs sd >= 0")
            return Axis(k, dist=dict(v), var=is_var)
        raise err(table, k, f"{table} {k}: a list (grid), a range {{start, stop, num}} or a "
                  f"distribution {{dist = ...}}")

    axes: list[Axis] = []
    for k, v in sweep.items():
        check_key("sweep", k)
        if k in fixed:
            raise err("sweep", k, f"'{k}' is both fixed and swept")
        axes.append(parse_axis("sweep", k, v, False))
    # [vars]: helper values (grids or draws) that [derived] computes parameters
    # from; recorded in the row as var.NAME, not given to the scenario.
    for k, v in variables.items():
        if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", k) or k in _FUNCS or k in _CONSTS:
            raise err("vars", k, f"var name '{k}': letters, digits and '_', not a function "
                      f"or constant name")
        if k in specs or k in fixed or k in sweep:
            raise err("vars", k, f"var '{k}' is also a parameter of the campaign")
        axes.append(parse_axis("vars", k, v, True))
    # [derived]: parameters computed from the others, in file order.
    known_names = set(fixed) | set(sweep) | set(variables)
    derived_exprs: list[tuple[str, Expr]] = []
    for k, v in derived.items():
        check_key("derived", k)
        if k in known_names:
            raise err("derived", k, f"'{k}' is derived and also fixed, swept or a var")
        if not isinstance(v, str):
            raise err("derived", k, f"derived {k} must be an expression in a string")
        try:
            e = Expr(f"derived {k}", v)
        except ValueError as ex:
            raise err("derived", k, str(ex)) from None
        unknown = sorted(e.names() - known_names)
        if unknown:
            raise err("derived", k, f"derived {k} reads {', '.join(unknown)}: not fixed, swept, "
                      f"a var or derived above it")
        derived_exprs.append((k, e))
        known_names.add(k)
    has_dist = any(a.dist is not None for a in axes)
    samples = c.get("samples", 1)
    if not isinstance(samples, int) or isinstance(samples, bool) or samples < 1:
        raise err("campaign", "samples", "samples must be an integer >= 1")
    if samples > 1 and not has_dist:
        raise err("campaign", "samples", "samples > 1 needs a distribution in [sweep] "
                  "(the runs of a grid point would be identical)")
    criteria = []
    for k, v in passes.items():
        if not isinstance(v, str):
            raise err("pass", k, f"pass criterion '{k}' must be an expression in a string")
        try:
            criteria.append(Criterion(k, v))
        except ValueError as e:
            raise err("pass", k, str(e)) from None
    camp = Campaign(path=os.path.abspath(path), name=c["name"], scenario=c["scenario"],
                    motor=motor, board=board, duration_s=float(dur) if dur is not None else None,
                    seed=seed, samples=samples, fixed=dict(fixed), axes=axes, criteria=criteria,
                    sha256=hashlib.sha256(raw).hexdigest(), has_seed_param="seed" in specs,
                    param_specs=specs, derived=derived_exprs)
    if camp.n_runs() > MAX_RUNS:
        raise err("sweep", None, f"{camp.n_runs()} runs: more than {MAX_RUNS}")
    return camp


# -------------------------------------------------------------------- a run
def _sha256(path: str | None) -> str | None:
    if not path:
        return None
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


@dataclass(frozen=True)
class RunSpec:
    """Everything a run depends on (what its row holds)."""
    run_id: int
    seed: int
    scenario: str
    motor: str | None
    board: str | None
    duration_s: float | None
    params: tuple  # ((key, value), ...)
    criteria: tuple  # ((name, expression), ...)
    pass_seed: bool
    variables: tuple = ()  # ((name, value), ...) of [vars]: recorded, not run
    refuse: str | None = None  # a derived value that could not be computed: not run


def specs(camp: Campaign, run_ids) -> list[RunSpec]:
    out = []
    for i in run_ids:
        r = camp.run_inputs(i)
        out.append(RunSpec(i, r["seed"], camp.scenario, camp.motor, camp.board, camp.duration_s,
                           tuple(r["params"].items()),
                           tuple((c.name, c.text) for c in camp.criteria), camp.has_seed_param,
                           tuple(r["vars"].items()), r["refuse"]))
    return out


def run_one(spec: RunSpec) -> dict[str, Any]:
    """One run into one row (the same function serially and on a worker)."""
    from . import sil

    t0 = time.perf_counter()
    params = dict(spec.params)
    row: dict[str, Any] = {"run_id": spec.run_id, "seed": spec.seed}
    if spec.refuse:
        summary, kind, error = {}, "usage", spec.refuse
    else:
        try:
            r = sil.run_raw(spec.scenario, spec.motor, spec.board, params, spec.duration_s,
                            seed=spec.seed if spec.pass_seed else None, trajectory=False)
            summary, kind, error = r.summary, r.error_kind, r.error
        except sil.UsageError as e:
            summary, kind, error = {}, "usage", str(e)
    # kind "verdict": the run ran to its end and judged itself not a pass
    # (mcsim exit 1): "fail", its summary whole, so the criteria are
    # evaluated on it too. kind "failed": it stopped on its way (a drive
    # fault, commissioning stopped with its error): "fault".
    ran = kind in (None, "verdict")
    crit, why = {}, []
    for name, text in spec.criteria:
        ok, reason = Criterion(name, text).judge(summary) if ran else (False, None)
        crit[name] = ok
        if reason:
            why.append(reason)  # a limit of the evaluator refused it: named in the row
    row["status"] = ("refused" if kind == "usage" else "fault" if kind == "failed"
                     else "pass" if kind is None and all(crit.values()) else "fail")
    verdict = summary.get("verdict") if kind in ("failed", "verdict") else None
    if isinstance(verdict, str) and verdict:
        # the named reason (the report groups runs by it); its figures apart
        error = "run failed: " + verdict
        row["verdict_detail"] = summary.get("verdict_detail", "")
    # an evaluator's limit is named after the run's own error (a verdict)
    parts = ([error] if error else []) + why
    row["error"] = "; ".join(parts) if parts else error
    row["pass"] = row["status"] == "pass"
    for name, ok in crit.items():
        row["pass." + name] = ok
    for k, v in params.items():
        row["in." + k] = v
    for k, v in spec.variables:
        row["var." + k] = v
    for k, v in summary.items():
        row["out." + k] = v
    row["scenario"] = spec.scenario
    row["motor"] = spec.motor
    row["board"] = spec.board
    row["duration_s"] = spec.duration_s
    row["firmware_git"] = sil.GIT_HASH
    row["wall_s"] = time.perf_counter() - t0
    row["worker"] = _WORKER  # which process ran it (host:pid): differs between runs
    return row


_WORKER = f"{socket.gethostname()}:{os.getpid()}"


def run_chunk(chunk: list[RunSpec]) -> list[dict[str, Any]]:
    return [run_one(s) for s in chunk]


# ------------------------------------------------------------- the campaign
def _parts_dir(out: str) -> str:
    return os.path.join(out, "parts")


class DamagedPart(CampaignError):
    """A part file that cannot be read (truncated, overwritten, not Parquet)."""

    def __init__(self, path: str, reason: str):
        super().__init__(f"{path}: damaged part ({reason}); `mdtool sweep` into this folder "
                         f"sets it aside and runs its runs again")
        self.path, self.reason = path, reason


def _read_part(path: str, columns: list[str] | None = None):
    """A part as a DataFrame, or DamagedPart naming the file and the reason."""
    import pyarrow as pa

    try:
        df = read_parquet(path, columns=columns)
    except (pa.ArrowException, OSError, ValueError) as e:
        raise DamagedPart(path, (str(e).splitlines() or [type(e).__name__])[0]) from None
    if "run_id" not in df.columns:
        raise DamagedPart(path, "no run_id column")
    return df


def _parts(out: str) -> list[str]:
    d = _parts_dir(out)
    return [os.path.join(d, f) for f in sorted(os.listdir(d))
            if f.endswith(".parquet")] if os.path.isdir(d) else []


def finished_ids(out: str, set_aside: bool = False) -> set[int]:
    """The run ids of OUT's readable parts. A damaged part (a truncated
    file, say) is DamagedPart, or with `set_aside` renamed to
    NAME.damaged (kept for a look) with a note on stderr: its runs are not
    finished, so the sweep runs them again."""
    ids: set[int] = set()
    for path in _parts(out):
        try:
            ids.update(_read_part(path, columns=["run_id"])["run_id"].tolist())
        except DamagedPart as e:
            if not set_aside:
                raise
            os.replace(path, path + ".damaged")
            print(f"mdtool: {path}: damaged part ({e.reason}): set aside as "
                  f"{os.path.basename(path)}.damaged; its runs run again", file=sys.stderr)
    return ids


def _write_part(out: str, rows: list[dict[str, Any]], files: dict) -> None:
    import pandas as pd

    df = pd.DataFrame(rows)
    for k, v in files.items():
        df[k] = v
    write_parquet(df, os.path.join(_parts_dir(out), f"part-{rows[0]['run_id']:09d}.parquet"))


def read_results(out: str):
    """Every finished run of OUT (the parts; results.parquet is their merge).
    A damaged part is DamagedPart (exit 2): `mdtool sweep` runs its runs again."""
    import pandas as pd

    parts = [_read_part(p) for p in _parts(out)]
    if not parts:
        return pd.DataFrame()
    df = pd.concat(parts, ignore_index=True, sort=False)
    return df.sort_values("run_id", kind="stable").reset_index(drop=True)


def _prepare_out(camp: Campaign, out: str) -> None:
    os.makedirs(_parts_dir(out), exist_ok=True)
    man = os.path.join(out, "campaign.json")
    want = {"name": camp.name, "campaign_sha256": camp.sha256, "runs": camp.n_runs(),
            "motor_sha256": _sha256(camp.motor), "board_sha256": _sha256(camp.board)}
    if os.path.exists(man):
        with open(man) as f:
            have = json.load(f)
        for k in want:
            if have.get(k) != want[k]:
                raise CampaignError(
                    f"{camp.path}:1: {out} holds runs of a different campaign ({k} changed: "
                    f"{have.get(k)} -> {want[k]}); finished runs would not match: use another "
                    f"--out or delete {out}")
    else:
        with open(man + ".tmp", "w") as f:
            json.dump(want, f, indent=1)
        os.replace(man + ".tmp", man)
        with open(camp.path, "rb") as src, open(os.path.join(out, "campaign.toml"), "wb") as dst:
            dst.write(src.read())
    for f in os.listdir(_parts_dir(out)):
        if f.endswith(".tmp"):  # a part being written when the campaign was stopped
            os.remove(os.path.join(_parts_dir(out), f))


class _Progress:
    def __init__(self, total: int, done: int, stream=sys.stderr):
        self.total, self.done0, self.done, self.t0 = total, done, done, time.monotonic()
        self.stream, self.last = stream, 0.0
        self.tty = stream.isatty()

    def add(self, n: int, force: bool = False):
        self.done += n
        now = time.monotonic()
        if not force and now - self.last < (0.5 if self.tty else 10.0):
            return
        self.last = now
        el = now - self.t0
        rate = (self.done - self.done0) / el if el > 0 else 0.0
        left = self.total - self.done
        eta = f"{left / rate:.0f} s" if rate > 0 else "?"
        msg = (f"{self.done}/{self.total} runs ({100.0 * self.done / max(1, self.total):.1f} %), "
               f"{rate:.1f} runs/s, ETA {eta}")
        self.stream.write(("\r" + msg + "\033[K") if self.tty else msg + "\n")
        self.stream.flush()

    def close(self):
        self.add(0, force=True)
        if self.tty:
            self.stream.write("\n")


def sweep(path: str, out: str, scheduler: str | None = None, workers: int | None = None,
          serial: bool = False, max_runs: int | None = None, chunk: int | None = None,
          progress: bool = True) -> dict[str, Any]:
    """Run (or resume) a campaign into OUT. Returns counts: total, already
    (finished before), ran, remaining; writes OUT/results.parquet when done."""
    camp = load(path)
    _prepare_out(camp, out)
    files = {"motor_sha256": _sha256(camp.motor), "board_sha256": _sha256(camp.board)}
    total = camp.n_runs()
    done = finished_ids(out, set_aside=True)
    todo = [i for i in range(total) if i not in done]
    if max_runs is not None:
        todo = todo[:max_runs]
    prog = _Progress(total, len(done)) if progress else None
    nworkers = 1 if serial else (workers or os.cpu_count() or 1)
    if chunk is None:
        # About 8 chunks per worker (balance), at most 256 runs a part.
        chunk = max(1, min(256, math.ceil(len(todo) / (8 * nworkers)) if todo else 1))
    chunks = [todo[i:i + chunk] for i in range(0, len(todo), chunk)]
    ran = 0
    if serial or not chunks:
        for ids in chunks:
            rows = run_chunk(specs(camp, ids))
            _write_part(out, rows, files)
            ran += len(rows)
            if prog:
                prog.add(len(rows))
    else:
        from dask.distributed import Client, LocalCluster, as_completed
        import logging

        cluster = None
        if scheduler:
            client = Client(scheduler)
        else:
            cluster = LocalCluster(n_workers=nworkers, threads_per_worker=1, processes=True,
                                   dashboard_address=None, silence_logs=logging.ERROR)
            client = Client(cluster)
        try:
            # The specs are built on the workers from (campaign, ids): small messages.
            futs = [client.submit(_run_ids, camp, ids, pure=False) for ids in chunks]
            for fut in as_completed(futs):
                rows = fut.result()
                _write_part(out, rows, files)
                ran += len(rows)
                if prog:
                    prog.add(len(rows))
                fut.release()
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    if prog:
        prog.close()
    remaining = total - len(done) - ran
    if remaining == 0:
        write_parquet(read_results(out), os.path.join(out, "results.parquet"))
    return {"campaign": camp.name, "out": out, "total": total, "already": len(done), "ran": ran,
            "remaining": remaining}


def _run_ids(camp: Campaign, ids: list[int]) -> list[dict[str, Any]]:
    return run_chunk(specs(camp, ids))


# ----------------------------------------------------------- one row again
def spec_from_row(row) -> RunSpec:
    """The run of a results row, from the row alone."""
    params = tuple((k[3:], _py(v)) for k, v in row.items()
                   if k.startswith("in.") and not _missing(_py(v)))
    variables = tuple((k[4:], _py(v)) for k, v in row.items()
                      if k.startswith("var.") and not _missing(_py(v)))
    crit = ()
    err = row.get("error")
    # A run refused because a [derived] value could not be computed: the row
    # lacks that value, and its reason is the record of it.
    refuse = (err if row.get("status") == "refused" and isinstance(err, str)
              and err.startswith("derived ") else None)
    dur = row.get("duration_s")
    return RunSpec(int(row["run_id"]), int(row["seed"]), row["scenario"], row.get("motor"),
                   row.get("board"), None if dur is None or _nan(dur) else float(dur), params,
                   crit, "out.param.seed" in row, variables,
                   refuse)


def _nan(v) -> bool:
    return isinstance(v, float) and math.isnan(v)


def _py(v):
    return v.item() if hasattr(v, "item") else v


def rerun_row(row) -> tuple[dict[str, Any], list[str]]:
    """Run a results row again; the keys whose values differ (none expected).
    A row from another firmware (firmware_git) may differ: the caller says so."""
    spec = spec_from_row(row)
    new = run_one(spec)
    diffs = []
    for k, v in new.items():
        if k in ("wall_s", "firmware_git", "worker") or k.startswith("pass"):
            continue
        if k == "status" and v in ("pass", "fail"):
            continue  # criteria are not in the row's inputs
        old, val = _py(row.get(k)), _py(v)
        if not (old == val or (_missing(old) and _missing(val))):
            diffs.append(f"{k}: {old!r} -> {val!r}")
    for k, old in row.items():  # columns of other runs are empty in this row
        if (k not in new and not _missing(_py(old)) and not k.startswith("pass")
                and k not in ("motor_sha256", "board_sha256")):
            diffs.append(f"{k}: {old!r} -> (absent)")
    for k in ("motor", "board"):
        if row.get(k) and _sha256(row[k]) != row.get(k + "_sha256"):
            diffs.append(f"{k}_sha256: the file {row[k]} changed since the campaign")
    return new, diffs


def _missing(v) -> bool:
    return v is None or _nan(v)
