"""The `mdtool` command. One subcommand family per module:

    mdtool sweep FILE [--out DIR] [--scheduler ADDRESS] [--workers N] [--serial]
    mdtool rerun OUT RUN_ID        run one row of a campaign again and compare
    mdtool report OUT [--x KEY --y KEY] [--metric KEY] [--hist KEY=BOUND ...]
    mdtool bench-sil [--duration S] [--runs N] [--json FILE] [--md FILE] [--from-json FILE]
    mdtool sil SCENARIO [--motor F] [--board F] [--set k=v ...]   one run, summary as JSON

CAN (mdtool/can; every command: --interface/--channel/--bitrate, --node):
    mdtool scan | status | config ... | run MODE SETPOINT | monitor SIG... |
           record OUT | decode LOG --out DIR | stats LOG | convert SRC DST |
           flash IMAGE [-n NODE ...]

Exit codes: 0 ok, 2 usage error (a malformed campaign file: "FILE:LINE:
reason"; CAN: also a value refused here before sending), 1 failure, 3
campaign stopped before every run finished (--max-runs): run the same
command again to resume; CAN commands: 3 no reply from the drive within the
timeout, 4 refused by the drive (its reason printed); 130 interrupted by
Ctrl-C (SIGINT), 143 by SIGTERM (CAN commands; `run` has sent DISABLE).
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys


def _default_out(path: str) -> str:
    from .campaign import load

    return os.path.join("out", "campaigns", load(path).name)


def cmd_sweep(a) -> int:
    from . import campaign

    out = a.out or _default_out(a.file)
    res = campaign.sweep(a.file, out, scheduler=a.scheduler, workers=a.workers, serial=a.serial,
                         max_runs=a.max_runs, chunk=a.chunk, progress=not a.quiet)
    print(json.dumps(res))
    if res["remaining"]:
        return 3
    if not a.quiet:
        df = campaign.read_results(out)
        counts = df["status"].value_counts().to_dict() if len(df) else {}
        print(f"{out}/results.parquet: {len(df)} runs, " +
              ", ".join(f"{k} {v}" for k, v in sorted(counts.items())), file=sys.stderr)
    return 0


def cmd_rerun(a) -> int:
    from . import campaign

    df = campaign.read_results(a.out)
    sel = df[df["run_id"] == a.run_id]
    if sel.empty:
        print(f"mdtool: no run {a.run_id} in {a.out}", file=sys.stderr)
        return 2
    row = sel.iloc[0].to_dict()
    new, diffs = campaign.rerun_row(row)
    print(json.dumps({"run_id": a.run_id, "status": new["status"], "same": not diffs,
                      "differences": diffs, "firmware_git": new["firmware_git"],
                      "same_firmware": new["firmware_git"] == row.get("firmware_git")}))
    return 0 if not diffs else 1


def cmd_report(a) -> int:
    from . import report

    try:
        res = report.make(a.out, x=a.x, y=a.y, metric=a.metric, out_dir=a.report_dir,
                          hists=a.hist, with_results=a.with_results)
    except ValueError as e:  # no runs, an unknown column, a malformed --hist
        print(f"mdtool: {e}", file=sys.stderr)
        return 2
    print(json.dumps(res))
    return 0


def cmd_bench(a) -> int:
    from . import bench

    if a.from_json:  # the page again from a saved measurement
        with open(a.from_json) as f:
            res = json.load(f)
    else:
        res = bench.run(duration=a.duration, runs=a.runs, mcsim=a.mcsim, motor=a.motor,
                        board=a.board, scaling=not a.no_scaling)
    bench.main_json(res, a.json, a.md, "mdtool bench-sil" + (
        f" --duration {a.duration:g}" if a.duration != 1.0 else "") + (
        f" --runs {a.runs}" if a.runs != 20 else ""))
    return 0


def cmd_sil(a) -> int:
    from . import sil

    params = {}
    for kv in a.set:
        k, eq, v = kv.partition("=")
        if not eq or not k:
            raise sil.UsageError(f"--set expects key=value, got '{kv}'")
        params[k] = v
    r = sil.run(a.scenario, motor=a.motor, board=a.board, params=params, duration=a.duration)
    print(json.dumps({k: (None if isinstance(v, float) and not math.isfinite(v) else v)
                      for k, v in r.summary.items()}, indent=1))
    return 0


def _run_can(a) -> int:
    """A CAN command with its documented exit code every time: CanToolError's
    (2, 3, 4, 1), 130/143 for SIGINT/SIGTERM (Interrupted, after the
    command's clean-up: run's DISABLE), 1 for a bus or file error."""
    from .can.cli import signals_raise
    from .can.errors import CanToolError, Interrupted

    try:
        with signals_raise():
            return a.fn(a)
    except CanToolError as e:
        print(f"mdtool: {e}", file=sys.stderr)
        return e.exit_code
    except Interrupted as e:
        print(f"mdtool: {e}", file=sys.stderr)
        return e.exit_code
    except KeyboardInterrupt:  # before the handlers were in place
        print("mdtool: interrupted by SIGINT", file=sys.stderr)
        return 130
    except OSError as e:  # a file; python-can's CanError (an Exception) below
        print(f"mdtool: {e}", file=sys.stderr)
        return 1
    except Exception as e:
        import can

        if isinstance(e, can.CanError):
            print(f"mdtool: CAN bus error: {e}", file=sys.stderr)
            return 1
        raise


def main(argv=None) -> int:
    from .can.cli import add_parsers, count

    ap = argparse.ArgumentParser(prog="mdtool", description="motor-drive host tool")
    sub = ap.add_subparsers(dest="cmd", required=True)

    s = sub.add_parser("sweep", help="run or resume a campaign (TOML) on Dask")
    s.add_argument("file")
    s.add_argument("--out", help="results folder (default out/campaigns/NAME)")
    s.add_argument("--scheduler", help="address of a running Dask scheduler "
                   "(default: a local cluster on every core)")
    s.add_argument("--workers", type=count(1, 4096), help="local workers (default: the core count)")
    s.add_argument("--serial", action="store_true", help="no Dask: run in this process")
    s.add_argument("--max-runs", type=count(0, 10**9),
                   help="stop after this many new runs (resume later)")
    s.add_argument("--chunk", type=count(1, 1_000_000), help="runs per task and per Parquet part")
    s.add_argument("--quiet", action="store_true", help="no progress")
    s.set_defaults(fn=cmd_sweep)

    s = sub.add_parser("rerun", help="run one campaign row again from the row alone")
    s.add_argument("out")
    s.add_argument("run_id", type=int)
    s.set_defaults(fn=cmd_rerun)

    s = sub.add_parser("report", help="envelope figure and summary table from a campaign")
    s.add_argument("out")
    s.add_argument("--x", help="swept key on the x axis (default: the first)")
    s.add_argument("--y", help="swept key on the y axis (default: the second)")
    s.add_argument("--metric", help="a summary key (out.KEY) to map instead of the worst "
                   "outcome, or pass_rate (the share of runs that pass)")
    s.add_argument("--report-dir", help="where to write (default OUT/report)")
    s.add_argument("--hist", action="append", default=[], metavar="KEY=BOUND",
                   help="histogram of |out.KEY| / BOUND and a row of the error table "
                   "(repeat for more)")
    s.add_argument("--with-results", action="store_true",
                   help="also copy the results (results.parquet, paths relative to here)")
    s.set_defaults(fn=cmd_report)

    s = sub.add_parser("bench-sil", help="runs per second: binding vs mcsim, 1 vs 2 workers")
    s.add_argument("--duration", type=float, default=1.0)
    s.add_argument("--runs", type=int, default=20)
    s.add_argument("--mcsim", help="mcsim binary (default: build/host-release or build/host)")
    s.add_argument("--motor", default="sim/motors/odrive-d5065.toml")
    s.add_argument("--board", default="sim/motors/odrive-v36-24v.toml")
    s.add_argument("--no-scaling", action="store_true")
    s.add_argument("--json", help="also write the JSON to this file")
    s.add_argument("--md", help="write the numbers and the 100,000-run sizing as Markdown")
    s.add_argument("--from-json", help="no measurement: the Markdown from a saved JSON")
    s.set_defaults(fn=cmd_bench)

    s = sub.add_parser("sil", help="one run in-process; the summary as JSON")
    s.add_argument("scenario")
    s.add_argument("--motor")
    s.add_argument("--board")
    s.add_argument("--duration", type=float)
    s.add_argument("--set", action="append", default=[])
    s.set_defaults(fn=cmd_sil)

    add_parsers(sub)

    a = ap.parse_args(argv)
    if a.fn.__module__ == "mdtool.can.cli":
        return _run_can(a)
    from .campaign import CampaignError

    try:
        return a.fn(a)
    except KeyboardInterrupt:
        print("mdtool: interrupted (Ctrl-C); a campaign resumes where it stopped when the "
              "same command runs again", file=sys.stderr)
        return 130
    except CampaignError as e:
        print(f"mdtool: {e}", file=sys.stderr)
        return 2
    except Exception as e:
        from . import sil

        if isinstance(e, sil.UsageError):
            print(f"mdtool: {e}", file=sys.stderr)
            return 2
        if isinstance(e, sil.RunFailed):
            print(f"mdtool: {e}", file=sys.stderr)
            return 1
        raise


if __name__ == "__main__":
    sys.exit(main())
