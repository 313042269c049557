#!/usr/bin/env bash
# command_line.sh PUMA_EXPERIMENT CASE [ARGS...]: one check of puma_experiment's command line
# (host_sim/experiment_cli.cpp, config.cpp): a bad value is exit status 2 with one clear message,
# before any run; a repeated option takes its last value and every one is checked; a configuration
# file's errors name the file and the key; --qemu refuses an image that is not an ARM ELF file.
# Exit 0: pass; anything else: fail, with the reason.
set -u
exe=$1 case=$2
shift 2
d=$(mktemp -d)
trap 'rm -rf "$d"' EXIT
fail() { echo "FAIL ($case): $*"; exit 1; }
# run ARGS...: puma_experiment's standard output and error in $out, its exit status in $status.
run() { out=$("$exe" "$@" 2>&1); status=$?; }
# run_stdout ARGS...: the same with its standard output alone in $out.
run_stdout() { out=$("$exe" "$@"); status=$?; }
exit_status_is() { test "$status" -eq "$1" || fail "exit $status, not $1; output: $out"; }
says() { grep -q "$@" <<<"$out" || fail "no '${*: -1}' in: $out"; }
did_not_run() { ! grep -q 'real time' <<<"$out" || fail "the run started: $out"; }

case $case in
exits_2)  # ARGS...: rejected with exit status 2
  "$exe" "$@"
  status=$?
  test $status -eq 2 || fail "exit $status, not 2"
  ;;
negative_value_gets_the_range_error)  # a negative value is out of range, not an unknown option
  run --duration=-5 --no-csv
  says -F -- '--duration: -5 is out of range [1, 86400]'
  ;;
repeated_option_takes_the_last_value)
  run_stdout --duration 5 --duration 1 --mode none --no-csv --no-progress
  says 'simulated 1 s'
  ;;
repeated_option_checks_every_value)  # a bad value before a good one is still an error
  run --duration=-5 --duration 1 --no-csv
  exit_status_is 2
  says -F 'out of range'
  ;;
help_exits_0)  # --help wins over a bad value
  run_stdout --help --duration 0
  exit_status_is 0
  says '^Usage: puma_experiment'
  ;;
accepts_flag_equals_value)  # --flag=value reads as --flag value
  run_stdout --duration=1 --mode=none --no-csv --no-progress
  says 'simulated 1 s'
  ;;
range_errors_read_plainly)
  run --duration 0 --no-csv
  says -F 'out of range [1, 86400]'
  ;;
error_is_one_message_not_the_usage)  # two lines: the error and where to look
  run --mode sideways
  exit_status_is 2
  test "$(echo "$out" | wc -l)" -eq 2 || fail "not two lines: $out"
  says -- '--help lists the options'
  ;;
set_rejects)  # KEY=VALUE: a bad --set is exit 2 before the run (a 3600 s run would print its timing), naming the key
  run --duration 3600 --no-csv --set "$1"
  exit_status_is 2
  did_not_run
  says "${1%%=*}"
  ;;
config_larger_than_1_MiB_is_refused)  # read up to 1 MiB (kMaxConfigBytes): /dev/zero is refused, not read forever
  out=$(timeout 20 "$exe" --config /dev/zero --no-csv 2>&1)
  status=$?
  exit_status_is 2
  says -F 'configuration file /dev/zero is larger than 1 MiB'
  ;;
config_file_errors_name_file_and_key)
  printf 'trajectory:\n  amplitude: 0.1\n  perod: 5\n' >"$d/c.yaml"
  run --config "$d/c.yaml" --no-csv
  exit_status_is 2
  says "c.yaml: unknown key 'trajectory.perod'"
  ;;
qemu_rejects_a_non_elf_image)  # a clear error, exit 2, QEMU never started
  echo hello >"$d/fw.elf"
  run --qemu --elf "$d/fw.elf" --no-csv
  exit_status_is 2
  says 'is not an ELF file'
  ;;
qemu_rejects_a_host_elf_image)  # IMAGE: an ELF file for the host (pil_peer)
  run --qemu --elf "$1" --no-csv
  exit_status_is 2
  says 'not a 32-bit little-endian ARM ELF'
  ;;
*)
  fail "unknown case"
  ;;
esac
echo "pass ($case)"
