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
    ap.add_argument("--summary", action="store_true", help="print the table by kind (docs/safety.md)")
    ap.add_argument("--full", help="write the table of every run into this Markdown file")
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
    lines = [f"| injection ({a.mode}) | detected after [ms] | fault | zero torque after [ms] | excursion [mm] |"
             " largest torque after detection [N m] |", "|---|---:|---|---:|---:|---:|"]
    for spec, r in results:
        at = r["at_s"]
        lines.append(f"| `{spec}` | {ms(r['detected_s'], at)} | {r['fault'] or '-'} | {ms(r['zero_torque_s'], at)} | "
                     f"{r['excursion_mm']:.2f} | {r['max_torque_after_detection_Nm']:.2f} |")
    if a.full:
        with open(a.full, "w") as f:
            f.write(f"# Fault injection, every run ({a.mode})\n\nWritten by `python3 scripts/injection_table.py "
                    f"--mode {a.mode} --full {a.full}` (or `scripts/docs_tables.py --kind long --only injection`)."
                    "\n\n" + "\n".join(lines) + "\n")
    if not a.summary:
        print("\n".join(lines))
        return
    # By kind: worst detection, how many within 50 ms and 5 mm, the faults raised.
    print("| kind | runs | worst detection [ms] | detected ≤ 50 ms | faults raised | worst excursion [mm] | "
          "excursion ≤ 5 mm | largest torque after detection [N m] |")
    print("|---|---:|---:|---:|---|---:|---:|---:|")
    groups = {}
    for spec, r in results:
        kind = spec.split("@")[0].split(":")[0]
        label = f"`{kind}` at t = 0" if r["at_s"] == 0 else f"`{kind}`"
        groups.setdefault(label, []).append(r)
    for label, rs in groups.items():
        det = [None if r["detected_s"] is None else (r["detected_s"] - r["at_s"]) * 1e3 for r in rs]
        worst = "never" if any(d is None for d in det) else f"{max(det):.0f}"
        fast = sum(1 for d in det if d is not None and d <= 50)
        faults = sorted({f for r in rs for f in r["faults"]})
        exc = [r["excursion_mm"] for r in rs]
        print(f"| {label} | {len(rs)} | {worst} | {fast}/{len(rs)} | {', '.join(faults)} | {max(exc):.2f} | "
              f"{sum(1 for e in exc if e <= 5)}/{len(rs)} | "
              f"{max(r['max_torque_after_detection_Nm'] for r in rs):.2f} |")


if __name__ == "__main__":
    main()
