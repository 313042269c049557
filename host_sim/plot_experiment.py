#!/usr/bin/env python3
"""Turns the experiment's time series (out/timeseries_{adaptive,none}.csv) into PNG figures:
fig1_tracking_errors.png (Fig. 1 of the paper, both modes) and friction_estimates.png; and, from
out/summary.json, window_max_errors.png (the worst error per window over the whole run)."""
import csv
import json
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
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    if not rows:
        raise ValueError(f"{path}: no rows")
    return {k: [float(r[k]) for r in rows] for k in rows[0]}


TABLE1 = [0.38, 0.44, 0.28, 0.06, 0.04, 0.06]


def plot_windows(out):
    """The worst |e| per window of every run in summary.json, with the paper's Table I."""
    p = os.path.join(out, "summary.json")
    if not os.path.exists(p):
        return
    with open(p) as f:
        runs = json.load(f).get("runs", [])
    runs = [r for r in runs if r.get("window_max_error")]
    if not runs:
        return
    fig, axs = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
    for r in runs:
        w = r["window_s"]
        t = [w * (k + 1) for k in range(len(r["window_max_error"]))]
        for i, name in enumerate("xyz"):
            axs[0].semilogy(t, [m[i] for m in r["window_max_error"]], lw=0.9,
                            label=f"{r['mode']} ({r.get('adaptation', '')}) e_{name}")
        for i, name in enumerate("xyz"):
            axs[1].semilogy(t, [m[3 + i] for m in r["window_max_error"]], lw=0.9, label=f"{r['mode']} e_φ{name}")
    for i, ls in zip(range(3), ("-", "--", ":")):
        axs[0].axhline(TABLE1[i], color="k", lw=0.6, ls=ls, label="Table I " + "xyz"[i] if i == 0 else None)
        axs[1].axhline(TABLE1[3 + i], color="k", lw=0.6, ls=ls)
    axs[0].set_ylabel("max |e| per window [mm]")
    axs[1].set_ylabel("max |e| per window [deg]")
    axs[-1].set_xlabel("end of window [s]")
    for a in axs:
        a.grid(True, lw=0.3, which="both")
    axs[0].legend(fontsize=7, ncol=2)
    fig.suptitle(f"Worst tracking error per {runs[0]['window_s']:.0f} s window; black: paper Table I")
    fig.tight_layout()
    p3 = os.path.join(out, "window_max_errors.png")
    fig.savefig(p3, dpi=110)
    print(f"wrote {p3}")


def main(argv):
    if len(argv) != 2:
        print("usage: plot_experiment.py OUT_DIR", file=sys.stderr)
        return 2
    out = argv[1]
    # The runs of this experiment are those of its summary.json: a CSV left in the folder by an
    # earlier run (another mode, another duration) is not plotted beside them.
    summary = {}
    sp = os.path.join(out, "summary.json")
    if os.path.exists(sp):
        with open(sp) as f:
            summary = {r["mode"]: r for r in json.load(f).get("runs", [])}
    runs = {}
    for mode in ("adaptive", "none"):
        p = os.path.join(out, f"timeseries_{mode}.csv")
        if not os.path.exists(p) or (summary and mode not in summary):
            continue
        d = load(p)
        if mode in summary and abs(d["t"][-1] - summary[mode]["duration_s"]) > 1.0:
            print(f"plot_experiment.py: {p} ends at {d['t'][-1]:.1f} s, but the run in summary.json lasted "
                  f"{summary[mode]['duration_s']:.1f} s: a stale file, not plotted", file=sys.stderr)
            continue
        runs[mode] = d
    if not runs:
        print(f"plot_experiment.py: no timeseries_*.csv of this run in {out}", file=sys.stderr)
        return 1
    print(f"plotted runs: {' '.join(runs)}")
    first = summary.get("adaptive") or summary.get("none") or {}
    what = (f"{first.get('duration_s', 0):.0f} s, plant friction '{first.get('friction_preset', '?')}'"
            if first else "")

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
    fig.suptitle(f"Tracking errors on the simulated PUMA 560 (cf. Fig. 1 of the paper){', ' + what if what else ''}")
    fig.tight_layout()
    p1 = os.path.join(out, "fig1_tracking_errors.png")
    fig.savefig(p1, dpi=110)
    print(f"wrote {p1}")

    if "adaptive" in runs:
        d = runs["adaptive"]
        fig, axs = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
        for k in range(3):
            for j in range(6):
                line, = axs[k].plot(d["t"], d[f"theta_{('vis', 'cou', 'sti')[k]}_j{j + 1}"], lw=0.8,
                                    label=f"J{j + 1}")
                if "adaptive" in summary:  # the plant's true value, dashed, same colour
                    axs[k].axhline(summary["adaptive"]["theta_true"][6 * k + j], color=line.get_color(), lw=0.6,
                                   ls="--")
            axs[k].set_ylabel(PARAMS[k] + (" [N m s/rad]" if k == 0 else " [N m]"))
            axs[k].grid(True, lw=0.3)
        axs[0].legend(ncol=6, fontsize=8)
        axs[-1].set_xlabel("t [s]")
        law = summary.get("adaptive", {}).get("adaptation", "")
        fig.suptitle(f"Friction coefficient estimates θ̂ ({law + ' law; ' if law else ''}dashed: the plant's true "
                     f"values){', ' + what if what else ''}")
        fig.tight_layout()
        p2 = os.path.join(out, "friction_estimates.png")
        fig.savefig(p2, dpi=110)
        print(f"wrote {p2}")
    plot_windows(out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
