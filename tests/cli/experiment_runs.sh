#!/usr/bin/env bash
# experiment_runs.sh PUMA_EXPERIMENT PYTHON PLOT_SCRIPT CASE: one check of short experiment runs end
# to end: the summary JSON (read with PYTHON), the console, and the figures of PLOT_SCRIPT
# (host_sim/plot_experiment.py) for an injected fault, a configuration file, a faulted run and a
# folder with an earlier run's data. Exit 0: pass; anything else: fail, with the reason.
set -u
exe=$1 py=$2 plot=$3 case=$4
d=$(mktemp -d)
trap 'rm -rf "$d"' EXIT
fail() { echo "FAIL ($case): $*"; exit 1; }
# has_line FILE GREP_ARGS...: FILE has the line.
has_line() { local f=$1; shift; grep -q "$@" "$f" || fail "no '${*: -1}' in $f: $(cat "$f")"; }
plot() { "$py" "$plot" "$d" >"$d/plot.log" || fail "plot: exit $?"; }

case $case in
injection_is_recorded_in_the_json)  # --inject: the JSON's injection object, the fault detected at once
  "$exe" --duration 2 --mode adaptive --no-csv --no-progress --inject encoder-garbage:3@1 --json "$d/s.json" >/dev/null ||
    fail "exit $?"
  "$py" -c "import json,sys; i=json.load(open(sys.argv[1]))['runs'][0]['injection']; \
assert i['kind']=='encoder-garbage' and 'encoder_range' in i['faults'] and i['detected_s']==1.0, i" "$d/s.json" ||
    fail "the JSON's injection"
  ;;
plots_show_only_this_runs_data)  # a CSV an earlier run left in the folder is not plotted
  "$exe" --duration 2 --mode both --no-progress --csv-dir "$d" --json "$d/summary.json" >/dev/null || fail "run 1: exit $?"
  "$exe" --duration 1 --mode adaptive --no-progress --csv-dir "$d" --json "$d/summary.json" >/dev/null ||
    fail "run 2: exit $?"
  plot
  has_line "$d/plot.log" -x 'plotted runs: adaptive'
  test -f "$d/fig1_tracking_errors.png" || fail "no fig1_tracking_errors.png"
  grep -m1 '^t,' "$d/timeseries_adaptive.csv" | grep -q 'theta_sti_j6' || fail "no theta_sti_j6 column"
  ;;
config_round_trip_reaches_json_and_figures)  # --print-config fed back with one --set: console, JSON, figures
  "$exe" --print-config >"$d/c.yaml" || fail "--print-config: exit $?"
  "$exe" --config "$d/c.yaml" --set trajectory.amplitude=0.1 --duration=3 --mode adaptive --no-progress --csv-dir "$d" \
    --json "$d/summary.json" >"$d/run.log" || fail "run: exit $?"
  has_line "$d/run.log" 'differs from the paper.s set-up in run.duration, trajectory.amplitude'
  "$py" -c "import json,sys; j=json.load(open(sys.argv[1])); assert j['config']['trajectory']['amplitude']==0.1 \
and j['differs_from_paper']==['run.duration','trajectory.amplitude'] and not j['paper_setup'], j['differs_from_paper']" \
    "$d/summary.json" || fail "the JSON's configuration"
  cmp -s "$d/config.yaml" "$d/c.yaml"
  status=$?
  test $status -eq 1 || fail "cmp config.yaml c.yaml: $status, not 1 (the written configuration must differ)"
  plot
  has_line "$d/plot.log" 'titles: .*trajectory.amplitude=0.1'
  test -f "$d/observer_errors.png" || fail "no observer_errors.png"
  ;;
fault_is_named_and_plotted)  # 0.2 m at 2 Hz is more than the robot can follow: the DAC range saturates (the saturation monitor trips)
  "$exe" --duration 2 --mode adaptive --no-progress --set trajectory.amplitude=0.2 --set trajectory.period=0.5 \
    --set trajectory.envelope=10 --csv-dir "$d" --json "$d/summary.json" >"$d/run.log"
  status=$?
  test $status -eq 1 || fail "exit $status, not 1"
  has_line "$d/run.log" 'FAULT saturation at tick 482, t = 0.482 s'
  has_line "$d/run.log" 'q .deg.:'
  has_line "$d/run.log" '(faulted)'
  plot
  has_line "$d/plot.log" 'fault saturation at t = 0.482 s (tick 482): marked'
  test -f "$d/fig1_tracking_errors.png" || fail "no fig1_tracking_errors.png"
  ;;
*)
  fail "unknown case"
  ;;
esac
echo "pass ($case)"
