#!/bin/bash
cd /work/wt8
out8/run.sh s2_d2_vdz100 --duration 1800 --adaptation delayed --adapt-vel-dead-zone 100 --windows
out8/run.sh s2_d4_vdz100 --duration 1800 --adaptation delayed --adapt-delay 4 --adapt-vel-dead-zone 100 --windows
out8/run.sh s2_d2_leak1e-3 --duration 1800 --adaptation delayed --adapt-leak 1e-3 --windows
