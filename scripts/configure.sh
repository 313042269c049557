#!/usr/bin/env bash
# Configures one CMake preset (cmake --preset PRESET [ARGS]) for scripts/run.sh and scripts/test.sh.
# A build folder left by another generator (the presets used Unix Makefiles until 2026-11-28, Ninja
# since) is configured afresh (--fresh) rather than refused.
set -euo pipefail
cd "$(dirname "$0")/.."
preset=$1
shift
dir=$(sed -n "/\"name\": \"$preset\"/,/binaryDir/s/.*\"binaryDir\": \"\${sourceDir}\/\(.*\)\".*/\1/p" CMakePresets.json | head -1)
cache=${dir:+$dir/CMakeCache.txt}
fresh=()
if [ -n "$cache" ] && [ -f "$cache" ] && ! grep -q '^CMAKE_GENERATOR:INTERNAL=Ninja$' "$cache"; then
  echo "configure: $dir was made by another generator; configuring it afresh" >&2
  fresh=(--fresh)
fi
cmake --preset "$preset" "${fresh[@]}" "$@" >/dev/null
