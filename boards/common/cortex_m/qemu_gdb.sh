#!/usr/bin/env bash
# Starts a firmware image in QEMU halted at its reset vector, with QEMU's GDB server on a free local
# port, attaches gdb-multiarch to it, and ends QEMU when gdb exits.
# Usage: qemu_gdb.sh GDB IMAGE.elf QEMU_COMMAND... [-- GDB_ARGUMENTS...]
#   QEMU_COMMAND is the board's command ending with -kernel (boards/CMakeLists.txt); the image
#   follows it. GDB_ARGUMENTS go to gdb after it has connected: none for an interactive session,
#   `-batch -ex ...` for a scripted one (osc_add_debug_test).
set -euo pipefail
gdb=$1
elf=$2
shift 2
qemu=()
while [ $# -gt 0 ] && [ "$1" != "--" ]; do
  qemu+=("$1")
  shift
done
[ $# -gt 0 ] && shift
port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
"${qemu[@]}" "$elf" -S -gdb "tcp:127.0.0.1:$port" &
qemu_pid=$!
trap 'kill "$qemu_pid" 2>/dev/null || true; wait "$qemu_pid" 2>/dev/null || true' EXIT
echo "qemu_gdb: QEMU (pid $qemu_pid) halted, GDB server on 127.0.0.1:$port"
# gdb retries the connection until QEMU listens (tcp auto-retry, within connect-timeout).
"$gdb" -q -nx -ex "set confirm off" -ex "set pagination off" -ex "set tcp connect-timeout 20" \
  -ex "target remote 127.0.0.1:$port" "$elf" "$@"
