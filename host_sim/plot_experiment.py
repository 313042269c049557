#!/usr/bin/env python3
"""Turns the experiment's time series (out/timeseries_{adaptive,none}.csv) into PNG figures:
fig1_tracking_errors.png (Fig. 1 of the paper, both modes) and friction_estimates.png."""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

AXES = ["e_x_mm", "e_y_mm", "e_z_mm", "e_phx_deg", "e_phy_deg", "e_phz_deg"]
LABELS = ["e_x [mm]", "e_y [mm]", "e_z [mm]", "e_φx [deg]", "e_φy [deg]", "e_φz [deg]"]
PARAMS = ["τ_vis", "τ_cou", "τ_sti"]


def load(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise ValueError(f"{path}: no rows")
    return {k: [float(r[k]) for r in rows] for k in rows[0]}


def main(argv):
    if len(argv) != 2:
        print("usage: plot_experiment.py OUT_DIR", file=sys.stderr)
        return 2
    out = argv[1]
    runs = {}
    for mode in ("adaptive", "none"):
        p = os.path.join(out, f"timeseries_{mode}.csv")
        if os.path.exists(p):
            runs[mode] = load(p)
    if not runs:
        print(f"plot_experiment.py: no timeseries_*.csv in {out}", file=sys.stderr)
        return 1

    fig, axs = plt.subplots(6, 1, figsize=(9, 11), sharex=True)
    for mode, d in runs.items():
        label = "with adaptive friction compensation" if mode == "adaptive" else "without friction compensation"
        for i, key in enumerate(AXES):
            axs[i].plot(d["t"], d[key], lw=0.6, label=label, alpha=0.8 if mode == "adaptive" else 0.6)
    for i, lab in enumerate(LABELS):
        axs[i].set_ylabel(lab)
        axs[i].grid(True, lw=0.3)
    axs[0].legend(loc="upper right", fontsize=8)
    axs[-1].set_xlabel("t [s]")
    fig.suptitle("Tracking errors on the simulated PUMA 560 (cf. Fig. 1 of the paper)")
    fig.tight_layout()
    p1 = os.path.join(out, "fig1_tracking_errors.png")
    fig.savefig(p1, dpi=110)
    print(f"wrote {p1}")

    if "adaptive" in runs:
        d = runs["adaptive"]
        fig, axs = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
        for k in range(3):
            for j in range(6):
                axs[k].plot(d["t"], d[f"theta_hat_{6 * k + j}"], lw=0.8, label=f"J{j + 1}")
            axs[k].set_ylabel(PARAMS[k] + (" [N m s/rad]" if k == 0 else " [N m]"))
            axs[k].grid(True, lw=0.3)
        axs[0].legend(ncol=6, fontsize=8)
        axs[-1].set_xlabel("t [s]")
        fig.suptitle("Friction coefficient estimates θ̂ (adaptation law (67))")
        fig.tight_layout()
        p2 = os.path.join(out, "friction_estimates.png")
        fig.savefig(p2, dpi=110)
        print(f"wrote {p2}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
