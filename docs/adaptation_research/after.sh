#!/bin/bash
cd /work/wt8
while pgrep -f "out8/full.sh robust" >/dev/null; do sleep 5; done
out8/run.sh long4h_robust --duration 14400 --adaptation robust --windows
out8/run.sh float_robust_paper --duration 3600 --adaptation robust --scalar float --windows
out8/full.sh paper
