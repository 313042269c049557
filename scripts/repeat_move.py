#!/usr/bin/env python3
"""Writes issue 26's repeated-move motion script (docs/adaptation.md, section 5) to stdout: the paper's
motion for 120 s, a stop, then one short move (DX metres along x and back) repeated N times.

usage: repeat_move.py [--dx 0.03] [--pairs 2400] > out/repeat_hour.yaml
       puma_experiment --motion out/repeat_hour.yaml --adaptation momentum --json out/repeat.json
The JSON's theta_hat_at_sent gives the friction estimates when each command was sent.
"""
import argparse

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--dx", type=float, default=0.03, help="the move's length along x [m] (default 0.03)")
ap.add_argument("--pairs", type=int, default=2400, help="moves there and back (default 2400: about an hour)")
a = ap.parse_args()
if not (0 < abs(a.dx) <= 0.2) or a.pairs < 1:
    ap.error("--dx must be within (0, 0.2] m in size and --pairs at least 1")
print("# the paper's motion for 120 s, then one short move repeated (scripts/repeat_move.py)")
print("timeout: 86400")
print("steps:")
print("  - {at: 0.0, cmd: enable}")
print("  - {at: 0.5, cmd: paper}")
print("  - {at: 120.5, cmd: stop}")
print(f"  - {{after: done, cmd: move_to, position: [{a.dx}, 0.0, 0.0], relative: true}}")
for _ in range(a.pairs):
    print(f"  - {{after: done, cmd: move_to, position: [{-a.dx}, 0.0, 0.0], relative: true}}")
    print(f"  - {{after: done, cmd: move_to, position: [{a.dx}, 0.0, 0.0], relative: true}}")
print("  - {after: done, cmd: disable}")
