#!/usr/bin/env bash
# Main job: set up, build, and run the paper's experiment on the simulated PUMA 560 (120 s, with
# and without friction compensation); writes out/summary.json, out/timeseries_*.csv and PNG figures.
# Extra arguments go to puma_experiment (e.g. --duration 30, --scalar float, --qemu,
# --config my.yaml, --set trajectory.amplitude=0.1; puma_experiment --help).
set -euo pipefail
cd "$(dirname "$0")/.."
# Set-up and build report on stderr: stdout is the experiment's (puma_experiment --print-config > c.yaml).
bash scripts/setup.sh >&2
bash scripts/configure.sh host
cmake --build --preset host --target puma_experiment osc_model_info >&2
# --qemu runs the controller as the Cortex-M4F firmware image in QEMU: build it first.
for a in "$@"; do
  if [ "$a" = "--qemu" ]; then
    bash scripts/configure.sh m4f
    cmake --build --preset m4f --target pil_firmware >&2
  fi
done
# --help and --print-config print and exit: no run, no figures.
for a in "$@"; do
  case "$a" in -h|--help|--print-config) exec ./build/host/host_sim/puma_experiment "$@" ;; esac
done
# Outputs go to out/ unless --csv-dir names another folder (--csv-dir DIR or --csv-dir=DIR).
dir=out
prev=""
for a in "$@"; do
  [ "$prev" = "--csv-dir" ] && dir=$a
  case "$a" in --csv-dir=*) dir=${a#--csv-dir=} ;; esac
  prev=$a
done
mkdir -p "$dir"
# The figures are made whatever the run's status (a faulted run is when they are needed most);
# the script then exits with the run's status.
status=0
./build/host/host_sim/puma_experiment --json "$dir/summary.json" --csv-dir "$dir" "$@" || status=$?
if [ -f "$dir/summary.json" ]; then
  /usr/bin/python3 host_sim/plot_experiment.py "$dir" || true
fi
exit "$status"
