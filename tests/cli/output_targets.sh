#!/usr/bin/env bash
# output_targets.sh PUMA_EXPERIMENT PYTHON PLOT_SCRIPT CASE: one check of how puma_experiment (and the
# figures' script) writes an output to what is at its path (host_sim/output_file.hpp). Each CASE checks
# the exit status, the message and what ends up at the path. Exit 0: pass; 77: skipped (ctest's
# SKIP_RETURN_CODE: a full tmpfs needs mount(2), root's); anything else: fail, with the reason.
set -u
exe=$1 py=$2 plot=$3 case=$4
d=$(mktemp -d)
trap 'mountpoint -q "$d/small" 2>/dev/null && umount "$d/small"; rm -rf "$d"' EXIT
cd "$d" || exit 1
fail() { echo "FAIL ($case): $*"; exit 1; }
# A one-second run of one mode: enough for a summary.
run() { "$exe" --duration 1 --mode adaptive --no-progress --no-csv "$@"; }
is_summary() { "$py" -c 'import json,sys; j=json.load(open(sys.argv[1])); assert j["program"]=="puma_experiment"' "$1" 2>/dev/null; }
no_temp_files() { test -z "$(find "${1:-.}" -name '.*.??????' 2>/dev/null)"; }

case $case in
new)  # a new path: created, a regular file of JSON, announced
  out=$(run --json s.json) || fail "exit $?"
  test -f s.json && ! test -L s.json || fail "s.json is not a regular file"
  is_summary s.json || fail "s.json is not the summary"
  echo "$out" | grep -qx 'summary: s.json' || fail "no 'summary: s.json' line"
  no_temp_files || fail "temporary files left"
  ;;
regular)  # an existing file: replaced whole, its mode kept
  echo old > s.json && chmod 640 s.json
  run --json s.json >/dev/null || fail "exit $?"
  is_summary s.json || fail "s.json is not the summary"
  test "$(stat -c %a s.json)" = 640 || fail "mode $(stat -c %a s.json), not 640"
  no_temp_files || fail "temporary files left"
  ;;
symlink)  # a link to a file: the link stays, its target gets the summary
  mkdir t && echo old > t/target.json && ln -s t/target.json s.json
  run --json s.json >/dev/null || fail "exit $?"
  test -L s.json && test "$(readlink s.json)" = t/target.json || fail "s.json is no longer the link"
  is_summary t/target.json || fail "the link's target is not the summary"
  no_temp_files || fail "temporary files left"
  ;;
dangling_symlink)  # a link to a file not there yet: created at the target
  ln -s target.json s.json
  run --json s.json >/dev/null || fail "exit $?"
  test -L s.json || fail "s.json is no longer a link"
  is_summary target.json || fail "target.json is not the summary"
  ;;
fifo)  # a named pipe with a reader: written in place, the pipe stays a pipe
  mkfifo p
  cat p > got &
  reader=$!
  run --json p >/dev/null || fail "exit $?"
  wait $reader
  test -p p || fail "p is no longer a FIFO"
  is_summary got || fail "the reader did not get the summary"
  ;;
stdout_dash)  # "-": the summary alone on standard output, the tables on standard error
  run --json - > o.json 2> e.txt || fail "exit $?"
  is_summary o.json || fail "standard output is not the summary alone"
  grep -q 'Maximum tracking errors' e.txt || fail "the tables are not on standard error"
  ;;
dev_stdout_pipe)  # --json /dev/stdout | a reader: JSON through the pipe, /dev/stdout untouched
  run --json /dev/stdout 2>/dev/null | cat > o.json
  test "${PIPESTATUS[0]}" -eq 0 || fail "exit ${PIPESTATUS[0]}"
  is_summary o.json || fail "the pipe did not carry the summary alone"
  test -L /dev/stdout || fail "/dev/stdout is no longer a link"
  ;;
dev_full)  # a device that refuses: exit 2 with the system's reason, the device left a device
  out=$(run --json /dev/full 2>&1)
  status=$?
  test $status -eq 2 || fail "exit $status, not 2"
  echo "$out" | grep -q 'cannot write /dev/full: No space left on device' || fail "message: $out"
  test -c /dev/full || fail "/dev/full is no longer a character device"
  ;;
