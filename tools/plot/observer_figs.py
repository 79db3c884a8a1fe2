#!/usr/bin/env python3
"""PNG figures for the paper-002 (sensorless) scenarios of mcsim.

usage: observer_figs.py DIR [DIR ...]

Looks in each DIR for the CSV files the observer scenarios write
(observer-error-phase.csv, observer-table1.csv, observer-test-motor.csv,
ii-observer.csv, observer-lowspeed-sweep.csv) and writes next to each a PNG
laid out like the paper's figures (Figs. 2-3, 5-7, 8-9). The sweep also
gets a Markdown table (observer-lowspeed-sweep.md) for the README.
"""
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

RPM = 60.0 / (2.0 * np.pi)


def load(path):
    return np.genfromtxt(path, delimiter=",", names=True)


def summary(path):
    j = os.path.splitext(path)[0] + ".json"
    if os.path.exists(j):
        with open(j) as f:
            return json.load(f)
    return {}


def fig_phase(path):
    d = load(path)
    omegas = sorted(set(d["omega0_1"]))
    n = len(omegas)
    cols = min(n, 3)
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 4.0 * rows), squeeze=False)
    for ax, w in zip(axes.flat, omegas, strict=False):
        sel = d[d["omega0_1"] == w]
        for tr in sorted(set(sel["traj_1"])):
            s = sel[sel["traj_1"] == tr]
            ax.plot(s["chi1_1"], s["chi2_1"], lw=0.7, color="tab:blue")
            ax.plot(s["chi1_1"][0], s["chi2_1"][0], ".", ms=3, color="tab:gray")
        th = np.linspace(0, 2 * np.pi, 200)
        ax.plot(2 * np.cos(th), 2 * np.sin(th), "k--", lw=0.8, label="|chi| = 2 (Prop. 2)")
        ax.plot(1 + np.cos(th), np.sin(th), "g:", lw=0.8, label="sigma = 0")
        eq = [(0.0, 0.0)]
        if 0 < w <= 0.5:
            dd = 0.5 * np.sqrt(max(0.0, 1 - 4 * w * w))
            eq += [(0.5 + dd, -w), (0.5 - dd, -w)]
        for e in eq:
            ax.plot(*e, "ro", ms=5)
        ax.set_title("Omega0 = %g" % w)
        ax.set_xlim(-1.6, 2.6)
        ax.set_ylim(-2.1, 2.1)
        ax.set_aspect("equal")
        ax.set_xlabel("chi1")
        ax.set_ylabel("chi2")
    axes.flat[0].legend(loc="lower left", fontsize=7)
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    fig.suptitle("Flux observer error system (17): phase portraits (paper 002, Figs. 2-3)")
    fig.tight_layout()
    return fig


