#!/usr/bin/env bash
# run_under_load.sh N COMMAND [ARGS...]: runs COMMAND while N busy processes (shell loops at the same
# priority) compete for the cores, and exits with its status. The busy processes end with COMMAND,
# and in any case after 20 minutes. For tests that must pass on a loaded machine (CI shares its two
# cores with other work): e.g. the PIL link over QEMU's UART (ctest pil_qemu_uart_loaded).
set -u
n=${1:?usage: run_under_load.sh N COMMAND [ARGS...]}
shift
pids=()
trap 'kill "${pids[@]}" 2>/dev/null' EXIT
for ((i = 0; i < n; i++)); do
  timeout 1200 bash -c 'while :; do :; done' &
  pids+=($!)
done
"$@"
