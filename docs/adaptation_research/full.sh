#!/bin/bash
# Full 3600 s table for the given laws: corke/paper/none friction and model error -0.1/+0.1.
cd /work/wt8
for law in "$@"; do
  out8/run.sh full_${law}_corke --duration 3600 --adaptation $law --friction corke --windows
  out8/run.sh full_${law}_paper --duration 3600 --adaptation $law --windows
  out8/run.sh full_${law}_none --duration 3600 --adaptation $law --friction none --windows
  out8/run.sh full_${law}_me-0.1 --duration 3600 --adaptation $law --model-error -0.1 --windows
  out8/run.sh full_${law}_me+0.1 --duration 3600 --adaptation $law --model-error 0.1 --windows
done
