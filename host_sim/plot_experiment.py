#!/usr/bin/env python3
"""Figures of one puma_experiment run, from its summary.json and the time series it names.

usage: plot_experiment.py OUT_DIR      (OUT_DIR holds summary.json, as scripts/run.sh writes it)

Only the runs listed in summary.json are drawn, from the CSV files it names, and a CSV whose
provenance line carries another configuration hash (a file left by an earlier run) is refused.
Every title carries the duration, the friction preset, the adaptation law, the configuration hash,
the git revision and the set-up (the paper's, or the keys that differ with their values); the
paper's Table I and III bounds are drawn only when the set-up is the paper's. A faulted run is drawn
too, with the fault marked.

Writes:
  fig1_tracking_errors.png   e per axis: whole run, |e| on a log scale, and the last window with
                             the paper's Table I (with compensation) and III (without) bounds
  friction_estimates.png     theta^ per joint and coefficient against the plant's true values
  observer_errors.png        the observer's position error x~ and velocity error
  window_max_errors.png      the worst |e| per window over the run, and the range of theta^ per window
"""
import csv
import json
import math
import os
import stat
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

AXES = ["x_mm", "y_mm", "z_mm", "phx_deg", "phy_deg", "phz_deg"]
LABELS = ["e_x [mm]", "e_y [mm]", "e_z [mm]", "e_φx [deg]", "e_φy [deg]", "e_φz [deg]"]
VEL = ["x_mm_s", "y_mm_s", "z_mm_s", "phx_deg_s", "phy_deg_s", "phz_deg_s"]
COEF = [("vis", "τ_vis [N m s/rad]"), ("cou", "τ_cou [N m]"), ("sti", "τ_sti [N m]")]
MODE_LABEL = {"adaptive": "with adaptive friction compensation", "none": "without friction compensation"}
MODE_COLOR = {"adaptive": "tab:blue", "none": "tab:orange"}


def fail(msg):
    print(f"plot_experiment.py: {msg}", file=sys.stderr)
    return 1


def load_csv(path):
    """The provenance line (without '# ') and the columns of a time series."""
    with open(path, newline="") as f:
        first = f.readline()
        if not first.startswith("#"):
            raise ValueError(f"{path}: no provenance line (written by an older puma_experiment?)")
        rows = list(csv.DictReader(f))
    if not rows:
        raise ValueError(f"{path}: no rows")
    return first[1:].strip(), {k: [float(r[k]) for r in rows] for k in rows[0]}


def lookup(config, key):
    node = config
    for part in key.split("."):
        node = node.get(part, {}) if isinstance(node, dict) else {}
    return node


def setup_text(summary):
    if summary.get("paper_setup"):
        return "the paper's set-up"
    parts = []
    for key in summary.get("differs_from_paper", []):
        v = lookup(summary.get("config", {}), key)
        if isinstance(v, list):
            v = "[" + ", ".join(f"{x:g}" for x in v) + "]"
        elif isinstance(v, float):
            v = f"{v:g}"
        parts.append(f"{key}={v}")
    return "differs from the paper: " + ", ".join(parts)


def title(summary, runs, what):
    r0 = runs[0][0]
    law = r0.get("adaptation", "")
    head = (f"{what} — {r0['duration_s']:g} s, plant friction '{r0['friction_preset']}', {law} law")
    prov = f"config {summary.get('config_hash', '?')}, rev {summary.get('git_revision', '?')}; {setup_text(summary)}"
    return head + "\n" + prov


def series(ax, r, t, y, log=False, **kw):
    """Plots y(t). After a fault the amplifiers are off and the robot falls: that part is drawn in
    grey and left out of the axis limits (fit_limits), so the run before the fault stays readable."""
    plot = ax.semilogy if log else ax.plot
    if log:
        y = [max(abs(v), 1e-6) for v in y]
    f = r.get("fault")
    k = next((i for i, x in enumerate(t) if x > f["time_s"]), len(t)) if f else len(t)
    plot(t[:k], y[:k], **kw)
    if k < len(t):
        plot(t[k - 1:], y[k - 1:], **dict(kw, color="0.7", label=None))
        ax.osc_fault = True
    kept = [v for v in y[:k] if math.isfinite(v)]
    if kept:
        lo, hi = getattr(ax, "osc_lims", (math.inf, -math.inf))
        ax.osc_lims = (min(lo, min(kept)), max(hi, max(kept)))


