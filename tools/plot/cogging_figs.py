#!/usr/bin/env python3
"""PNG figure of the anticogging map's effect (issue 35): the peak-to-peak
speed ripple of `mcsim run cogging` without the map (--set anticogging=0)
and with the map the drive calibrates first (--set anticogging=1), per
motor and speed.

    cogging_figs.py LABEL OFF.json ON.json [LABEL OFF.json ON.json ...] PNG

Each JSON is the scenario's summary (speed_ripple_pp_rad_s,
speed_target_rad_s); the numbers the figure shows are in the checked table
`gen:cogging-ripple` (firmware/app/commission/README.md), from the same
runs (tools/docs/gen_docs.py write --figures).
"""
import json
import sys

# pyplot on the Agg backend and the plots' shared PNG writer
from csmc_figs import plt, save


def main(argv):
    if len(argv) < 4 or (len(argv) - 1) % 3:
        print(__doc__, file=sys.stderr)
        return 2
    png = argv[-1]
    groups = []
    for i in range(0, len(argv) - 1, 3):
        lab, off, on = argv[i:i + 3]
        with open(off) as fh:
            s0 = json.load(fh)
        with open(on) as fh:
            s1 = json.load(fh)
        groups.append((lab, s0["speed_ripple_pp_rad_s"], s1["speed_ripple_pp_rad_s"]))
    fig, ax = plt.subplots(figsize=(9, 4.5))
    x = range(len(groups))
    w = 0.38
    b0 = ax.bar([k - w / 2 for k in x], [g[1] for g in groups], w, color="tab:red", label="without map")
    b1 = ax.bar([k + w / 2 for k in x], [g[2] for g in groups], w, color="tab:blue",
                label="with the calibrated map")
    for bars in (b0, b1):
        for r in bars:
            ax.annotate(f"{r.get_height():.3g}", (r.get_x() + r.get_width() / 2, r.get_height()),
                        ha="center", va="bottom", fontsize=8)
    for k, (_lab, off, on) in enumerate(groups):
        ax.annotate(f"without / with: {off / on:.2g}", (k, max(off, on)), xytext=(0, 16),
                    textcoords="offset points", ha="center", fontsize=8, color="k")
    ax.set_xticks(list(x))
    ax.set_xticklabels([g[0] for g in groups], fontsize=8)
    ax.set_yscale("log")
    ax.set_ylim(top=3.0 * max(max(g[1], g[2]) for g in groups))  # room for the labels
    ax.set_ylabel("speed ripple, peak to peak [rad/s]")
    ax.set_title("mcsim run cogging: the rotor's speed ripple without and with the anticogging map\n"
                 "(above each pair the ratio: above 1 the map reduces the ripple)", fontsize=9)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, axis="y")
    save(fig, png)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
