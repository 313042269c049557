#!/bin/bash
cd /work/wt8
for law in "$@"; do
  for fr in paper corke none; do
    out8/run.sh scr_${law}_$fr --friction $fr --duration 600 --adaptation $law
  done
done
