#!/usr/bin/env python3
"""PNG figures of the CSMC stepper scenarios (paper 001, Seshagiri and Khalil).

    csmc_figs.py OUT_DIR [PNG_DIR]

Reads every csmc-*.csv that `mcsim run csmc-...` wrote into OUT_DIR and
writes one PNG per scenario (default: next to the CSVs):
    csmc-state-feedback.png       Fig. 2: e2 (and e1) under state feedback
    csmc-output-feedback.png      Fig. 3(a): e2 output vs partial state feedback
    csmc-output-feedback-eps.png  Fig. 3(b): e2 for several eps
    csmc-sampled.png              Fig. 4: CSMC vs ideal SMC, e2 and v_q, T = 0.1 ms
    csmc-sinusoid.png             Fig. 5: e2 with and without servocompensator
    csmc-drive.png                the same loop through the drive + plug-in
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def read(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    head, data = rows[0], rows[1:]
    return {h: [float(r[i]) for r in data] for i, h in enumerate(head)}


def save(fig, png):
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)
    print(png)


def state_feedback(c, png):
    fig, ax = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    ax[0].plot(c["t"], c["x4_rad"], label="phi")
    ax[0].plot(c["t"], c["phi_d_rad"], "--", label="phi_d")
    ax[0].set_ylabel("rad")
    ax[0].legend()
    ax[1].plot(c["t"], c["e2_rad"])
    ax[1].set_ylabel("e2 [rad]")
    ax[2].plot(c["t"], c["e1_a"])
    ax[2].set_ylabel("e1 [A]")
    ax[2].set_xlabel("t [s]")
    ax[0].set_title("Fig. 2: state-feedback CSMC with conditional integrators")
    save(fig, png)


def output_feedback(c, png):
    fig, ax = plt.subplots(2, 1, figsize=(8, 6.5), sharex=True)
    ax[0].plot(c["t"], c["e2_rad"], label="output feedback (HGO)")
    ax[0].plot(c["t"], c["sf_e2_rad"], "--", label="partial state feedback")
    ax[0].set_ylabel("e2 [rad]")
    ax[0].legend()
    ax[1].plot(c["t"], c["u2_v"], label="v_q output fb")
    ax[1].plot(c["t"], c["sf_u2_v"], "--", label="v_q state fb")
    ax[1].set_ylabel("V")
    ax[1].set_xlabel("t [s]")
    ax[1].legend()
    ax[0].set_title("Fig. 3(a): output feedback, eps = 1e-4")
    save(fig, png)


def eps_sweep(c, png):
    fig, ax = plt.subplots(figsize=(8, 4.5))
    ax.plot(c["t"], c["sf_e2_rad"], "k--", label="state feedback")
    for k in c:
        if k.startswith("e2_eps_"):
            ax.plot(c["t"], c[k], label="eps = " + k[len("e2_eps_"):-len("_rad")])
    ax.set_xlim(0, min(0.1, c["t"][-1]))
    ax.set_ylabel("e2 [rad]")
    ax.set_xlabel("t [s]")
    ax.legend()
    ax.set_title("Fig. 3(b): output feedback approaches state feedback as eps -> 0")
    save(fig, png)


def sampled(c, png):
    fig, ax = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    ax[0].plot(c["t"], c["e2_rad"], label="CSMC + conditional integrators")
    ax[0].plot(c["t"], c["smc_e2_rad"], label="ideal SMC")
    ax[0].set_ylabel("e2 [rad]")
    ax[0].legend()
    t_end = c["t"][-1]
    ax[1].plot(c["t"], c["e2_rad"])
    ax[1].plot(c["t"], c["smc_e2_rad"])
    ax[1].set_ylim(-1e-3, 1e-3)
    ax[1].set_ylabel("e2, zoom [rad]")
    ax[2].plot(c["t"], c["smc_u2_v"], "C1", lw=0.5, label="v_q ideal SMC")
    ax[2].plot(c["t"], c["u2_v"], "C0", label="v_q CSMC")
    ax[2].set_ylabel("V")
    ax[2].set_xlabel("t [s]")
    ax[2].set_xlim(0, t_end)
    ax[2].legend()
    ax[0].set_title("Fig. 4: sampled data, T = 0.1 ms")
    save(fig, png)


def sinusoid(c, png):
    fig, ax = plt.subplots(2, 1, figsize=(8, 6.5), sharex=True)
    ax[0].plot(c["t"], c["x4_rad"], label="phi")
    ax[0].plot(c["t"], c["phi_d_rad"], "--", label="phi_d")
    ax[0].set_ylabel("rad")
    ax[0].legend()
    ax[1].semilogy(c["t"], [abs(v) + 1e-12 for v in c["e2_rad"]], label="with servocompensator")
    ax[1].semilogy(c["t"], [abs(v) + 1e-12 for v in c["nosvc_e2_rad"]], label="without")
    ax[1].set_ylabel("|e2| [rad]")
    ax[1].set_xlabel("t [s]")
    ax[1].legend()
    ax[0].set_title("Fig. 5: sinusoidal reference, output feedback")
    save(fig, png)


def drive(c, png):
    fig, ax = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    ax[0].plot(c["t"], c["x4_rad"], label="phi")
    ax[0].plot(c["t"], c["phi_d_rad"], "--", label="phi_d")
    ax[0].set_ylabel("rad")
    ax[0].legend()
    ax[1].plot(c["t"], c["e2_rad"], label="e2 (true)")
    ax[1].plot(c["t"], c["e2_meas_rad"], lw=0.6, label="e2 (encoder)")
    ax[1].set_ylabel("rad")
    ax[1].legend()
    ax[2].plot(c["t"], c["duty2_a_1"], label="duty a")
    ax[2].plot(c["t"], c["duty2_b_1"], label="duty b")
    ax[2].set_ylabel("1")
    ax[2].set_xlabel("t [s]")
    ax[2].legend()
    ax[0].set_title("CSMC through the drive (CTRL mode, dual H-bridge, 10 kHz)")
    save(fig, png)


FIGS = {
    "csmc-state-feedback": state_feedback,
    "csmc-output-feedback": output_feedback,
    "csmc-output-feedback-eps": eps_sweep,
    "csmc-sampled": sampled,
    "csmc-sinusoid": sinusoid,
    "csmc-drive": drive,
}


def main(argv):
    if len(argv) < 2 or argv[1] in ("-h", "--help"):
        print(__doc__)
        return 2
    src = argv[1]
    dst = argv[2] if len(argv) > 2 else src
    os.makedirs(dst, exist_ok=True)
    done = 0
    for name, fn in FIGS.items():
        path = os.path.join(src, name + ".csv")
        if os.path.exists(path):
            fn(read(path), os.path.join(dst, name + ".png"))
            done += 1
    if done == 0:
        print(f"csmc_figs: no csmc-*.csv in {src}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
