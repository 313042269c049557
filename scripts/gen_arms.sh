#!/usr/bin/env bash
# Regenerates every arm's table (firmware/robots/include/osc/robots/<arm>.hpp) from its description
# (firmware/robots/<arm>/<arm>.yaml and the URDF it names) with tools/armgen: docs/arms.md. The host
# build checks the committed tables (target arm_tables) and fails while one differs from this.
# usage: scripts/gen_arms.sh [--check] [HOST_BUILD_DIR]   (default build/host; --check: compare only)
set -euo pipefail
cd "$(dirname "$0")/.."
mode=write
if [ "${1:-}" = "--check" ]; then mode=check; shift; fi
build=${1:-build/host}
[ -f "$build/build.ninja" ] || cmake --preset host >/dev/null
cmake --build "$build" --target armgen >/dev/null
armgen=$build/tools/armgen/armgen
status=0
for sheet in firmware/robots/*/*.yaml; do
  arm=$(basename "$sheet" .yaml)
  header=firmware/robots/include/osc/robots/$arm.hpp
  if [ $mode = write ]; then
    "$armgen" "$sheet" --output "$header" && echo "gen_arms: wrote $header" || status=$?
  else
    "$armgen" "$sheet" --check "$header" && echo "gen_arms: $header is current" || status=$?
  fi
done
exit $status
