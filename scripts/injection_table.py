#!/usr/bin/env python3
"""Fault-injection table for docs/safety.md: every kind of puma_experiment --inject (read from
SIM_INJECTION_LIST in host_sim/injection.hpp), on every joint where it applies, in every direction
for a contact, at several times along the task; prints a Markdown table (and writes the raw JSON of
each run into --out).

  python3 scripts/injection_table.py [--exe build/host/host_sim/puma_experiment] [--mode adaptive]
"""
import argparse
import concurrent.futures
import json
import os
import re
import subprocess
import sys

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
# Along one period of the trajectory (5 s) once its envelope has settled (20 s), and at the start.
TIMES = [20.0, 21.25, 22.5, 23.75]
DIRECTIONS = ["+x", "-x", "+y", "-y", "+z", "-z"]
# What each form of SIM_INJECTION_LIST runs with: every joint; nothing; a 50 N step, or a wall 5 mm
# away (the reference moves 50 mm about the start in x, y and z: it meets it), in every direction.
ARGS = {"Joint": [f":{j}" for j in range(1, 7)], "None": [""], "Force": [f":{d}:50" for d in DIRECTIONS],
        "Wall": [f":{d}:5" for d in DIRECTIONS]}
# How long a run goes on after the injection [s]: a contact for a whole period of the trajectory.
AFTER = {"Force": 5.0, "Wall": 5.0}


def kinds():
    """(name, form) of every injection kind, in SIM_INJECTION_LIST's order (the one source)."""
    with open(os.path.join(ROOT, "host_sim", "injection.hpp")) as f:
        return re.findall(r'X\(\w+, "([\w-]+)", k(\w+),', f.read())


def run(exe, mode, kind, form, arg, at, out):
    spec = f"{kind}{arg}@{at:g}"
    path = os.path.join(out, spec.replace(":", "_").replace("@", "_at_") + f"_{mode}.json")
    cmd = [exe, "--duration", f"{at + AFTER.get(form, 1.0):g}", "--mode", mode, "--inject", spec, "--no-csv",
           "--no-progress", "--json", path]
    if kind.startswith("current-"):  # a current monitor's own fault: the monitors on (the ideal plant has none)
        cmd += ["--set", "plant.current_monitor=on"]
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
    for kind, form in kinds():
        times = ([0.0] if kind == "encoder-garbage" else []) + TIMES
        for at in times:
            for arg in ARGS[form]:
                jobs.append((kind, form, arg, at))
    with concurrent.futures.ThreadPoolExecutor(a.jobs) as ex:
        results = list(ex.map(lambda j: run(a.exe, a.mode, *j, a.out), jobs))
    lines = [f"| injection ({a.mode}) | detected after [ms] | fault | zero torque after [ms] | excursion [mm] |"
             " largest torque after detection [N m] | peak contact force [N] |", "|---|---:|---|---:|---:|---:|---:|"]
    for spec, r in results:
        at = r["at_s"]
        lines.append(f"| `{spec}` | {ms(r['detected_s'], at)} | {r['fault'] or '-'} | {ms(r['zero_torque_s'], at)} | "
                     f"{r['excursion_mm']:.2f} | {r['max_torque_after_detection_Nm']:.2f} | "
                     f"{r['peak_contact_force_N']:.1f} |")
    if a.full:
        full = os.path.relpath(os.path.abspath(a.full), ROOT)  # the repository's path, not this checkout's
        with open(a.full, "w") as f:
            f.write(f"# Fault injection, every run ({a.mode})\n\nWritten by `python3 scripts/injection_table.py "
                    f"--mode {a.mode} --full {full}` (or `scripts/docs_tables.py --kind long --only injection`)."
                    "\n\n" + "\n".join(lines) + "\n")
    if a.summary:
        print_summary(results)
    else:
        print("\n".join(lines))


def print_summary(results):
    """By kind: worst detection, how many within 50 ms and 5 mm, the faults raised, a contact's force."""
    print("| kind | runs | worst detection [ms] | detected ≤ 50 ms | faults raised | worst excursion [mm] | "
          "excursion ≤ 5 mm | largest torque after detection [N m] | largest contact force [N] |")
    print("|---|---:|---:|---:|---|---:|---:|---:|---:|")
    contacts = {kind for kind, form in kinds() if form in AFTER}
    groups = {}
    for spec, r in results:
        kind = spec.split("@")[0].split(":")[0]
        label = f"`{kind}` at t = 0" if r["at_s"] == 0 else f"`{kind}`"
        groups.setdefault(label, (kind, []))[1].append(r)
    for label, (kind, rs) in groups.items():
        det = [None if r["detected_s"] is None else (r["detected_s"] - r["at_s"]) * 1e3 for r in rs]
        worst = "never" if any(d is None for d in det) else f"{max(det):.0f}"
        fast = sum(1 for d in det if d is not None and d <= 50)
        faults = sorted({f for r in rs for f in r["faults"]})
        exc = [r["excursion_mm"] for r in rs]
        force = f"{max(r['peak_contact_force_N'] for r in rs):.0f}" if kind in contacts else "-"
        print(f"| {label} | {len(rs)} | {worst} | {fast}/{len(rs)} | {', '.join(faults)} | {max(exc):.2f} | "
              f"{sum(1 for e in exc if e <= 5)}/{len(rs)} | "
              f"{max(r['max_torque_after_detection_Nm'] for r in rs):.2f} | {force} |")


if __name__ == "__main__":
    main()
