#!/usr/bin/env bash
# Configures one CMake preset (cmake --preset PRESET [ARGS]) for scripts/run.sh and scripts/test.sh.
# A build folder left by another generator (the presets used Unix Makefiles until 2026-11-28, Ninja
# since) is configured afresh (--fresh) rather than refused.
set -euo pipefail
cd "$(dirname "$0")/.."
preset=$1
shift
dir=$(python3 -c 'import json, sys
for p in json.load(open("CMakePresets.json"))["configurePresets"]:
    if p["name"] == sys.argv[1]:
        print(p["binaryDir"].replace("${sourceDir}/", ""))' "$preset")
cache=${dir:+$dir/CMakeCache.txt}
fresh=()
if [ -n "$cache" ] && [ -f "$cache" ] && ! grep -q '^CMAKE_GENERATOR:INTERNAL=Ninja$' "$cache"; then
  echo "configure: $dir was made by another generator; configuring it afresh" >&2
  fresh=(--fresh)
fi
# A folder configured with another compiler than the preset's (the host preset compiled with GCC until
# 2026-12-06, clang since) is configured afresh too: CMake does not change a cache's compiler.
want_cxx=$(python3 -c 'import json, sys
for p in json.load(open("CMakePresets.json"))["configurePresets"]:
    if p["name"] == sys.argv[1]:
        print(p.get("cacheVariables", {}).get("CMAKE_CXX_COMPILER", ""))' "$preset")
have_cxx=$( [ -f "$cache" ] && sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' "$cache" || true)
if [ -n "$want_cxx" ] && [ -n "$have_cxx" ] && [ "${have_cxx##*/}" != "$want_cxx" ]; then
  echo "configure: $dir was configured with another compiler than $want_cxx; configuring it afresh" >&2
  fresh=(--fresh)
fi
cmake --preset "$preset" "${fresh[@]}" "$@" >/dev/null
