#!/bin/sh
# Runs a libFuzzer target over a copy of its seed corpus, so that the repository's corpus stays as
# it is (new inputs go to the copy, which is deleted afterwards); crash artifacts go to the current
# directory.  usage: run_fuzzer.sh FUZZER CORPUS_DIR [libFuzzer options...]
set -eu
fuzzer=$1
corpus=$2
shift 2
work=$(mktemp -d "${TMPDIR:-/tmp}/osc_fuzz.XXXXXX")
trap 'rm -rf "$work"' EXIT INT TERM
mkdir "$work/corpus"
cp "$corpus"/* "$work/corpus/"
"$fuzzer" "$@" "$work/corpus"
