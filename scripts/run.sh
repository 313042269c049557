#!/usr/bin/env bash
# Main job: set up, build, and run the paper's experiment on the simulated PUMA 560 (120 s, with
# and without friction compensation); writes out/summary.json, out/timeseries_*.csv and PNG figures.
# Extra arguments go to puma_experiment (e.g. --duration 30, --scalar float).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cmake --preset host >/dev/null
cmake --build --preset host --target puma_experiment
mkdir -p out
./build/host/host_sim/puma_experiment --json out/summary.json --csv-dir out "$@"
/usr/bin/python3 host_sim/plot_experiment.py out
