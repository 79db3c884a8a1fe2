"""Reports from a campaign's Parquet: a robustness envelope over two swept
parameters (each cell the worst case over every other parameter), error
histograms against their bounds, and a summary table.

    mdtool report OUT [--x KEY] [--y KEY] [--metric KEY] [--hist KEY=BOUND ...]
                      [--report-dir DIR] [--with-results]

writes DIR (default OUT/report)/envelope.png, envelope.csv and summary.md;
with --hist also histograms.png; with --with-results a copy of the results
(results.parquet) whose file paths are relative to the current directory.

Axes (--x, --y) are swept inputs (in.KEY, the default prefix) or helper
draws (var.KEY); a numeric axis with more than 12 distinct values (a
distribution) is cut into 10 bins, logarithmic when its values are positive,
span more than a decade and are spread logarithmically (their median nearer
their geometric than their arithmetic mean). Without --metric a cell is the worst outcome of
its runs (fault > refused > fail > pass); with --metric out.KEY (or KEY) it
is the largest value of that summary key among its runs (a fault counts as
missing); with --metric pass_rate the share of its runs that pass.
--hist out.KEY=BOUND (or KEY=BOUND) adds the histogram of
|value| / BOUND and a row of the error table (how many runs have a value,
how many within the bound, median, 95th percentile and largest |value|).
"""
from __future__ import annotations

import math
import os
from typing import Any

import numpy as np

from .parquet import write_parquet

RANK = {"pass": 0, "fail": 1, "refused": 2, "fault": 3}
COLORS = ["#2e7d32", "#f9a825", "#9e9e9e", "#c62828"]


def _key(k: str, default: str = "in.") -> str:
    return k if k.startswith(("in.", "var.", "out.")) else default + k


def _axis(df, key: str, bins: int = 10):
    """(cell value of each row, sorted cell values): the values themselves, or
    bin centres (geometric for a positive axis spanning more than a decade)."""
    import pandas as pd

    vals = df[key]
    if (vals.nunique() <= 12 or not pd.api.types.is_numeric_dtype(vals)
            or (pd.api.types.is_integer_dtype(vals) and vals.nunique() <= 24)):
        return vals, sorted(vals.unique())
    lo, hi = float(vals.min()), float(vals.max())
    v = vals.to_numpy(float)
    # Logarithmic bins for values spread logarithmically (a loguniform draw,
    # a log range): the median nearer the geometric than the arithmetic mean.
    if lo > 0 and hi / lo > 10 and abs(math.log(np.median(v) / np.exp(np.mean(np.log(v))))) < \
            abs(math.log(np.median(v) / np.mean(v))):
        edges = np.geomspace(lo, hi, bins + 1)
        mids = np.sqrt(edges[:-1] * edges[1:])
    else:
        edges = np.linspace(lo, hi, bins + 1)
        mids = 0.5 * (edges[:-1] + edges[1:])
    idx = np.clip(np.searchsorted(edges, vals.to_numpy(float), side="right") - 1, 0, bins - 1)
    mids = [float(f"{m:.4g}") for m in mids]
    return pd.Series([mids[i] for i in idx], index=vals.index), mids


def swept(df) -> list[str]:
    return [c for c in df.columns if c.startswith(("in.", "var."))
            and df[c].nunique(dropna=True) > 1]


def parse_hist(spec: str) -> tuple[str, float]:
    """"KEY=BOUND" -> ("out.KEY", BOUND)."""
    k, eq, b = spec.partition("=")
    try:
        bound = float(b)
    except ValueError:
        bound = float("nan")
    if not eq or not k or not (math.isfinite(bound) and bound > 0):
        raise ValueError(f"--hist {spec!r}: KEY=BOUND with a positive BOUND is expected")
    return _key(k, "out."), bound


