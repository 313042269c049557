#!/usr/bin/env python3
"""Per-hour figures of a long run (docs/adaptation.md): the worst 60 s window of each hour (from
120 s on), the mean of the hour's window maxima, and theta^ J1 at the end.
usage: soak_hours.py summary.json"""
import json
import sys


def main(argv):
    if len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    run = json.load(open(argv[1]))["runs"][0]
    w = run["window_s"]
    wins = run["window_max_error"]
    per_hour = int(round(3600 / w))
    print("| hour | worst window x/y/z mm, φx/φy/φz ° | mean of the window maxima x/y/z mm, φx/φy/φz ° |")
    print("|---|---|---|")
    for h in range(len(wins) // per_hour):
        hour = [m for k, m in enumerate(wins[h * per_hour:(h + 1) * per_hour]) if (h * per_hour + k) * w >= 120]
        worst = [max(m[i] for m in hour) for i in range(6)]
        mean = [sum(m[i] for m in hour) / len(hour) for i in range(6)]

        def f(v):
            return "/".join(f"{x:.3f}" for x in v[:3]) + ", " + "/".join(f"{x:.4f}" for x in v[3:])
        print(f"| {h + 1}{' (from 120 s)' if h == 0 else ''} | {f(worst)} | {f(mean)} |")
    th = run["theta_hat"]
    print(f"\nθ̂ J1 at the end: vis {th[0]:.2f}, cou {th[6]:.2f}, sti {th[12]:.2f}; friction rms error "
          f"{run['friction_rms_error_Nm']:.3f} N·m; faults {', '.join(run['faults']) or 'none'}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
