#!/usr/bin/env bash
# Sets up, builds, lints (scripts/lint.sh) and runs every test: host (kernels, simulator,
# experiment; the closed-loop runs of label "long" included), the Cortex-M4F and Cortex-M3 cross
# builds (image checks and firmware tests under QEMU; the M3 runs the fixed-point controller), and
# the sanitizer build (the host tests but label "long" under ASan + UBSan, and each libFuzzer target
# for a fixed time: docs/fuzzing.md). Not here: the hours of scripts/long_runs.sh (docs/long_runs.md).
set -euo pipefail
cd "$(dirname "$0")/.."
# Each stage's wall time, printed as it ends (CI must stay under 45 minutes on the 2-core machine).
stage_start=$SECONDS
stage() { echo "test.sh: $1 took $((SECONDS - stage_start)) s (total $SECONDS s)"; stage_start=$SECONDS; }
bash scripts/setup.sh
stage setup
bash scripts/configure.sh host
cmake --build --preset host
stage "host build"
bash scripts/lint.sh build/host
stage lint
# Every host test, label "long" included (docs/long_runs.md): ctest's "Label Time Summary" at the
# end of its output gives that label's share of this stage. Four at a time on the two cores (the
# preset's jobs): the virtual board's tests run the simulator at the wall clock's pace and leave a
# core idle; two at a time kept 75 % of the cores busy, 201 s, and four take 151 s (2026-12-06).
ctest --preset host
stage "host tests"
if [ -f boards/CMakeLists.txt ]; then
  # puma_experiment without SIMD: the M4F's motion test compares the image with its float controller.
  bash scripts/configure.sh host-scalar
  cmake --build --preset host-scalar
  stage "host-scalar build"
  for preset in m4f m3; do
    bash scripts/configure.sh $preset
    cmake --build --preset $preset
    stage "$preset build"
    ctest --preset $preset
    stage "$preset tests"
  done
fi
bash scripts/configure.sh fuzz
cmake --build --preset fuzz
stage "fuzz build"
ctest --preset fuzz
stage "fuzz tests"
