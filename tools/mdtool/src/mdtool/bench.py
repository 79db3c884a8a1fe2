"""`mdtool bench-sil`: SIL throughput, printed as JSON; `--md FILE` writes
the same numbers as a Markdown page with the sizing of a 100,000-run
campaign computed from them (docs quote this output, never typed numbers).

Measured, for a `current-step` of --duration seconds (default 1 s):
- one core: runs per second in-process (mdtool.sil, no trajectory kept)
  and as an `mcsim run` subprocess writing its CSV and JSON;
- Dask: the same runs on a local cluster of 1 and of 2 single-threaded
  worker processes, 4 tasks of about 0.25 CPU seconds each per worker;
  efficiency = rate(2) / (2 rate(1));
- the cost of a run that faults early (OVERCURRENT a millisecond in: the
  scenario stops at the fault) against one that runs to the end;
- the scheduler's overhead per task (empty tasks) and the Parquet bytes
  per result row, for sizing.
Wall-clock rates depend on what else the machine runs: the load averages
before and after, the core count and the CPU seconds per run (the
process's own time, which other processes barely change) are recorded
alongside, so a reader can judge.
"""
from __future__ import annotations

import math
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from typing import Any

from .parquet import write_parquet

SCEN = "current-step"
SIZING_RUNS = 100_000
SIZING_CORES = (2, 32, 128, 512)


def _timed(fn, runs: int) -> tuple[float, float]:
    """(runs per wall second, CPU seconds per run of this process)."""
    fn()  # warm-up
    c0, t0 = time.process_time(), time.perf_counter()
    for _ in range(runs):
        fn()
    return runs / (time.perf_counter() - t0), (time.process_time() - c0) / runs


def _find_mcsim() -> str | None:
    for b in ("build/host-release", "build/host"):
        p = os.path.join(b, "sim/cli/mcsim")
        if os.access(p, os.X_OK):
            return p
    return None


def _cpu_model() -> str:
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _timed_chunk(specs) -> tuple[list, float]:
    """A chunk of runs on a worker, with the worker thread's CPU seconds."""
    from . import campaign

    c0 = time.thread_time()
    rows = campaign.run_chunk(specs)
    return rows, time.thread_time() - c0


def _noop(i: int) -> int:
    return i


def _cluster(n_workers: int, per: int, motor: str, board: str, duration: float,
             parquet_dir: str | None = None) -> dict[str, float]:
    """4 tasks of `per` runs per worker, all submitted at once."""
    import logging

    import pandas as pd
    from dask.distributed import Client, LocalCluster, wait

    from . import campaign

    # CRITICAL: a worker's heartbeat racing the cluster's shutdown logs an
    # ERROR that means nothing here.
    with LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                      dashboard_address=None, silence_logs=logging.CRITICAL) as cl, \
            Client(cl) as c:
        spec = campaign.RunSpec(0, 1, SCEN, motor, board, duration, (), (), False)
        wait(c.map(campaign.run_one, [spec] * n_workers, pure=False))  # warm-up
        t0 = time.perf_counter()
        futs = c.map(_timed_chunk, [[spec] * per] * (4 * n_workers), pure=False)
        wait(futs)
        wall = time.perf_counter() - t0
        res = [f.result() for f in futs]
        n = per * len(res)
        out = {"runs": n, "runs_per_s": n / wall, "cpu_s_per_run": sum(r[1] for r in res) / n}
        if n_workers == 1:
            # Scheduler round trip of an empty task, one at a time (latency),
            # and many at once (throughput): what a chunk must outweigh.
            k = 200
            t0 = time.perf_counter()
            for i in range(20):
                c.submit(_noop, i, pure=False).result()
            out["task_latency_s"] = (time.perf_counter() - t0) / 20
            t0 = time.perf_counter()
            wait(c.map(_noop, range(k), pure=False))
            out["task_overhead_s"] = (time.perf_counter() - t0) / k
        if parquet_dir:
            rows = [row for r in res for row in r[0]]
            p = os.path.join(parquet_dir, "rows.parquet")
            write_parquet(pd.DataFrame(rows), p)
            out["parquet_bytes_per_row"] = os.path.getsize(p) / len(rows)
        return out


def _load() -> list[float]:
    return [round(x, 2) for x in os.getloadavg()]


