#!/usr/bin/env python3
"""Turn an mcsim CSV into a PNG figure.

    mcplot.py RUN.csv [-o RUN.png] [--columns a,b,c] [--tmax S] [--title T]

Columns are grouped into stacked subplots by their unit suffix (the part of
the name after the last known unit, e.g. ``i_d_a`` and ``i_q_ref_a`` share an
amperes axis), all against ``t`` in seconds. Reference columns (``*_ref*``)
are drawn dashed. Exit code 2 with a message on a missing or malformed file.
"""
import argparse
import csv
import os
import sys

UNITS = [  # longest first, so "_rad_s" wins over "_s"
    ("_rad_s2", "rad/s²"), ("_rad_s", "rad/s"), ("_rpm", "rpm"), ("_rad", "rad"),
    ("_nm", "N·m"), ("_wb", "Wb"), ("_hz", "Hz"), ("_pu", "p.u."), ("_ohm", "Ω"),
    ("_a", "A"), ("_v", "V"), ("_w", "W"), ("_s", "s"), ("_c", "°C"), ("_1", "1"),
]


def unit_of(name):
    for suffix, label in UNITS:
        if name.endswith(suffix):
            return label
    return None


def load(path):
    try:
        with open(path, newline="") as f:
            rows = list(csv.reader(f))
    except OSError as e:
        raise SystemExit(f"mcplot: cannot read {path}: {e.strerror}") from e
    if len(rows) < 2 or not rows[0] or rows[0][0] != "t":
        raise SystemExit(f"mcplot: {path} is not an mcsim CSV (header must start with 't')")
    header = rows[0]
    cols = {h: [] for h in header}
    for i, r in enumerate(rows[1:], start=2):
        if len(r) != len(header):
            raise SystemExit(f"mcplot: {path}:{i}: {len(r)} fields, header has {len(header)}")
        try:
            for h, v in zip(header, r, strict=True):
                cols[h].append(float(v))
        except ValueError:
            raise SystemExit(f"mcplot: {path}:{i}: not a number") from None
    return header, cols


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv")
    ap.add_argument("-o", "--out")
    ap.add_argument("--columns", help="comma-separated subset of columns")
    ap.add_argument("--tmax", type=float, help="plot only t <= TMAX")
    ap.add_argument("--title")
    a = ap.parse_args(argv)

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    header, cols = load(a.csv)
    names = list(header[1:])
    if a.columns:
        wanted = [c.strip() for c in a.columns.split(",") if c.strip()]
        unknown = [c for c in wanted if c not in cols]
        if unknown:
            raise SystemExit(f"mcplot: unknown column(s): {', '.join(unknown)}")
        names = wanted
    t = cols["t"]
    n = len(t) if a.tmax is None else sum(1 for x in t if x <= a.tmax)

    groups = {}
    for name in names:
        u = unit_of(name)
        key = u if u is not None else name
        groups.setdefault(key, []).append(name)

    fig, axes = plt.subplots(len(groups), 1, sharex=True,
                             figsize=(9, 1.9 * len(groups) + 1.0), squeeze=False)
    for ax, (unit, members) in zip(axes[:, 0], groups.items(), strict=True):
        for name in members:
            style = "--" if "_ref" in name else "-"
            ax.plot(t[:n], cols[name][:n], style, lw=1.2, label=name)
        ax.set_ylabel(unit)
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize=8)
    axes[-1, 0].set_xlabel("t [s]")
    fig.suptitle(a.title or os.path.splitext(os.path.basename(a.csv))[0])
    fig.tight_layout()
    out = a.out or os.path.splitext(a.csv)[0] + ".png"
    fig.savefig(out, dpi=110)
    print(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
