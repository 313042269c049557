#!/usr/bin/env bash
# Sets up, builds and runs every test: host (kernels, simulator, experiment), the Cortex-M4F
# cross build (image checks and firmware tests under QEMU), and the sanitizer build (the host tests
# under ASan + UBSan, and each libFuzzer target for a fixed time: docs/fuzzing.md).
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
cmake --preset fuzz >/dev/null
cmake --build --preset fuzz
ctest --preset fuzz
