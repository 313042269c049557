#!/usr/bin/env python3
"""Fault-injection table for docs/safety.md: every kind of puma_experiment --inject, on every joint
where it applies, at several times along the task; prints a Markdown table (and writes the raw JSON
of each run into --out).

  python3 scripts/injection_table.py [--exe build/host/host_sim/puma_experiment] [--mode adaptive]
"""
import argparse
import concurrent.futures
import json
import os
import subprocess
import sys

KINDS = [("encoder-stuck", True), ("encoder-jump", True), ("encoder-garbage", True), ("encoder-noise", True),
         ("dac-stuck", True), ("overrun", False), ("estop", False)]
# Along one period of the trajectory (5 s) once its envelope has settled (20 s), and at the start.
TIMES = [20.0, 21.25, 22.5, 23.75]


def run(exe, mode, kind, joint, at, out):
    spec = f"{kind}{'' if joint is None else ':' + str(joint)}@{at:g}"
    path = os.path.join(out, spec.replace(":", "_").replace("@", "_at_") + f"_{mode}.json")
    cmd = [exe, "--duration", f"{at + 1.0:g}", "--mode", mode, "--inject", spec, "--no-csv", "--no-progress",
           "--json", path]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed ({p.returncode}):\n{p.stdout}{p.stderr}")
    with open(path) as f:
        r = json.load(f)["runs"][0]["injection"]
    return spec, r


def ms(a, b):
    return "never" if a is None else f"{(a - b) * 1e3:.0f}"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--exe", default="build/host/host_sim/puma_experiment")
    ap.add_argument("--mode", default="adaptive", choices=["adaptive", "none"])
    ap.add_argument("--out", default="out/injection")
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    jobs = []
    for kind, per_joint in KINDS:
        times = ([0.0] if kind == "encoder-garbage" else []) + TIMES
        for at in times:
            for joint in (range(1, 7) if per_joint else [None]):
                jobs.append((kind, joint, at))
    with concurrent.futures.ThreadPoolExecutor(a.jobs) as ex:
        results = list(ex.map(lambda j: run(a.exe, a.mode, *j, a.out), jobs))
    print(f"| injection ({a.mode}) | detected after [ms] | fault | zero torque after [ms] | excursion [mm] |"
          " largest torque after detection [N m] |")
    print("|---|---:|---|---:|---:|---:|")
    for spec, r in results:
        at = r["at_s"]
        print(f"| `{spec}` | {ms(r['detected_s'], at)} | {r['fault'] or '-'} | {ms(r['zero_torque_s'], at)} | "
              f"{r['excursion_mm']:.2f} | {r['max_torque_after_detection_Nm']:.2f} |")


if __name__ == "__main__":
    main()
