"""Reports from a campaign's Parquet: a robustness envelope over two swept
parameters (each cell the worst case over every other parameter) and a
summary table.

    mdtool report OUT [--x KEY] [--y KEY] [--metric KEY]

writes OUT/report/envelope.png, envelope.csv and summary.md. Without
--metric a cell is the worst outcome of its runs (fault > refused > fail >
pass); with --metric out.KEY (or KEY) it is the largest value of that
summary key among its runs (a fault counts as missing).
"""
from __future__ import annotations

import os
from typing import Any

import numpy as np

RANK = {"pass": 0, "fail": 1, "refused": 2, "fault": 3}
COLORS = ["#2e7d32", "#f9a825", "#9e9e9e", "#c62828"]


def _axis(df, key: str, bins: int = 10):
    vals = df[key]
    if vals.nunique() <= 12:
        return vals, sorted(vals.unique())
    cut = __import__("pandas").cut(vals, bins)
    return cut.map(lambda iv: round(iv.mid, 6)).astype(float), sorted(cut.cat.categories.mid)


def swept(df) -> list[str]:
    return [c for c in df.columns if c.startswith("in.") and df[c].nunique(dropna=True) > 1]


def make(out: str, x: str | None = None, y: str | None = None, metric: str | None = None,
         out_dir: str | None = None) -> dict[str, Any]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    from .campaign import read_results

    df = read_results(out)
    if df.empty:
        raise ValueError(f"no finished runs in {out}")
    keys = swept(df)
    x = ("in." + x if x and not x.startswith("in.") else x) or (keys[0] if keys else None)
    y = ("in." + y if y and not y.startswith("in.") else y) or (keys[1] if len(keys) > 1 else None)
    if x is None:
        raise ValueError("the campaign sweeps no parameter")
    out_dir = out_dir or os.path.join(out, "report")
    os.makedirs(out_dir, exist_ok=True)
    d = df.copy()
    d["_x"], xs = _axis(d, x)
    if y is not None:
        d["_y"], ys = _axis(d, y)
    else:
        d["_y"], ys = 0.0, [0.0]
    d["_rank"] = d["status"].map(RANK)
    if metric:
        m = metric if metric.startswith("out.") else "out." + metric
        cell = d.groupby(["_y", "_x"])[m].max()
        title = f"worst (largest) {m[4:]}"
    else:
        cell = d.groupby(["_y", "_x"])["_rank"].max()
        title = "worst outcome over the other parameters"
    grid = np.full((len(ys), len(xs)), np.nan)
    for (yy, xx), v in cell.items():
        grid[ys.index(yy), xs.index(xx)] = v
    fig, ax = plt.subplots(figsize=(6.4, 4.8), dpi=100)
    if metric:
        im = ax.imshow(grid, origin="lower", aspect="auto", cmap="viridis")
        fig.colorbar(im, ax=ax, label=m[4:])
    else:
        ax.imshow(grid, origin="lower", aspect="auto", cmap=ListedColormap(COLORS), vmin=-0.5,
                  vmax=3.5)
        from matplotlib.patches import Patch
        ax.legend(handles=[Patch(color=c, label=k) for k, c in zip(RANK, COLORS)],
                  loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    ax.set_xticks(range(len(xs)), [f"{v:.4g}" for v in xs], rotation=45, fontsize=8)
    ax.set_yticks(range(len(ys)), [f"{v:.4g}" for v in ys] if y else [""], fontsize=8)
    ax.set_xlabel(x[3:])
    ax.set_ylabel(y[3:] if y else "")
    others = [k[3:] for k in keys if k not in (x, y)]
    ax.set_title(title + (f"\n(over {', '.join(others)})" if others else ""), fontsize=9)
    fig.tight_layout()
    png = os.path.join(out_dir, "envelope.png")
    fig.savefig(png)
    plt.close(fig)
    env = os.path.join(out_dir, "envelope.csv")
    cell.rename("value").reset_index().rename(columns={"_x": x, "_y": y or "y"}).to_csv(
        env, index=False)
    md = os.path.join(out_dir, "summary.md")
    with open(md, "w") as f:
        f.write(summary_table(df, x))
    return {"figure": png, "envelope": env, "summary": md, "runs": len(df)}


def summary_table(df, by: str) -> str:
    """Markdown: runs per outcome for each value of `by`, and overall."""
    import pandas as pd

    status = pd.Categorical(df["status"], categories=list(RANK))
    t = pd.crosstab(df[by] if df[by].nunique() <= 12 else pd.cut(df[by], 10), status,
                    dropna=False)
    lines = [f"| {by[3:]} | runs | " + " | ".join(RANK) + " | pass rate |",
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
    fw = ", ".join(sorted(df["firmware_git"].astype(str).unique()))
    return "\n".join(lines) + f"\n\nfirmware {fw}; {n} runs.\n"