def run(duration: float = 1.0, runs: int = 20, mcsim: str | None = None,
        motor: str = "sim/motors/odrive-d5065.toml", board: str = "sim/motors/odrive-v36-24v.toml",
        scaling: bool = True) -> dict[str, Any]:
    from . import sil

    motor, board = os.path.abspath(motor), os.path.abspath(board)
    t_start = time.perf_counter()
    res: dict[str, Any] = {
        "scenario": SCEN, "duration_s": duration, "runs": runs, "firmware_git": sil.GIT_HASH,
        "build_type": sil.BUILD_TYPE,
        "cpu": _cpu_model(), "nproc": os.cpu_count(),
        "cores_usable": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
        else os.cpu_count(),
        "python": platform.python_version(), "load_avg_before": _load()}
    one = lambda: sil.run_raw(SCEN, motor, board, {}, duration, trajectory=False)  # noqa: E731
    rate, cpu = _timed(one, runs)
    res["inprocess_runs_per_s"] = rate
    res["inprocess_cpu_s_per_run"] = cpu
    res["inprocess_realtime_factor"] = rate * duration
    mcsim = mcsim or _find_mcsim()
    if mcsim:
        with tempfile.TemporaryDirectory() as tmp:
            argv = [mcsim, "run", SCEN, "--motor", motor, "--board", board, "--duration",
                    repr(duration), "--out", tmp]
            n = max(3, runs // 2)
            ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
            rate_s, _ = _timed(lambda: subprocess.run(argv, check=True, capture_output=True), n)
            ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)
            res["mcsim"] = os.path.abspath(mcsim)
            res["mcsim_subprocess_runs_per_s"] = rate_s
            res["mcsim_subprocess_cpu_s_per_run"] = (
                (ru1.ru_utime + ru1.ru_stime - ru0.ru_utime - ru0.ru_stime) / (n + 1))
            res["inprocess_over_subprocess"] = rate / rate_s
    # A run that faults early: the drive told 20 times the motor's
    # inductance (its current loop's gain 20 times too high) trips
    # OVERCURRENT on the current step; the scenario stops at the fault.
    bad = {"iq_step_a": 50, "model_l_scale": 20}
    r = sil.run_raw(SCEN, motor, board, bad, duration, trajectory=True)
    res["fault_run_error"] = r.error
    res["fault_run_sim_s"] = float(r.data[-1][0]) if len(r.data) else None
    f_rate, f_cpu = _timed(lambda: sil.run_raw(SCEN, motor, board, bad, duration,
                                               trajectory=False), max(3, runs))
    res["fault_run_s"] = 1.0 / f_rate
    res["fault_run_cpu_s"] = f_cpu
    res["pass_run_s"] = 1.0 / rate
    res["fault_cost_ratio"] = res["fault_run_s"] / res["pass_run_s"]
    if scaling:
        # Tasks of about 0.25 s of CPU (at least 4 runs): the scaling of the
        # runs, not of the scheduler's overhead per task (measured apart).
        per = max(4, math.ceil(0.25 / max(cpu, 1e-6)))
        with tempfile.TemporaryDirectory() as tmp:
            c1 = _cluster(1, per, motor, board, duration)
            c2 = _cluster(2, per, motor, board, duration, parquet_dir=tmp)
        res.update({
            "dask_runs_per_task": per, "dask_1_worker_runs": c1["runs"],
            "dask_2_workers_runs": c2["runs"],
            "dask_1_worker_runs_per_s": c1["runs_per_s"],
            "dask_1_worker_cpu_s_per_run": c1["cpu_s_per_run"],
            "dask_2_workers_runs_per_s": c2["runs_per_s"],
            "dask_2_workers_cpu_s_per_run": c2["cpu_s_per_run"],
            "dask_scaling_efficiency": c2["runs_per_s"] / (2 * c1["runs_per_s"]),
            "dask_cpu_efficiency": c1["cpu_s_per_run"] / c2["cpu_s_per_run"],
            "dask_task_latency_s": c1["task_latency_s"],
            "dask_task_overhead_s": c1["task_overhead_s"],
            "parquet_bytes_per_row": c2["parquet_bytes_per_row"]})
    res["load_avg_after"] = _load()
    res["bench_wall_s"] = time.perf_counter() - t_start
    return res