def fig_drive(path, title):
    d = load(path)
    t = d["t"]
    fig, ax = plt.subplots(4, 1, figsize=(9, 11), sharex=True)
    ax[0].plot(t, d["omega_ref_rad_s"] * RPM, "k--", lw=1, label="omega* (reference)")
    ax[0].plot(t, d["omega_m_rad_s"] * RPM, lw=1.2, label="omega (true)")
    ax[0].plot(t, d["omega_hat_rad_s"] * RPM, lw=0.8, label="omega_hat (PLL on theta_hat)")
    ax[0].set_ylabel("speed [r/min]")
    ax[0].legend(fontsize=8)
    ax[1].plot(t, d["tau_e_nm"], lw=1, label="tau_e")
    ax[1].plot(t, d["tau_load_nm"], lw=1, label="tau_L")
    ax[1].set_ylabel("torque [N m]")
    ax[1].legend(fontsize=8)
    ax[2].plot(t, d["angle_err_rad"], lw=0.8, color="tab:red")
    ax[2].set_ylabel("theta_hat - theta [rad]")
    ph = d["phase_1"]
    ax2 = ax[2].twinx()
    ax2.plot(t, ph, color="tab:gray", lw=0.8)
    ax2.set_yticks([0, 1, 2])
    ax2.set_yticklabels(["ALIGN", "I-f", "closed"], fontsize=7)
    ax[3].plot(t, d["id_a"], lw=0.8, label="i_d (true frame)")
    ax[3].plot(t, d["iq_a"], lw=0.8, label="i_q (true frame)")
    ax[3].set_ylabel("current [A]")
    ax[3].set_xlabel("t [s]")
    ax[3].legend(fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def fig_drive_zoom(path, title):
    """Figs. 6-7 style: theta and theta_hat on an expanded time scale, the
    estimated sin/cos and the flux estimate planes."""
    d = load(path)
    t = d["t"]
    t0 = t[len(t) // 2]
    sel = (t >= t0) & (t < t0 + 0.05)
    fig, ax = plt.subplots(2, 2, figsize=(10, 8))
    ax[0, 0].plot(t[sel], d["theta_e_rad"][sel], label="theta")
    ax[0, 0].plot(t[sel], d["theta_e_hat_rad"][sel], "--", label="theta_hat")
    ax[0, 0].set_xlabel("t [s]")
    ax[0, 0].set_ylabel("electrical angle [rad]")
    ax[0, 0].legend(fontsize=8)
    ax[0, 1].plot(t[sel], np.sin(d["theta_e_hat_rad"][sel]), label="sin theta_hat (w1)")
    ax[0, 1].plot(t[sel], np.cos(d["theta_e_hat_rad"][sel]), label="cos theta_hat (w2)")
    ax[0, 1].set_xlabel("t [s]")
    ax[0, 1].legend(fontsize=8)
    ax[1, 0].plot(np.cos(d["theta_e_hat_rad"]), np.sin(d["theta_e_hat_rad"]), lw=0.5)
    ax[1, 0].set_xlabel("cos theta_hat")
    ax[1, 0].set_ylabel("sin theta_hat")
    ax[1, 0].set_aspect("equal")
    ax[1, 1].plot(d["x_hat_alpha_wb"], d["x_hat_beta_wb"], lw=0.5)
    ax[1, 1].set_xlabel("x_hat_1 [Wb]")
    ax[1, 1].set_ylabel("x_hat_2 [Wb]")
    ax[1, 1].set_aspect("equal")
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def fig_ii(path):
    d = load(path)
    t = d["t"]
    fig, ax = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
    ax[0].plot(t, d["omega_m_rad_s"], "k", lw=1.2, label="omega (true)")
    ax[0].plot(t, d["omega_ii_rad_s"], lw=0.8, label="I&I (30)")
    ax[0].plot(t, d["omega_pll_rad_s"], lw=0.8, label="PLL")
    ax[0].plot(t, d["omega_dd_rad_s"], lw=0.8, label="dirty derivative")
    ax[0].set_ylabel("speed [rad/s]")
    ax[0].legend(fontsize=8)
    for k, lab in (("omega_ii_rad_s", "I&I"), ("omega_pll_rad_s", "PLL"), ("omega_dd_rad_s", "dirty derivative")):
        ax[1].plot(t, d[k] - d["omega_m_rad_s"], lw=0.7, label=lab)
    ax[1].set_ylabel("speed error [rad/s]")
    ax[1].legend(fontsize=8)
    ax[2].plot(t, d["tau_load_nm"], "k", lw=1.2, label="tau_L (true)")
    ax[2].plot(t, d["tau_load_ii_nm"], lw=0.8, label="tau_L (I&I)")
    ax[2].set_ylabel("load torque [N m]")
    ax[2].set_xlabel("t [s]")
    ax[2].legend(fontsize=8)
    fig.suptitle("I&I speed and load observer on the quantised encoder (paper 002, Sec. IV)")
    fig.tight_layout()
    return fig


def sweep(path):
    d = load(path)
    lines = ["| speed reference [r/min] | works | mean speed [r/min] | speed ripple rms [r/min] "
             "| angle error mean [rad] | angle error max [rad] | drive fault |",
             "|---|---|---|---|---|---|---|"]
    for r in np.atleast_1d(d):
        f = lambda v, fmt: ("-" if np.isnan(v) else fmt % v)  # noqa: E731
        lines.append("| %g | %s | %s | %s | %s | %s | %s |" % (
            r["speed_ref_rpm"], "yes" if r["works_1"] > 0.5 else "no",
            f(r["speed_mean_rpm"], "%.1f"), f(r["speed_ripple_rms_rpm"], "%.2f"),
            f(r["angle_err_mean_rad"], "%.3f"), f(r["angle_err_max_rad"], "%.3f"),
            "none" if r["fault_1"] == 0 else "0x%x" % int(r["fault_1"])))
    with open(os.path.splitext(path)[0] + ".md", "w") as fh:
        fh.write("\n".join(lines) + "\n")
    fig, ax = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    ok = d["works_1"] > 0.5
    ax[0].semilogy(d["speed_ref_rpm"], np.abs(d["angle_err_max_rad"]), "o-")
    ax[0].semilogy(d["speed_ref_rpm"][~ok], np.abs(d["angle_err_max_rad"][~ok]), "rx", ms=10)
    ax[0].axhline(0.35, color="k", ls="--", lw=0.8)
    ax[0].set_ylabel("max |angle error| [rad]")
    ax[1].plot(d["speed_ref_rpm"], d["speed_ripple_rms_rpm"], "o-")
    ax[1].set_ylabel("speed ripple rms [r/min]")
    ax[1].set_xlabel("speed reference [r/min]")
    fig.suptitle("Sensorless loop at low speed (x: does not hold the reference)")
    fig.tight_layout()
    return fig


def main(argv):
    if len(argv) < 2:
        print(__doc__)
        return 2
    made = 0
    for dname in argv[1:]:
        for name, fn in (
            ("observer-error-phase.csv", fig_phase),
            ("observer-table1.csv", lambda p: fig_drive(p, "40 kW machine of Table I (paper 002, Fig. 5)")),
            ("observer-test-motor.csv", lambda p: fig_drive(
                p, "0.3 kW test motor, profile %d (paper 002, Figs. 8-9)" % summary(p).get("profile", -1))),
            ("ii-observer.csv", fig_ii),
            ("observer-lowspeed-sweep.csv", sweep),
        ):
            p = os.path.join(dname, name)
            if not os.path.exists(p):
                continue
            fig = fn(p)
            out = os.path.splitext(p)[0] + ".png"
            fig.savefig(out, dpi=110)
            plt.close(fig)
            print(out)
            made += 1
            if name == "observer-table1.csv":
                fig = fig_drive_zoom(p, "40 kW machine: expanded time scale (paper 002, Figs. 6-7)")
                out = os.path.splitext(p)[0] + "-zoom.png"
                fig.savefig(out, dpi=110)
                plt.close(fig)
                print(out)
    if made == 0:
        print("no observer scenario CSV found", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
