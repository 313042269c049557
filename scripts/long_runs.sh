#!/usr/bin/env bash
# The long runs, which CI does not run (docs/long_runs.md): every generated table of kind "long" in
# docs/ (scripts/docs_tables.py --kind long: the QEMU experiment, the fault-injection matrix, the
# one-hour runs of every law, plant and scalar, the monitors' margins, the residual monitor's runs,
# the host benchmarks), regenerated in place, then the four-hour soak of the default law
# (docs/adaptation.md, section 5; scripts/soak_hours.py). Hours of simulated time, most of an hour of
# wall time on the 2-core machine. The host tests of label "long" are not these: `ctest --preset
# host` runs them, in scripts/test.sh and CI.
#
# usage: bash scripts/long_runs.sh [--check] [--no-soak] [--only TABLE ...]
#   --check    compare each table with the docs (numbers within 2 %) instead of writing it; the
#              wall-clock figures (host_benchmarks, the QEMU experiment's wall time) differ anyway
#   --no-soak  the tables only
#   --only T   only table T (repeatable; implies --no-soak)
# It ends with the line to record in docs/long_runs.md: date, revision, tables done of all, the soak.
# Exit 1 when a table failed (a run that faulted where its table expects none, a build missing) or
# the soak faulted. Written tables: review with git diff docs/.
set -euo pipefail
cd "$(dirname "$0")/.."
check=() only=() soak=1
while (($#)); do
  case $1 in
    --check) check=(--check) ;;
    --no-soak) soak=0 ;;
    --only) only+=(--only "$2"); soak=0; shift ;;
    *) echo "long_runs.sh: unknown argument $1 (see the header of scripts/long_runs.sh)" >&2; exit 2 ;;
  esac
  shift
done
stage_start=$SECONDS
stage() { echo "long_runs.sh: $1 took $((SECONDS - stage_start)) s (total $SECONDS s)"; stage_start=$SECONDS; }
revision=$(git rev-parse --short HEAD)$(git diff --quiet HEAD -- . ':!docs' || echo "+changes")
bash scripts/setup.sh
bash scripts/configure.sh host
cmake --build --preset host --target puma_experiment osc_bench
bash scripts/configure.sh m4f
cmake --build --preset m4f --target pil_firmware  # the QEMU experiment's image
stage builds
status=0
log=$(mktemp)
python3 scripts/docs_tables.py --kind long --keep-going "${check[@]}" "${only[@]}" | tee "$log" || status=1
tables=$(tail -n 1 "$log")
rm -f "$log"
stage tables
soak_result="not run"
if ((soak)); then
  mkdir -p out/long_runs
  build/host/host_sim/puma_experiment --mode adaptive --duration 14400 --no-csv --no-progress \
    --json out/long_runs/soak.json >/dev/null
  python3 scripts/soak_hours.py out/long_runs/soak.json
  faults=$(python3 -c 'import json, sys; print(",".join(json.load(open(sys.argv[1]))["runs"][0]["faults"]))' \
           out/long_runs/soak.json)
  soak_result="four hours, ${faults:-no fault}"
  [ -z "$faults" ] || status=1
  stage "four-hour soak"
fi
echo "long_runs.sh: $(date -u +%F), revision $revision: $tables; soak: $soak_result; $SECONDS s" \
     "($([ $status -eq 0 ] && echo pass || echo FAIL))"
exit $status