def _h(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


def markdown(r: dict[str, Any], command: str = "mdtool bench-sil") -> str:
    """The benchmark as a Markdown page; every number from `r`, the sizing by
    arithmetic on them."""
    d = r["duration_s"]
    busy = max(r["load_avg_before"][0], r["load_avg_after"][0])
    lines = [
        "# SIL throughput (generated)",
        "",
        f"Generated by `{command}` (tools/mdtool/src/mdtool/bench.py) from its JSON "
        f"([bench.json](bench.json)); do not edit by hand.",
        "",
        f"Firmware `{r['firmware_git']}`, {r['build_type']} build; {r['cpu']}; {r['nproc']} cores "
        f"({r['cores_usable']} usable); Python {r['python']}.",
        f"Machine load (1, 5, 15 min averages): before {r['load_avg_before']}, "
        f"after {r['load_avg_after']}; the benchmark took {r['bench_wall_s']:.0f} s.",
        "",
        f"Run: `{r['scenario']}` on the ODrive D5065 / v3.6 files, {d:g} s simulated, "
        f"{r['runs']} runs per one-core measurement"
        + (f"; Dask: 4 tasks of {r['dask_runs_per_task']} runs per worker."
           if "dask_runs_per_task" in r else "."),
        "",
        "| measurement | runs/s | CPU s per run | note |",
        "|---|---|---|---|",
        f"| in-process (mdtool.sil), one core | {r['inprocess_runs_per_s']:.3g} | "
        f"{r['inprocess_cpu_s_per_run']:.3g} | {r['inprocess_realtime_factor']:.3g}x real time |",
    ]
    if "mcsim_subprocess_runs_per_s" in r:
        lines.append(f"| `mcsim run` subprocess (CSV + JSON), one core | "
                     f"{r['mcsim_subprocess_runs_per_s']:.3g} | "
                     f"{r['mcsim_subprocess_cpu_s_per_run']:.3g} | in-process is "
                     f"{r['inprocess_over_subprocess']:.3g}x faster |")
    if "dask_1_worker_runs_per_s" in r:
        lines += [
            f"| Dask, 1 worker | {r['dask_1_worker_runs_per_s']:.3g} | "
            f"{r['dask_1_worker_cpu_s_per_run']:.3g} | |",
            f"| Dask, 2 workers | {r['dask_2_workers_runs_per_s']:.3g} | "
            f"{r['dask_2_workers_cpu_s_per_run']:.3g} | wall-clock efficiency "
            f"{100 * r['dask_scaling_efficiency']:.0f} %, CPU-time efficiency "
            f"{100 * r['dask_cpu_efficiency']:.0f} % |"]
    lines += [
        f"| a run that faults early ({r['fault_run_error']}, at "
        f"{1e3 * r['fault_run_sim_s']:.3g} ms simulated) | {1 / r['fault_run_s']:.3g} | "
        f"{r['fault_run_cpu_s']:.3g} | {100 * r['fault_cost_ratio']:.2g} % of a full run |",
        "",
        "Wall-clock efficiency = rate(2 workers) / (2 rate(1 worker)); CPU-time "
        "efficiency = CPU seconds per run with 1 worker / with 2 (below 100 % when the "
        "workers slow each other down: shared caches, memory, a busy machine).",
    ]
    if r["build_type"] not in ("Release", "RelWithDebInfo"):
        lines += ["", f"**A {r['build_type']} build**: not what a campaign runs "
                  "(`pip install ./tools/mdtool` builds Release); measure a Release build."]
    if busy > 0.5 * r["nproc"]:
        lines += ["", f"**The machine was busy** (load average up to {busy:g} on {r['nproc']} "
                  "cores while this ran): the wall-clock rates are lower bounds and the "
                  "wall-clock efficiency measures the other processes as much as Dask. The "
                  "CPU seconds per run are the better figure for sizing; rerun "
                  f"`{command}` on an idle machine to measure the scaling."]
    if "dask_2_workers_cpu_s_per_run" not in r:
        return "\n".join(lines) + "\n"
    n = SIZING_RUNS
    c = r["dask_2_workers_cpu_s_per_run"]
    eff = r["dask_scaling_efficiency"]
    core_s = n * c
    chunk = max(1, math.ceil(100 * r["dask_task_overhead_s"] / c))
    rows = [f"| {k} | {_h(core_s / k)} | {_h(core_s / (k * eff))} |" for k in SIZING_CORES]
    fault = r["fault_cost_ratio"]
    lines += [
        "",
        f"## Sizing a {n:,}-run campaign (arithmetic on the numbers above)",
        "",
        f"One {d:g} s run costs c = {c:.3g} CPU seconds in a Dask worker (2 workers), so "
        f"{n:,} runs need {n:,} x c = {core_s / 3600:.3g} core-hours. On K cores the wall "
        f"time is {n:,} x c / (K x E), E the scaling efficiency: E = 1 if cores scale as "
        f"they should on idle nodes, E = {eff:.2f} as measured here.",
        "",
        "| cores K | wall time, E = 1 | wall time, E as measured |",
        "|---|---|---|",
        *rows,
        "",
        f"Runs of another length cost in proportion to the simulated time (the SIL steps "
        f"every PWM period). A run that faults early costs {100 * fault:.2g} % of a full "
        f"one: with a fraction f of such runs the campaign costs (1 - f) + "
        f"{fault:.2g} f of the above.",
        "",
        f"The scheduler costs {1e3 * r['dask_task_overhead_s']:.3g} ms per task (empty "
        f"tasks; {1e3 * r['dask_task_latency_s']:.3g} ms for one round trip): tasks of at "
        f"least {chunk} run{'s' if chunk != 1 else ''} keep it below 1 % of the work "
        f"(`mdtool sweep --chunk`; the default gives each worker about 8 tasks). The "
        f"results take about "
        f"{r['parquet_bytes_per_row']:.0f} bytes per run in Parquet "
        f"(this scenario's {n:,} rows: {n * r['parquet_bytes_per_row'] / 1e6:.3g} MB).",
    ]
    return "\n".join(lines) + "\n"


def main_json(res: dict[str, Any], json_path: str | None, md_path: str | None,
              command: str) -> None:
    import json

    text = json.dumps(res, indent=1)
    if json_path:
        with open(json_path, "w") as f:
            f.write(text + "\n")
    if md_path:
        with open(md_path, "w") as f:
            f.write(markdown(res, command))
    sys.stdout.write(text + "\n")
