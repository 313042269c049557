#!/bin/bash
cd /work/wt8
while pgrep -f "out8/full.sh" >/dev/null; do sleep 5; done
out8/run.sh diag_delayed_1e6 --duration 1800 --adaptation delayed --encoder-cpr 1e6 --windows
out8/run.sh diag_paper_1e6 --duration 1800 --adaptation paper --encoder-cpr 1e6 --windows
out8/run.sh diag_delayed_d4 --duration 1800 --adaptation delayed --adapt-delay 4 --windows
