#!/usr/bin/env bash
# Sets up, builds and runs every test: host (kernels, simulator, experiment) and the Cortex-M4F
# cross build (image checks and firmware tests under QEMU).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cmake --preset host >/dev/null
cmake --build --preset host
ctest --preset host
if [ -f boards/CMakeLists.txt ]; then
  cmake --preset m4f >/dev/null
  cmake --build --preset m4f
  ctest --preset m4f
fi