full_tmpfs)  # a full file system: exit 2, the old file as it was, no temporary file left
  mkdir small
  mount -t tmpfs -o size=16k tmpfs small 2>/dev/null || { echo "SKIP: cannot mount a tmpfs here"; exit 77; }
  echo old > small/s.json
  head -c 20000 /dev/zero > small/filler 2>/dev/null
  out=$(run --json small/s.json 2>&1)
  status=$?
  test $status -eq 2 || fail "exit $status, not 2"
  echo "$out" | grep -q 'cannot write small/s.json: No space left on device' || fail "message: $out"
  test "$(cat small/s.json)" = old || fail "the old file was changed"
  no_temp_files small || fail "temporary files left"
  ;;
directory)  # a directory: refused before the run
  mkdir s.json
  out=$(run --duration 3600 --json s.json 2>&1)
  status=$?
  test $status -eq 2 || fail "exit $status, not 2"
  echo "$out" | grep -q 'cannot write s.json: it is a directory' || fail "message: $out"
  ! echo "$out" | grep -q 'real time' || fail "the run started"
  ;;
csv_symlink)  # a time series whose name is a link: written through, the link stays
  mkdir out && ln -s ../kept.csv out/timeseries_adaptive.csv
  "$exe" --duration 1 --mode adaptive --no-progress --csv-dir out >/dev/null || fail "exit $?"
  test -L out/timeseries_adaptive.csv || fail "the link was replaced"
  grep -q '^t,' kept.csv || fail "the link's target has no time series"
  ;;
csv_directory)  # a time series whose name is a directory: refused before the run
  mkdir -p out/timeseries_adaptive.csv
  out=$("$exe" --duration 3600 --mode adaptive --no-progress --csv-dir out 2>&1)
  status=$?
  test $status -eq 2 || fail "exit $status, not 2"
  echo "$out" | grep -q 'timeseries_adaptive.csv: it is a directory' || fail "message: $out"
  ;;
figure_symlink_and_directory)  # the figures: a link written through; a directory refused, exit 1
  "$exe" --duration 2 --mode adaptive --no-progress --csv-dir out --json out/summary.json >/dev/null || fail "run: exit $?"
  ln -s ../fig.png out/fig1_tracking_errors.png
  "$py" "$plot" out >/dev/null || fail "plot: exit $?"
  test -L out/fig1_tracking_errors.png || fail "the figure's link was replaced"
  head -c 8 fig.png | grep -q PNG || fail "the link's target is not a PNG"
  rm out/window_max_errors.png && mkdir out/window_max_errors.png
  out=$("$py" "$plot" out 2>&1)
  status=$?
  test $status -eq 1 || fail "plot over a directory: exit $status, not 1"
  echo "$out" | grep -q 'cannot write out/window_max_errors.png: it is a directory' || fail "message: $out"
  no_temp_files out || fail "temporary files left"
  ;;
csv_dir_is_not_a_command)  # a directory name is never handed to a shell: this one used to run `touch pwned`
  "$exe" --duration 1 --mode none --no-progress --csv-dir "x'; touch pwned; echo '" >/dev/null || fail "exit $?"
  test ! -e pwned || fail "the directory's name ran as a command"
  test -d "x'; touch pwned; echo '" || fail "no directory of that name"
  ;;
unwritable_json_fails_before_the_run)  # a missing folder: refused before the run, nothing left behind
  out=$("$exe" --duration 3600 --no-csv --json missing/dir/s.json 2>&1)
  status=$?
  test $status -eq 2 || fail "exit $status, not 2"
  echo "$out" | grep -q 'cannot write missing/dir/s.json' || fail "message: $out"
  ! echo "$out" | grep -q 'real time' || fail "the run started"
  test -z "$(find . -name '*.tmp')" || fail "temporary files left"
  ;;
json_that_is_a_directory_fails_before_the_run)
  mkdir j
  out=$("$exe" --duration 3600 --no-csv --json j 2>&1)
  echo "$out" | grep -q 'is a directory' || fail "message: $out"
  test -z "$(find . -name '*.tmp')" || fail "temporary files left"
  ;;
*)
  fail "unknown case"
  ;;
esac
echo "pass ($case)"
