#!/usr/bin/env python3
"""Long-run table of the adaptation law from puma_experiment JSON summaries (docs/adaptation.md).

usage: adaptation_table.py NAME=summary.json ...

Per run: faults, the range of every theta^ over the run against its bounds (params::kThetaMax), the
friction prediction error over the final window, the worst max |e| over the 60 s windows after
120 s, the worst window of the first and of the last 20 minutes after 120 s (growth), and how many
windows exceed the paper's Table I on any axis.
"""
import json
import re
import sys
from pathlib import Path

TABLE1 = [0.38, 0.44, 0.28, 0.06, 0.04, 0.06]
PARAMS = Path(__file__).resolve().parent.parent / "firmware/control/include/osc/control/params.hpp"


def theta_max():
    text = PARAMS.read_text()
    body = re.search(r"kThetaMax\[18\]\s*=\s*\{(.*?)\};", text, re.S).group(1)
    body = re.sub(r"//[^\n]*", "", body)
    return [float(v) for v in body.replace("\n", " ").split(",") if v.strip()]


def worst(windows):
    return [max(w[i] for w in windows) for i in range(6)] if windows else [float("nan")] * 6


def fmt(v, n=3):
    return "/".join(f"{x:.{n}f}" for x in v)


def row(name, run, tmax):
    w = run["window_s"]
    wins = run["window_max_error"]
    after = [m for k, m in enumerate(wins) if k * w >= 120 and (k + 1) * w <= run["duration_s"] + 1e-9]
    per20 = int(round(1200 / w))
    first, last = after[:per20], after[-per20:]
    over = sum(any(m[i] > TABLE1[i] for i in range(6)) for m in after)
    lo, hi = run.get("theta_min_seen"), run.get("theta_max_seen")
    if lo and hi:
        inside = all(lo[i] >= 0 and hi[i] <= tmax[i] for i in range(18))
        at_bound = [i for i in range(18) if hi[i] >= tmax[i]]
        rng = f"{'yes' if inside else 'NO'} [{min(lo):.2f}, max/bound {max(hi[i] / tmax[i] for i in range(18)):.2f}]"
        if at_bound:
            rng += " at bound: " + ", ".join(f"{['vis', 'cou', 'sti'][i // 6]} J{i % 6 + 1}" for i in at_bound)
    else:  # older summaries: only the range of all theta^ per window
        lo_all = min(r[0] for r in run["window_theta_range"])
        hi_all = max(r[1] for r in run["window_theta_range"])
        rng = f"{'yes' if lo_all >= 0 else 'NO'} [{lo_all:.2f}, {hi_all:.2f}] (all coefficients)"
    wa = worst(after)
    faults = ", ".join(run["faults"]) if run.get("faults") else "0"
    return (f"| {name} | {faults} | {rng} | {run['friction_rms_error_Nm']:.3f} "
            f"({run.get('final_window_s', 20):.0f} s) | {fmt(wa[:3])} mm, {fmt(wa[3:], 4)}° | "
            f"{fmt(worst(first)[:3])} → {fmt(worst(last)[:3])} | {over}/{len(after)} |")


def main(argv):
    if len(argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    tmax = theta_max()
    print("| run | faults | θ̂ in bounds [min, max/bound] | friction rms error N·m (final window) | worst 60 s "
          "window after 120 s | first 20 min → last 20 min, x/y/z mm | windows over Table I |")
    print("|---|---|---|---|---|---|---|")
    for arg in argv[1:]:
        name, path = arg.split("=", 1)
        with open(path) as f:
            data = json.load(f)
        for run in data["runs"]:
            print(row(name if len(data["runs"]) == 1 else f"{name} ({run['mode']})", run, tmax))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
