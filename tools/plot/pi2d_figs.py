#!/usr/bin/env python3
"""PNG figures of the PI^2D scenarios (paper 000).

    pi2d_figs.py paper OUT_DIR/pi2d-paper.csv [PNG]   Figs. 1-8 of Section V
    pi2d_figs.py motor OUT_DIR/pi2d-motor.csv [PNG]   PI^2D vs PI cascade

Reads the CSV written by `mcsim run pi2d-paper` / `mcsim run pi2d-motor`
(header row, seconds in `t`) and writes one PNG (default: next to the CSV).
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def read(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    head, data = rows[0], rows[1:]
    cols = {h: [float(r[i]) for r in data] for i, h in enumerate(head)}
    return cols


def paper(c, png):
    t = c["t"]
    fig, ax = plt.subplots(4, 2, figsize=(11, 12), sharex=True)
    panels = [
        ("Fig. 1  speed x3 (solid), x3* (dashed)", [("x3", "-"), ("x3_ref", "--")]),
        ("Fig. 2  speed error e3", [("e3", "-")]),
        ("Fig. 3  i_d = x1 (desired 0)", [("x1", "-")]),
        ("Fig. 4  i_q = x2 (solid), x2* (dashed)", [("x2", "-"), ("x2_ref", "--")]),
        ("Fig. 5  position x4 (solid), x4* (dashed)", [("x4", "-"), ("x4_ref", "--")]),
        ("Fig. 6  load estimate nu (tau_L = 1)", [("nu", "-")]),
        ("Fig. 7  dirty-derivative state theta_f", [("theta_f", "-")]),
        ("Fig. 8  voltages u1, u2", [("u1", "-"), ("u2", "-")]),
    ]
    for a, (title, series) in zip(ax.flat, panels, strict=True):
        for name, style in series:
            a.plot(t, c[name], style, label=name, linewidth=1.0)
        a.set_title(title, fontsize=10)
        a.grid(True, alpha=0.3)
        if len(series) > 1:
            a.legend(fontsize=8)
    for a in ax[-1]:
        a.set_xlabel("t (normalised)")
    fig.suptitle("PI$^2$D, paper 000 Section V: firmware kernel at 10 kHz on the normalised PMSM")
    fig.tight_layout()
    fig.savefig(png, dpi=110)


def motor(c, png):
    t = c["t"]
    fig, ax = plt.subplots(3, 1, figsize=(10, 10), sharex=True)
    ax[0].plot(t, c["omega_ref_rad_s"], "k--", label="reference", linewidth=1.0)
    ax[0].plot(t, c["pi2d_omega_m_rad_s"], label="PI$^2$D", linewidth=1.0)
    ax[0].plot(t, c["pi_omega_m_rad_s"], label="PI cascade", linewidth=1.0)
    ax[0].set_ylabel("speed [rad/s]")
    ax[1].plot(t, [a - b for a, b in zip(c["pi2d_omega_m_rad_s"], c["omega_ref_rad_s"], strict=True)],
               label="PI$^2$D", linewidth=1.0)
    ax[1].plot(t, [a - b for a, b in zip(c["pi_omega_m_rad_s"], c["omega_ref_rad_s"], strict=True)],
               label="PI cascade", linewidth=1.0)
    ax[1].set_ylabel("speed error [rad/s]")
    ax[2].plot(t, c["pi2d_i_q_a"], label="i_q PI$^2$D", linewidth=1.0)
    ax[2].plot(t, c["pi_i_q_a"], label="i_q PI cascade", linewidth=1.0)
    ax[2].plot(t, c["load_nm"], "k:", label="load [N m]")
    ax[2].plot(t, c["pi2d_nu_nm"], label="nu (PI$^2$D load estimate) [N m]", linewidth=1.0)
    ax[2].set_ylabel("[A] / [N m]")
    ax[2].set_xlabel("t [s]")
    for a in ax:
        a.grid(True, alpha=0.3)
        a.legend(fontsize=8)
    fig.suptitle("0.3 kW test motor (paper 002), 200 V, 20 kHz, encoder only: "
                 "0 -> 1000 r/min -> 0, 3 N m step at 1 s")
    fig.tight_layout()
    fig.savefig(png, dpi=110)


def main(argv):
    if len(argv) < 3 or argv[1] not in ("paper", "motor"):
        sys.stderr.write(__doc__)
        return 2
    png = argv[3] if len(argv) > 3 else argv[2].rsplit(".", 1)[0] + ".png"
    (paper if argv[1] == "paper" else motor)(read(argv[2]), png)
    print(png)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
