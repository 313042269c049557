#!/usr/bin/env bash
# The C++ client installed (docs/motion.md, "The C++ client installed"): cmake --install of this build's
# component osc_client into a new prefix puts there the library, its headers and the firmware's they
# include, and the package (nothing else, and nothing that names the source tree); examples/cpp_client
# configures and builds against it alone (find_package, the same compiler) in a new build folder; on
# osc_sim --pty the example reads the state, enables, moves, sees the move done and disables (exit 0);
# with the E-stop pressed, enable is refused (exit 1, nothing moved); a bad argument or port is a named
# error, exit 2.
#
# usage: cpp_client_install.sh CMAKE BUILD_DIR SOURCE_DIR CXX GENERATOR ROBOT OSC_SIM
set -euo pipefail
cmake=$1 build=$2 src=$3 cxx=$4 generator=$5 robot=$6 sim=$7
# $tmp, its cleanup on exit (stopping $sim_pid), fail.
. "${BASH_SOURCE[0]%/*}/scratch.sh"
prefix=$tmp/prefix

# (a) Installed: the component alone.
"$cmake" --install "$build" --component osc_client --prefix "$prefix" >"$tmp/install.log" 2>&1 ||
  { cat "$tmp/install.log"; fail "cmake --install $build --component osc_client"; }
echo "installed $(grep -c '^-- Installing' "$tmp/install.log") files into the prefix"
for f in include/osc_client/osc_client.hpp include/osc_client/osc/robot.hpp include/osc_client/osc/link/frames.hpp; do
  [ -f "$prefix/$f" ] || fail "no $f in the prefix"
done
config=$(find "$prefix" -path '*/cmake/osc_client/osc_clientConfig.cmake')
[ -n "$config" ] || fail "no cmake/osc_client/osc_clientConfig.cmake in the prefix"
[ -f "$(dirname "$config")/osc_clientConfigVersion.cmake" ] || fail "no osc_clientConfigVersion.cmake"
others=$(cd "$prefix" && find . -type f ! -path './include/osc_client/*' ! -path '*/cmake/osc_client/*' ! -name libosc_client.a)
[ -z "$others" ] || fail "installed besides the client: $others"
! grep -rlF -e "$src" -e "$build" "$prefix" >"$tmp/named" || fail "installed files name the source or build tree: $(cat "$tmp/named")"

# (b) The example, built apart against the prefix.
"$cmake" -S "$src/examples/cpp_client" -B "$tmp/example" -G "$generator" -DCMAKE_CXX_COMPILER="$cxx" \
  -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release >"$tmp/configure.log" 2>&1 ||
  { cat "$tmp/configure.log"; fail "configuring examples/cpp_client against the prefix"; }
grep -E "osc_client [0-9.]+ for the arm $robot\$" "$tmp/configure.log" || fail "the package does not name the arm $robot"
"$cmake" --build "$tmp/example" -j 1 >"$tmp/build.log" 2>&1 || { cat "$tmp/build.log"; fail "building examples/cpp_client"; }
example=$tmp/example/cpp_client

# (d) Bad arguments: named errors, exit 2.
expect_2() {
  local rc=0
  "$example" "$@" >"$tmp/out" 2>&1 </dev/null || rc=$?
  echo "\$ cpp_client $* -> $rc: $(head -1 "$tmp/out")"
  [ "$rc" -eq 2 ] || fail "exit status $rc, expected 2"
  grep -Eq "$pattern" "$tmp/out" || fail "no line matching '$pattern'"
}
pattern='^usage: cpp_client PORT' expect_2
pattern='^usage: cpp_client PORT' expect_2 a b c
pattern="^cpp_client: $tmp/none: No such file" expect_2 "$tmp/none"
pattern="^cpp_client: DY 'far'" expect_2 "$tmp/none" far

# (c) On the virtual board: the steps done; on a board whose E-stop is pressed, enable refused (exit 1).
start_sim() {
  "$sim" --pty --speed 4 "$@" >"$tmp/sim.out" 2>"$tmp/sim.err" &
  sim_pid=$!
  port=
  for _ in $(seq 1200); do
    port=$(sed -n '1s/^pty: //p' "$tmp/sim.out")
    [ -n "$port" ] && [ -e "$port" ] && return 0
    kill -0 "$sim_pid" 2>/dev/null || fail "osc_sim exited: $(cat "$tmp/sim.err")"
    sleep 0.05
  done
  fail "osc_sim printed no 'pty: PATH' line within 60 s"
}
stop_sim() {
  kill -TERM "$sim_pid"
  wait "$sim_pid" || fail "osc_sim exited with status $? on SIGTERM"
  sim_pid=
}
# run STATUS PATTERN...: the example on the board's port, moving 15 mm; its status and lines.
run() {
  local want=$1 rc=0
  shift
  "$example" "$port" 15 >"$tmp/run" 2>&1 </dev/null || rc=$?
  echo "\$ cpp_client PORT 15 -> $rc"
  sed 's/^/    /' "$tmp/run"
  [ "$rc" -eq "$want" ] || fail "cpp_client exited $rc, expected $want"
  for p in "$@"; do
    grep -Eq -- "$p" "$tmp/run" || fail "no line matching '$p'"
  done
}
start_sim
run 0 '^state: disabled$' '^enable: accepted$' '^move \+15 mm along y: done$' '^disable: done$'
stop_sim
start_sim --inject estop@0
run 1 '^faults: estop$' '^enable: refused: faulted'
! grep -q '^move' "$tmp/run" || fail "a move was sent after enable was refused"
stop_sim
echo "PASS: cpp_client_install"
