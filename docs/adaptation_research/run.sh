#!/bin/bash
# usage: run.sh TAG args...   -> out8/TAG.txt, prints SUMMARY
tag=$1; shift
cd /work/wt8 && ./build/host/host_sim/puma_experiment --mode adaptive --no-csv --no-progress "$@" > out8/$tag.txt 2>&1
echo "$tag: $(grep SUMMARY out8/$tag.txt)"