def fit_limits(axes):
    """Limits from the data before any fault, on the axes that show a faulted run."""
    for ax in axes:
        if getattr(ax, "osc_fault", False) and hasattr(ax, "osc_lims"):
            lo, hi = ax.osc_lims
            if ax.get_yscale() == "log":
                ax.set_ylim(lo / 2, hi * 2)
            else:
                pad = 0.1 * ((hi - lo) or 1.0)
                ax.set_ylim(lo - pad, hi + pad)


def mark_faults(ax, runs, label=False):
    for r, _ in runs:
        if r.get("fault"):
            f = r["fault"]
            ax.axvline(f["time_s"], color="red", lw=0.9, ls="-.",
                       label=(f"{r['mode']}: fault {'+'.join(f['names'])} at {f['time_s']:.3f} s" if label else None))


def plot_tracking(out, summary, runs):
    paper = summary.get("paper_setup", False)
    t1 = summary["paper"]["table1_max_error_mm_deg"]
    t3 = summary["paper"]["table3_max_error_mm_deg"]
    fig, axs = plt.subplots(6, 3, figsize=(15, 12), sharex="col")
    for r, d in runs:
        c = MODE_COLOR[r["mode"]]
        t = d["t"]
        end = r["stats_until_s"] if r.get("fault") else r["duration_s"]
        w0 = max(0.0, end - r["final_window_s"])
        last = [k for k, x in enumerate(t) if w0 <= x <= end]
        for i, ax_name in enumerate(AXES):
            e = d["e_" + ax_name]
            series(axs[i][0], r, t, e, lw=0.6, color=c, label=MODE_LABEL[r["mode"]])
            series(axs[i][1], r, t, e, log=True, lw=0.5, color=c)
            axs[i][2].plot([t[k] for k in last], [e[k] for k in last], lw=0.7, color=c)
    for i, lab in enumerate(LABELS):
        axs[i][0].set_ylabel(lab)
        for j in range(3):
            axs[i][j].grid(True, lw=0.3, which="both")
        # The paper's bounds: max |e| with (Table I) and without (Table III) compensation.
        style = dict(lw=0.8, color="k")
        for sign in (1, -1):
            axs[i][2].axhline(sign * t1[i], ls="--", **style, label=("Table I (with)" if sign > 0 and i == 0 else None))
            axs[i][2].axhline(sign * t3[i], ls=":", **style,
                              label=("Table III (without)" if sign > 0 and i == 0 else None))
        axs[i][1].axhline(t1[i], ls="--", **style)
        axs[i][1].axhline(t3[i], ls=":", **style)
        for j in range(2):
            mark_faults(axs[i][j], runs, label=(i == 0 and j == 0))
    fw = runs[0][0]["final_window_s"]
    axs[0][2].legend(loc="upper right", fontsize=7)
    return finish_grid(fig, axs, ["whole run", "|e|, log scale (black: paper Table I --, III ··)",
                                  f"last {fw:g} s" + ("" if paper else " (paper bounds: its set-up, not this one)")],
                       title(summary, runs, "Tracking errors of the simulated PUMA 560 (cf. the paper's Fig. 1)"),
                       out, "fig1_tracking_errors.png")


def finish_grid(fig, axs, column_titles, suptitle, out, name):
    """Common end of the per-axis grids: limits, column titles, legend, labels, title, file."""
    fit_limits(axs.flat)
    for j, t in enumerate(column_titles):
        axs[0][j].set_title(t)
        axs[-1][j].set_xlabel("t [s]")
    axs[0][0].legend(loc="upper right", fontsize=7)
    fig.suptitle(suptitle, fontsize=10)
    fig.tight_layout()
    return save(fig, out, name)


