#!/usr/bin/env bash
# The long runs, which CI does not run (docs/long_runs.md): every generated table of kind "long" in
# docs/ (scripts/docs_tables.py --kind long: the QEMU experiment, the fault-injection matrix, the
# one-hour runs of every law, plant and scalar, the monitors' margins, the residual monitor's runs,
# the identify run's sweeps, the host benchmarks), regenerated in place, then the four-hour soak of the default law
# (docs/adaptation.md, section 5; scripts/soak_hours.py). Hours of simulated time, most of an hour of
# wall time on the 2-core machine. The host tests of label "long" are not these: `ctest --preset
# host` runs them, in scripts/test.sh and CI.
#
# usage: bash scripts/long_runs.sh [--check] [--no-soak] [--only TABLE ...] [--fuzz | --fuzz-only]
#   --check      compare each table with the docs (numbers within 2 %) instead of writing it; the
#                wall-clock figures (host_benchmarks, the QEMU experiment's wall time) differ anyway
#   --no-soak    the tables only
#   --only T     only table T (repeatable; implies --no-soak)
#   --fuzz       then every libFuzzer target for 10^7 inputs or 15 minutes (docs/fuzzing.md, "Long
#                runs"; the sanitizer build): up to two hours more
#   --fuzz-only  the fuzz targets' long runs alone
# It ends with the line to record in docs/long_runs.md: date, revision, tables done of all, the soak,
# the fuzz targets. Exit 1 when a table failed (a run that faulted where its table expects none, a
# build missing), the soak faulted or a fuzz target found something (its input: build/fuzz/tests/fuzz/
# crash-*). Written tables: review with git diff docs/.
set -euo pipefail
cd "$(dirname "$0")/.."
check=() only=() soak=1 tables=1 fuzz=0
while (($#)); do
  case $1 in
    --check) check=(--check) ;;
    --no-soak) soak=0 ;;
    --only) only+=(--only "$2"); soak=0; shift ;;
    --fuzz) fuzz=1 ;;
    --fuzz-only) fuzz=1 tables=0 soak=0 ;;
    *) echo "long_runs.sh: unknown argument $1 (see the header of scripts/long_runs.sh)" >&2; exit 2 ;;
  esac
  shift
done
stage_start=$SECONDS
stage() { echo "long_runs.sh: $1 took $((SECONDS - stage_start)) s (total $SECONDS s)"; stage_start=$SECONDS; }
revision=$(git rev-parse --short HEAD)$(git diff --quiet HEAD -- . ':!docs' || echo "+changes")
bash scripts/setup.sh
status=0
tables_result="not run"
if ((tables)); then
  bash scripts/configure.sh host
  # the test binaries of the tables of 20-seed and nine-payload sweeps (sigma_coverage, payload_identified)
  cmake --build --preset host --target puma_experiment osc_bench test_identification_loop test_identify_sim
  bash scripts/configure.sh m4f
  cmake --build --preset m4f --target pil_firmware  # the QEMU experiment's image
  stage builds
  log=$(mktemp)
  python3 scripts/docs_tables.py --kind long --keep-going "${check[@]}" "${only[@]}" | tee "$log" || status=1
  tables_result=$(tail -n 1 "$log")
  rm -f "$log"
  stage tables
fi
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
fuzz_result="not run"
if ((fuzz)); then
  bash scripts/configure.sh fuzz
  mapfile -t targets < <(cd tests/fuzz/corpus && ls -d fuzz_*)
  cmake --build --preset fuzz --target "${targets[@]}"
  stage "fuzz build"
  clean=0
  for t in "${targets[@]}"; do
    extra=()
    case $t in
      fuzz_frames) extra=(-max_len=300) ;;      # two frames and garbage
      fuzz_pil_client) extra=(-max_len=600) ;;  # more than one 512-byte read
    esac
    [ -f "tests/fuzz/$t.dict" ] && extra+=("-dict=$PWD/tests/fuzz/$t.dict")
    # Over a copy of its corpus (run_fuzzer.sh); a crash's input stays in build/fuzz/tests/fuzz.
    if (cd build/fuzz/tests/fuzz && sh "$OLDPWD/tests/fuzz/run_fuzzer.sh" "./$t" "$OLDPWD/tests/fuzz/corpus/$t" \
          -runs=10000000 -max_total_time=900 -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 "${extra[@]}"); then
      clean=$((clean + 1))
    else
      status=1
    fi
    stage "$t"
  done
  fuzz_result="$clean of ${#targets[@]} fuzz targets without a finding"
fi
echo "long_runs.sh: $(date -u +%F), revision $revision: tables: $tables_result; soak: $soak_result; fuzz: $fuzz_result; $SECONDS s" \
     "($([ $status -eq 0 ] && echo pass || echo FAIL))"
exit $status
