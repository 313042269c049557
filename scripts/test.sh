#!/usr/bin/env bash
# Sets up, builds, lints (scripts/lint.sh) and runs every test: host (kernels, simulator,
# experiment), the Cortex-M4F and Cortex-M3 cross builds (image checks and firmware tests under QEMU; the M3 runs the fixed-point
# controller), and the sanitizer build (the host tests under ASan + UBSan, and each libFuzzer target
# for a fixed time: docs/fuzzing.md).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cmake --preset host >/dev/null
cmake --build --preset host
bash scripts/lint.sh build/host
ctest --preset host
if [ -f boards/CMakeLists.txt ]; then
  for preset in m4f m3; do
    cmake --preset $preset >/dev/null
    cmake --build --preset $preset
    ctest --preset $preset
  done
fi
cmake --preset fuzz >/dev/null
cmake --build --preset fuzz
ctest --preset fuzz