def plot_theta(out, summary, runs):
    ad = [(r, d) for r, d in runs if r["mode"] == "adaptive"]
    if not ad:
        return None
    r, d = ad[0]
    fig, axs = plt.subplots(3, 1, figsize=(10, 9), sharex=True)
    for k, (coef, lab) in enumerate(COEF):
        for j in range(6):
            line, = axs[k].plot(d["t"], d[f"theta_{coef}_j{j + 1}"], lw=0.8, label=f"J{j + 1}")  # frozen after a fault
            axs[k].axhline(r["theta_true"][6 * k + j], color=line.get_color(), lw=0.7, ls="--")
        axs[k].set_ylabel(lab)
        axs[k].grid(True, lw=0.3)
        mark_faults(axs[k], ad, label=(k == 0))
    axs[0].legend(ncol=7, fontsize=8)
    axs[-1].set_xlabel("t [s]")
    fig.suptitle(title(summary, ad, "Friction estimates θ̂ (solid) and the plant's true coefficients (dashed)"),
                 fontsize=10)
    fig.tight_layout()
    return save(fig, out, "friction_estimates.png")


def plot_observer(out, summary, runs):
    obs = [(r, d) for r, d in runs if "xt_x_mm" in d]
    if not obs:
        print("plot_experiment.py: no observer errors in these runs (the controller ran over the link)")
        return None
    fig, axs = plt.subplots(6, 2, figsize=(13, 11), sharex=True)
    for r, d in obs:
        c = MODE_COLOR[r["mode"]]
        for i in range(6):
            series(axs[i][0], r, d["t"], d["xt_" + AXES[i]], lw=0.5, color=c, label=MODE_LABEL[r["mode"]])
            series(axs[i][1], r, d["t"], d["xdt_" + VEL[i]], lw=0.5, color=c)
    units = ["mm", "mm", "mm", "deg", "deg", "deg"]
    for i in range(6):
        axs[i][0].set_ylabel(f"x̃_{AXES[i].split('_')[0]} [{units[i]}]")
        axs[i][1].set_ylabel(f"velocity error [{units[i]}/s]")
        for j in range(2):
            axs[i][j].grid(True, lw=0.3)
            mark_faults(axs[i][j], obs)
    return finish_grid(fig, axs, ["position error x̂ − x (x from the encoders)",
                                  "velocity error x̂̇ − ẋ (ẋ: the plant's true velocity)"],
                       title(summary, obs, "The velocity observer's errors"), out, "observer_errors.png")


def plot_windows(out, summary, runs):
    rs = [(r, d) for r, d in runs if r.get("window_max_error")]
    if not rs:
        return None
    t1 = summary["paper"]["table1_max_error_mm_deg"]
    fig, axs = plt.subplots(3, 1, figsize=(10, 9), sharex=True)
    for r, _ in rs:
        w = r["window_s"]
        t = [w * (k + 1) for k in range(len(r["window_max_error"]))]
        c = MODE_COLOR[r["mode"]]
        mk = "o" if len(t) < 30 else None  # a few windows: points, not a trend
        for i, ls in zip(range(3), ("-", "--", ":")):
            axs[0].semilogy(t, [m[i] for m in r["window_max_error"]], lw=0.9, ls=ls, color=c, marker=mk, ms=3,
                            label=f"{r['mode']} e_{'xyz'[i]}")
            axs[1].semilogy(t, [m[3 + i] for m in r["window_max_error"]], lw=0.9, ls=ls, color=c, marker=mk,
                            ms=3, label=f"{r['mode']} e_φ{'xyz'[i]}")
        if r["mode"] == "adaptive":
            axs[2].plot(t, [m[0] for m in r["window_theta_range"]], color=c, lw=0.9, label="smallest θ̂")
            axs[2].plot(t, [m[1] for m in r["window_theta_range"]], color=c, lw=0.9, ls="--", label="largest θ̂")
    if summary.get("paper_setup"):
        for i, ls in zip(range(3), ("-", "--", ":")):
            axs[0].axhline(t1[i], color="k", lw=0.6, ls=ls, label="Table I" if i == 0 else None)
            axs[1].axhline(t1[3 + i], color="k", lw=0.6, ls=ls)
    axs[0].set_ylabel("max |e| per window [mm]")
    axs[1].set_ylabel("max |e| per window [deg]")
    axs[2].set_ylabel("θ̂ range per window")
    axs[-1].set_xlabel("end of window [s]")
    for a in axs:
        a.grid(True, lw=0.3, which="both")
        mark_faults(a, rs)
    axs[0].legend(fontsize=7, ncol=2)
    axs[2].legend(fontsize=7)
    fig.suptitle(title(summary, rs, f"Worst tracking error per {rs[0][0]['window_s']:g} s window"), fontsize=10)
    fig.tight_layout()
    return save(fig, out, "window_max_errors.png")


