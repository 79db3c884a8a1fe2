"""`mdtool bench-sil`: SIL throughput, printed as JSON (docs quote this
command's output, never typed numbers).

- runs per second on one core for a `current-step` of --duration seconds:
  in-process (mdtool.sil, no trajectory kept) and as an `mcsim run`
  subprocess writing its CSV and JSON;
- Dask scaling: the same runs on a local cluster of 1 and of 2 workers
  (efficiency = rate(2) / (2 rate(1)));
- the cost of a run that faults (OVERCURRENT) against one that passes.
"""
from __future__ import annotations

import os
import platform
import subprocess
import tempfile
import time
from typing import Any

SCEN = "current-step"


def _rate(fn, runs: int) -> float:
    fn()  # warm-up
    t0 = time.perf_counter()
    for _ in range(runs):
        fn()
    return runs / (time.perf_counter() - t0)


def _find_mcsim() -> str | None:
    for b in ("build/host-release", "build/host"):
        p = os.path.join(b, "sim/cli/mcsim")
        if os.access(p, os.X_OK):
            return p
    return None


def _cluster_rate(n_workers: int, runs: int, motor: str, board: str, duration: float) -> float:
    import logging

    from dask.distributed import Client, LocalCluster, wait

    from . import campaign

    with LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                      dashboard_address=None, silence_logs=logging.ERROR) as cl, Client(cl) as c:
        spec = campaign.RunSpec(0, 1, SCEN, motor, board, duration, (), (), False)
        wait(c.map(campaign.run_one, [spec] * n_workers, pure=False))  # warm-up
        t0 = time.perf_counter()
        futs = c.map(campaign.run_chunk, [[spec] * 4] * (runs // 4), pure=False)
        wait(futs)
        return 4 * (runs // 4) / (time.perf_counter() - t0)


def run(duration: float = 1.0, runs: int = 20, mcsim: str | None = None,
        motor: str = "sim/motors/odrive-d5065.toml", board: str = "sim/motors/odrive-v36-24v.toml",
        scaling: bool = True) -> dict[str, Any]:
    from . import sil

    motor, board = os.path.abspath(motor), os.path.abspath(board)
    res: dict[str, Any] = {"scenario": SCEN, "duration_s": duration, "runs": runs,
                           "firmware_git": sil.GIT_HASH, "cpu": platform.processor() or
                           platform.machine(), "cores": os.cpu_count(),
                           "load_avg_1min": os.getloadavg()[0]}
    one = lambda: sil.run_raw(SCEN, motor, board, {}, duration, trajectory=False)  # noqa: E731
    res["inprocess_runs_per_s"] = _rate(one, runs)
    res["inprocess_realtime_factor"] = res["inprocess_runs_per_s"] * duration
    mcsim = mcsim or _find_mcsim()
    if mcsim:
        with tempfile.TemporaryDirectory() as tmp:
            argv = [mcsim, "run", SCEN, "--motor", motor, "--board", board, "--duration",
                    repr(duration), "--out", tmp]
            res["mcsim"] = mcsim
            res["mcsim_subprocess_runs_per_s"] = _rate(
                lambda: subprocess.run(argv, check=True, capture_output=True), max(3, runs // 2))
            res["inprocess_over_subprocess"] = (res["inprocess_runs_per_s"]
                                                / res["mcsim_subprocess_runs_per_s"])
    bad = {"iq_step_a": 60, "cur_bw_rad_s": 1e5}
    r = sil.run_raw(SCEN, motor, board, bad, duration, trajectory=False)
    res["fault_run_error"] = r.error
    res["fault_run_s"] = 1.0 / _rate(lambda: sil.run_raw(SCEN, motor, board, bad, duration,
                                                         trajectory=False), max(3, runs // 4))
    res["pass_run_s"] = 1.0 / res["inprocess_runs_per_s"]
    res["fault_cost_ratio"] = res["fault_run_s"] / res["pass_run_s"]
    if scaling:
        r1 = _cluster_rate(1, runs, motor, board, duration)
        r2 = _cluster_rate(2, 2 * runs, motor, board, duration)
        res.update({"dask_1_worker_runs_per_s": r1, "dask_2_workers_runs_per_s": r2,
                    "dask_scaling_efficiency": r2 / (2 * r1)})
    return res