def make(out: str, x: str | None = None, y: str | None = None, metric: str | None = None,
         out_dir: str | None = None, hists: list[str] | None = None,
         with_results: bool = False) -> dict[str, Any]:
    from .campaign import read_results

    df = read_results(out)
    if df.empty:
        raise ValueError(f"no finished runs in {out}")
    hist_specs = [parse_hist(h) for h in hists or []]
    keys = swept(df)
    x = _key(x) if x else (keys[0] if keys else None)
    y = _key(y) if y else (keys[1] if len(keys) > 1 else None)
    if x is None:
        raise ValueError("the campaign sweeps no parameter")
    for k in [x, y] + [h for h, _ in hist_specs]:
        if k is not None and k not in df.columns:
            raise ValueError(f"no column {k} in {out} (swept: {', '.join(keys)})")
    if metric and metric != "pass_rate" and _key(metric, "out.") not in df.columns:
        raise ValueError(f"no column {_key(metric, 'out.')} in {out}")
    import matplotlib  # after the checks: a refused report costs no plotting set-up

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    out_dir = out_dir or os.path.join(out, "report")
    os.makedirs(out_dir, exist_ok=True)
    d = df.copy()
    d["_x"], xs = _axis(d, x)
    if y is not None:
        d["_y"], ys = _axis(d, y)
    else:
        d["_y"], ys = 0.0, [0.0]
    d["_rank"] = d["status"].map(RANK)
    rate = metric == "pass_rate"
    if rate:
        d["_pass"] = (d["status"] == "pass").astype(float)
        cell = d.groupby(["_y", "_x"])["_pass"].mean()
        title = "share of runs that pass"
    elif metric:
        m = _key(metric, "out.")
        if m not in df.columns:
            raise ValueError(f"no column {m} in {out}")
        cell = d.groupby(["_y", "_x"])[m].max()
        title = f"worst (largest) {m[4:]}"
    else:
        cell = d.groupby(["_y", "_x"])["_rank"].max()
        title = "worst outcome over the other parameters"
    grid = np.full((len(ys), len(xs)), np.nan)
    for (yy, xx), v in cell.items():
        grid[ys.index(yy), xs.index(xx)] = v
    fig, ax = plt.subplots(figsize=(6.4, 4.8), dpi=100)
    if rate:
        im = ax.imshow(grid, origin="lower", aspect="auto", cmap="RdYlGn", vmin=0.0, vmax=1.0)
        fig.colorbar(im, ax=ax, label="passed / runs")
        for (yy, xx), g in d.groupby(["_y", "_x"]):
            ax.text(xs.index(xx), ys.index(yy), f"{int(g['_pass'].sum())}/{len(g)}",
                    ha="center", va="center", fontsize=6)
    elif metric:
        im = ax.imshow(grid, origin="lower", aspect="auto", cmap="viridis")
        fig.colorbar(im, ax=ax, label=m[4:])
    else:
        ax.imshow(grid, origin="lower", aspect="auto", cmap=ListedColormap(COLORS), vmin=-0.5,
                  vmax=3.5)
        from matplotlib.patches import Patch
        ax.legend(handles=[Patch(color=c, label=k) for k, c in zip(RANK, COLORS)],
                  loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
        if df[x].nunique() > 12 or (y and df[y].nunique() > 12):  # a population: runs per cell
            n = d.groupby(["_y", "_x"]).size()
            for (yy, xx), c in n.items():
                ax.text(xs.index(xx), ys.index(yy), str(c), ha="center", va="center",
                        fontsize=6, color="white")
    ax.set_xticks(range(len(xs)), [f"{v:.4g}" for v in xs], rotation=45, fontsize=8)
    ax.set_yticks(range(len(ys)), [f"{v:.4g}" for v in ys] if y else [""], fontsize=8)
    ax.set_xlabel(x.split(".", 1)[1])
    ax.set_ylabel(y.split(".", 1)[1] if y else "")
    others = [k.split(".", 1)[1] for k in keys if k not in (x, y)]
    if others:
        shown = ", ".join(others) if len(others) <= 4 else f"{len(others)} other draws"
        title += f"\n(over {shown})"
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    png = os.path.join(out_dir, "envelope.png")
    fig.savefig(png)
    plt.close(fig)
    env = os.path.join(out_dir, "envelope.csv")
    cell.rename("value").reset_index().rename(columns={"_x": x, "_y": y or "y"}).to_csv(
        env, index=False)
    res: dict[str, Any] = {"figure": png, "envelope": env, "runs": len(df)}
    if hist_specs:
        res["histograms"] = histograms(df, hist_specs, os.path.join(out_dir, "histograms.png"))
    md = os.path.join(out_dir, "summary.md")
    with open(md, "w") as f:
        f.write(summary_table(df, x, hist_specs, out))
    res["summary"] = md
    if with_results:
        res["results"] = _copy_results(df, os.path.join(out_dir, "results.parquet"))
    return res


def _copy_results(df, path: str) -> str:
    """The rows for a repository: motor/board paths relative to the current
    directory (rerun from there), without the worker's host name."""
    d = df.drop(columns=[c for c in ("worker",) if c in df.columns])
    for c in ("motor", "board"):
        if c in d.columns:
            d[c] = d[c].map(lambda p: os.path.relpath(p) if isinstance(p, str) else p)
    write_parquet(d, path)
    return path


def _abs_values(df, key: str) -> np.ndarray:
    v = df[key].to_numpy(dtype=float, na_value=np.nan) if key in df.columns else np.array([])
    return np.abs(v[np.isfinite(v)])


def histograms(df, specs: list[tuple[str, float]], path: str) -> str:
    """One panel per key: the histogram of |value| / bound on a log axis
    (0 and values below 1e-4 of the bound in the first bin), the bound at 1."""
    import matplotlib.pyplot as plt

    n = len(specs)
    cols = min(3, n)
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.4 * cols, 2.6 * rows), dpi=100,
                             squeeze=False)
    edges = np.logspace(-4, 2, 25)
    for i, (key, bound) in enumerate(specs):
        ax = axes[i // cols][i % cols]
        a = _abs_values(df, key) / bound
        within = int(np.sum(a < 1.0))
        ax.hist(np.clip(a, edges[0], edges[-1] * 0.999), bins=edges, color="#1565c0")
        ax.axvline(1.0, color="#c62828", lw=1.2)
        ax.set_xscale("log")
        ax.set_title(f"{key[4:]}\n{within} of {len(a)} within {bound:g}", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.set_xlabel("|value| / bound", fontsize=7)
    for j in range(n, rows * cols):
        axes[j // cols][j % cols].axis("off")
    fig.suptitle(f"{len(df)} runs; runs without a value (faulted) not shown", fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path


def _fmt(v: float) -> str:
    return "-" if not math.isfinite(v) else f"{v:.3g}"


def summary_table(df, by: str, hist_specs: list[tuple[str, float]] | None = None,
                  out: str | None = None) -> str:
    """Markdown: runs per outcome for each value of `by`, and overall; the
    criteria; the error table (hist_specs); the faults and refusals by reason."""
    import pandas as pd

    status = pd.Categorical(df["status"], categories=list(RANK))
    col, _ = _axis(df, by)
    t = pd.crosstab(col, status, dropna=False)
    lines = [f"| {by.split('.', 1)[1]} | runs | " + " | ".join(RANK) + " | pass rate |",
             "|---|---|" + "---|" * len(RANK) + "---|"]
    for k, row in t.iterrows():
        n = int(row.sum())
        lines.append(f"| {k:.4g} | {n} | " if isinstance(k, float) else f"| {k} | {n} | ")
        lines[-1] += " | ".join(str(int(row[c])) for c in RANK) + \
            f" | {100.0 * row['pass'] / n if n else 0:.0f} % |"
    n = len(df)
    counts = df["status"].value_counts()
    lines.append(f"| **all** | {n} | " + " | ".join(str(int(counts.get(c, 0))) for c in RANK)
                 + f" | {100.0 * counts.get('pass', 0) / n:.0f} % |")
    if len(t) != df[by].nunique():
        lines.append(f"\n{by.split('.', 1)[1]}: bin centres of 10 bins.")
    crit = [c for c in df.columns if c.startswith("pass.")]
    ran = df[df["status"].isin(["pass", "fail"])]
    if crit and len(ran):
        lines += ["", f"Criteria over the {len(ran)} runs that finished (pass or fail):", "",
                  "| criterion | held | failed |", "|---|---|---|"]
        for c in crit:
            held = int(ran[c].astype(bool).sum())
            lines.append(f"| {c[5:]} | {held} | {len(ran) - held} |")
    if hist_specs:
        lines += ["", "| value | bound | runs with a value | within | median abs | 95th pct abs "
                  "| largest abs (run) |", "|---|---|---|---|---|---|---|"]
        for key, bound in hist_specs:
            v = (df[key].to_numpy(dtype=float, na_value=np.nan) if key in df.columns
                 else np.full(len(df), np.nan))
            ok = np.isfinite(v)
            a = np.abs(v[ok])
            if len(a):
                worst = int(df["run_id"].to_numpy()[ok][np.argmax(a)])
                med, p95, mx = (float(np.median(a)), float(np.percentile(a, 95)),
                                float(np.max(a)))
                largest = f"{_fmt(mx)} ({worst})"
            else:
                med = p95 = float("nan")
                largest = "-"
            lines.append(f"| {key[4:]} | {bound:g} | {len(a)} | {int(np.sum(a < bound))} | "
                         f"{_fmt(med)} | {_fmt(p95)} | {largest} |")
    bad = df[df["status"].isin(["fault", "refused"])]
    if len(bad):
        lines += ["", "Faults and refusals by reason:", "", "| status | reason | runs | run ids |",
                  "|---|---|---|---|"]
        g = bad.groupby(["status", "error"], dropna=False)["run_id"]
        for (st, err), ids in sorted(g, key=lambda kv: (-len(kv[1]), str(kv[0]))):
            shown = ", ".join(str(int(i)) for i in list(ids)[:8]) + (", ..." if len(ids) > 8
                                                                     else "")
            reason = (str(err).replace(os.getcwd() + os.sep, "").replace("|", "\\|")
                      .replace("\n", " "))
            lines.append(f"| {st} | {reason} | {len(ids)} | {shown} |")
    lines += _where(df, out)
    fw = ", ".join(sorted(df["firmware_git"].astype(str).unique()))
    return "\n".join(lines) + f"\n\nfirmware {fw}; {n} runs.\n"


def _drawn(out: str | None, df) -> list[str]:
    """The inputs drawn from distributions ([sweep] distributions and [vars]
    of OUT/campaign.toml), else every swept numeric input."""
    import pandas as pd

    path = os.path.join(out, "campaign.toml") if out else None
    if path and os.path.exists(path):
        from .campaign import tomllib

        with open(path, "rb") as f:
            doc = tomllib.load(f)
        keys = ["in." + k for k, v in doc.get("sweep", {}).items()
                if isinstance(v, dict) and "dist" in v]
        keys += ["var." + k for k in doc.get("vars", {})]
    else:
        keys = [k for k in swept(df) if df[k].nunique() > 12]
    return [k for k in keys if k in df.columns and pd.api.types.is_numeric_dtype(df[k])]


def _where(df, out: str | None = None) -> list[str]:
    """For a population (inputs drawn from distributions): the median of
    each drawn input per outcome (pass, fail, each fault or refusal reason),
    to show where the failures lie."""
    keys = _drawn(out, df)
    if not keys:
        return []
    reason = df["error"].astype(str).str.rsplit(": ", n=1).str[-1].str.slice(0, 40)
    outcome = df["status"].where(df["status"].isin(["pass", "fail"]),
                                 df["status"] + " " + reason)
    groups = sorted(df.groupby(outcome), key=lambda kv: (kv[0] not in ("pass", "fail"),
                                                         kv[0] != "pass", -len(kv[1]), kv[0]))
    lines = ["", "Where: the median of each drawn input per outcome (runs in brackets).", "",
             "| input | " + " | ".join(f"{name.replace('|', '/')} ({len(g)})"
                                       for name, g in groups) + " |",
             "|---|" + "---|" * len(groups)]
    for k in keys:
        lines.append(f"| {k} | " + " | ".join(f"{g[k].median():.3g}" for _, g in groups) + " |")
    return lines