class OutputError(Exception):
    pass


def write_output(path, write):
    """Writes a file as puma_experiment does (host_sim/output_file.hpp): a regular file or a new path
    through a temporary file beside it, renamed over it when complete (a failed write leaves the old
    one as it was; a replaced file keeps its mode); a symbolic link written through to its target; a
    device or a FIFO written in place; a directory refused. write(f) writes to a binary file."""
    if os.path.isdir(path):
        raise OutputError(f"cannot write {path}: it is a directory")
    if os.path.exists(path) and not stat.S_ISREG(os.stat(path).st_mode):
        try:
            with open(path, "wb") as f:
                write(f)
        except OSError as e:
            raise OutputError(f"cannot write {path}: {e.strerror}") from e
        return
    target = os.path.realpath(path)  # through links, also to a file that does not exist yet
    if os.path.exists(target):
        mode = stat.S_IMODE(os.stat(target).st_mode)
    else:
        mask = os.umask(0)
        os.umask(mask)
        mode = 0o666 & ~mask
    tmp = None
    try:
        fd, tmp = tempfile.mkstemp(prefix="." + os.path.basename(target) + ".", dir=os.path.dirname(target))
        with os.fdopen(fd, "wb") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
            os.fchmod(f.fileno(), mode)
        os.replace(tmp, target)
    except OSError as e:
        if tmp and os.path.exists(tmp):
            os.unlink(tmp)
        raise OutputError(f"cannot write {path}: {e.strerror}") from e


def save(fig, out, name):
    p = os.path.join(out, name)
    try:
        write_output(p, lambda f: fig.savefig(f, dpi=110, format="png"))
    finally:
        plt.close(fig)
    print(f"wrote {p}")
    return p


def main(argv):
    if len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    out = argv[1]
    sp = os.path.join(out, "summary.json")
    if not os.path.exists(sp):
        return fail(f"no summary.json in {out}: the figures are drawn from one run's summary")
    with open(sp) as f:
        summary = json.load(f)
    runs = []
    for r in summary.get("runs", []):
        name = r.get("timeseries")
        if not name:
            continue
        p = os.path.join(out, name)
        if not os.path.exists(p):
            print(f"plot_experiment.py: {p} is missing: run '{r['mode']}' not plotted", file=sys.stderr)
            continue
        try:
            prov, d = load_csv(p)
        except ValueError as e:
            print(f"plot_experiment.py: {e}: not plotted", file=sys.stderr)
            continue
        if summary.get("config_hash", "") not in prov or f"mode {r['mode']}" not in prov:
            print(f"plot_experiment.py: {p} is from another run ({prov}): a stale file, not plotted", file=sys.stderr)
            continue
        if abs(d["t"][-1] - r["duration_s"]) > 1.0:
            print(f"plot_experiment.py: {p} ends at {d['t'][-1]:.1f} s, but the run lasted {r['duration_s']:.1f} s: "
                  "a stale file, not plotted", file=sys.stderr)
            continue
        runs.append((r, d))
    if not runs:
        return fail(f"no time series of this run in {out}")
    print(f"plotted runs: {' '.join(r['mode'] for r, _ in runs)}")
    print(f"titles: config {summary.get('config_hash', '?')}, rev {summary.get('git_revision', '?')}; "
          f"{setup_text(summary)}")
    for r, _ in runs:
        if r.get("fault"):
            f = r["fault"]
            print(f"[{r['mode']}] fault {'+'.join(f['names'])} at t = {f['time_s']:.3f} s (tick {f['tick']}): marked")
    try:
        plot_tracking(out, summary, runs)
        plot_theta(out, summary, runs)
        plot_observer(out, summary, runs)
        plot_windows(out, summary, runs)
    except OutputError as e:
        return fail(str(e))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
