#!/usr/bin/env bash
# Every test of the firmware built for another arm (CMake OSC_ROBOT; docs/arms.md): the host build
# (its tests; those marked PUMA, of the PUMA's own figures, are skipped), the float controller
# without SIMD (host-scalar, what the M4F image is compared with bit for bit), and the Cortex-M4F and
# Cortex-M3 images with their QEMU tests (closed loop against the host's controller, the motion tour
# bit for bit, the instruction counts). Each in its own folder, build/<arm>, build/<arm>-scalar,
# build/<arm>-m4f and build/<arm>-m3, so that the default (PUMA) builds are left as they are. The
# docs' tables are the PUMA's (a build for another arm does not define their checks); the arms'
# table (docs/arms.md, arm_instructions: every arm's counts side by side) is checked last.
# A long run (docs/long_runs.md): about 40 minutes from nothing on the 2-core machine; CI runs the
# default arm only (scripts/test.sh).
#
# usage: bash scripts/test_arm.sh ARM      (ARM: a folder firmware/robots/ARM/ with ARM.yaml; e.g. ur5e)
set -euo pipefail
cd "$(dirname "$0")/.."
if (($# != 1)); then
  echo "test_arm.sh: usage: bash scripts/test_arm.sh ARM (an arm of firmware/robots/)" >&2
  exit 2
fi
arm=$1
if [ ! -f "firmware/robots/$arm/$arm.yaml" ]; then
  echo "test_arm.sh: no arm '$arm': firmware/robots/$arm/$arm.yaml does not exist (docs/arms.md)" >&2
  exit 2
fi
stage_start=$SECONDS
stage() { echo "test_arm.sh: $arm: $1 took $((SECONDS - stage_start)) s (total $SECONDS s)"; stage_start=$SECONDS; }
bash scripts/setup.sh
root=$PWD
host=build/$arm scalar=build/$arm-scalar
cmake --preset host -B "$host" -DOSC_ROBOT="$arm" >/dev/null
cmake --build "$host" -j2
stage "host build"
(cd "$host" && ctest -j2 --output-on-failure)
stage "host tests"
cmake --preset host-scalar -B "$scalar" -DOSC_ROBOT="$arm" >/dev/null
cmake --build "$scalar" -j2 --target puma_experiment
stage "host-scalar build"
for preset in m4f m3; do
  dir=build/$arm-$preset
  cmake --preset $preset -B "$dir" -DOSC_ROBOT="$arm" -DOSC_HOST_TOOLS_DIR="$root/$host" \
    -DOSC_HOST_SCALAR_TOOLS_DIR="$root/$scalar" >/dev/null
  cmake --build "$dir" -j2
  stage "$preset build"
  (cd "$dir" && ctest --output-on-failure)
  stage "$preset tests"
done
# The arms' instruction counts side by side (docs/arms.md, table arm_instructions): the default arm's
# images from the m4f and m3 presets' builds.
for preset in m4f m3; do
  bash scripts/configure.sh $preset
  cmake --build --preset $preset --target kernels_image timer_worst_firmware
done
python3 scripts/docs_tables.py --check --kind arms
stage "arms table"
echo "test_arm.sh: $arm: pass ($SECONDS s)"
