"""The SIL in-process: mcsim's scenario runner as a Python library.

    from mdtool import sil
    r = sil.run("current-step", motor="sim/motors/odrive-d5065.toml",
                board="sim/motors/odrive-v36-24v.toml", params={"iq_step_a": 5})
    r.trajectory   # pandas DataFrame, the columns of `mcsim run`'s CSV
    r.summary      # dict, the keys of `mcsim run`'s JSON; a nested object
                   # ("identified": {"r_ohm": ...}) as dotted keys "identified.r_ohm"
    r.objects      # the nested objects as they are: {"identified": {"r_ohm": ...}}

The numbers are those of `mcsim run` with the same arguments, bit for bit:
the same C++ function runs (mcsim::execute_run); the CSV prints the
trajectory with %.9g and the JSON the summary with 10 significant digits,
the values here are the full doubles those were printed from.

Errors are exceptions with mcsim's messages (what it prints after "mcsim: "):
UsageError (a ValueError; mcsim's exit code 2) for invalid inputs and
settings a scenario refuses, RunFailed (a RuntimeError; exit code 1) for a
run whose verdict is not a pass (summary["verdict"]: "not settled",
"faulted: OVERCURRENT", ...) or that stopped on its way. Both carry the
partial `summary` and `trajectory` of a run that started.
"""
from __future__ import annotations

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import _sil

#: The commit the extension was built from (git describe --dirty).
GIT_HASH: str = _sil.git_hash
#: CMake's build type of the extension (Debug runs several times slower).
BUILD_TYPE: str = _sil.build_type
#: The longest run mcsim accepts [s] (--duration, a campaign's duration_s).
MAX_DURATION_S: float = _sil.max_duration_s


class UsageError(ValueError):
    """Invalid input, or settings the scenario refuses (mcsim exit code 2)."""

    def __init__(self, message: str, summary: dict | None = None, trajectory=None):
        super().__init__(message)
        self.summary = summary
        self.trajectory = trajectory


class RunFailed(RuntimeError):
    """The run failed on its way, e.g. a drive fault (mcsim exit code 1)."""

    def __init__(self, message: str, summary: dict | None = None, trajectory=None):
        super().__init__(message)
        self.summary = summary
        self.trajectory = trajectory


@dataclass
class Result:
    columns: list[str]
    data: np.ndarray  # (rows, columns), float64
    summary: dict[str, Any]
    error: str | None = None
    # None (passed), "usage" (refused: exit 2), "failed" (stopped on its way:
    # a drive fault, a sequence that stopped, an error) or "verdict" (ran to
    # its end, verdict not a pass); both of the last are exit 1
    error_kind: str | None = None
    objects: dict[str, dict[str, float]] = field(default_factory=dict)

    @property
    def trajectory(self):
        import pandas as pd

        return pd.DataFrame(self.data, columns=self.columns, copy=False)

    @property
    def ok(self) -> bool:
        return self.error is None


def _value(v: Any) -> str:
    """A --set value as mcsim reads it: names stay names, floats exact."""
    if isinstance(v, str):
        return v
    if isinstance(v, bool):
        return "1" if v else "0"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        v = float(v)
        if v.is_integer() and 0 < abs(v) < 2**53:
            # An integral value as an integer: a motor file's integer keys
            # (pole_pairs, encoder_cpr) refuse "7.0", every number key takes
            # "7"; a Parquet column holding ints and NaN comes back as floats.
            return str(int(v))
        return repr(v)  # shortest text that strtod reads back exactly
    raise TypeError(f"parameter value {v!r}: a number or a name is expected")


def _summary(raw: dict) -> dict[str, Any]:
    """Texts and numbers by key; each nested object's numbers as "OBJECT.KEY"."""
    s: dict[str, Any] = dict(raw["texts"])
    s.update(raw["numbers"])
    for name, obj in raw["objects"].items():
        for k, v in obj.items():
            key = f"{name}.{k}"
            if key in s:  # a scenario's naming bug; never silently overwrite
                raise RuntimeError(f"summary key '{key}' is both a number and in object '{name}'")
            s[key] = v
    return s


def run_raw(scenario: str, motor: str | os.PathLike | None = None,
            board: str | os.PathLike | None = None, params: Mapping[str, Any] | None = None,
            duration: float | None = None, seed: int | None = None,
            trajectory: bool = True) -> Result:
    """One run; a failed run is returned (error, error_kind), not raised.
    trajectory=False keeps no rows (data is empty; summary["rows"] counts them).

    Invalid inputs (unknown scenario or key, malformed value, bad motor or
    board file) still raise UsageError: nothing ran.
    """
    sets = [(str(k), _value(v)) for k, v in (params or {}).items()]
    if seed is not None:
        if any(k == "seed" for k, _ in sets):
            raise UsageError("seed given twice (params['seed'] and seed=)")
        sets.append(("seed", _value(int(seed))))
    if duration is not None and not (math.isfinite(duration) and duration > 0):
        raise UsageError(f"malformed duration '{duration}' (a positive number is expected)")
    try:
        raw = _sil.run(scenario, os.fspath(motor) if motor else "",
                       os.fspath(board) if board else "", sets,
                       float(duration) if duration is not None else 0.0, trajectory)
    except _sil.UsageError as e:
        raise UsageError(str(e)) from None
    return Result(columns=list(raw["columns"]), data=raw["data"], summary=_summary(raw),
                  error=raw["error"], error_kind=raw["error_kind"],
                  objects={k: dict(v) for k, v in raw["objects"].items()})


def run(scenario: str, motor: str | os.PathLike | None = None,
        board: str | os.PathLike | None = None, params: Mapping[str, Any] | None = None,
        duration: float | None = None, seed: int | None = None) -> Result:
    """One run of a named scenario, as `mcsim run SCENARIO --motor M --board B
    --set k=v ... [--duration D]`; `seed` sets the scenario's `seed` parameter
    (the sensor-noise generator; scenarios without noise have none).
    Raises UsageError or RunFailed with mcsim's message."""
    r = run_raw(scenario, motor, board, params, duration, seed)
    if r.error_kind == "usage":
        raise UsageError(r.error, r.summary, r.trajectory)
    if r.error_kind in ("failed", "verdict"):
        raise RunFailed(r.error, r.summary, r.trajectory)
    return r


def scenarios() -> list[dict[str, Any]]:
    """The registered scenarios (as `mcsim list`); takes_duration False: the
    run's length is set by what it does and a duration is refused."""
    return [{"name": n, "description": d, "default_duration_s": t, "any_motor": m,
             "takes_duration": td}
            for n, d, t, m, td in _sil.scenarios()]


def params(scenario: str, motor: str | os.PathLike | None = None,
           board: str | os.PathLike | None = None) -> list[dict[str, Any]]:
    """The declared parameters (as `mcsim describe`), with defaults and ranges."""
    try:
        return list(_sil.params(scenario, os.fspath(motor) if motor else "",
                                os.fspath(board) if board else ""))
    except _sil.UsageError as e:
        raise UsageError(str(e)) from None
