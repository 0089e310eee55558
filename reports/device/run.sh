#!/bin/bash
# One prepared device run: 16-core figures for issues 31 and 37.
set -u
D=.dev
T0=$(date +%s)
{ date -u; nproc; lscpu; free -g; cat /proc/loadavg; ls -la /usr/bin/time; } > $OUT/machine.txt 2>&1
el() { echo "elapsed $(( $(date +%s) - T0 )) s: $*" >> $OUT/progress.txt; }
# 1. Kernel strong scaling (issue 37): 32k fcc block, 100 steps; 1M, 5 steps.
for t in 1 2 4 8 16; do for w in spacing oriented; do
  echo "work=$w threads=$t cells=20 $(timeout 60 $D/performance_report child $w $t 100 - 20 2>&1)"
done; done > $OUT/kernels.txt
el kernels 32k
for t in 1 4 16; do for w in spacing oriented; do
  echo "work=$w threads=$t cells=63 $(timeout 90 $D/performance_report child $w $t 5 - 63 2>&1)"
done; done >> $OUT/kernels.txt
el kernels 1M
# 2. Determinism: the same frames at 1 and 16 threads.
for s in sheet_on_sphere fig_14_sphere_to_torus ball_vs_spiral; do
  for t in 1 16; do timeout 60 $D/opsim run scenes/$s.ron --threads $t --out /tmp/det_$t >/dev/null 2>&1; done
  if diff -r -q /tmp/det_1/frames /tmp/det_16/frames > /tmp/d.txt 2>&1 && cmp <(cut -d, -f1-7 /tmp/det_1/metrics.csv) <(cut -d, -f1-7 /tmp/det_16/metrics.csv) >> /tmp/d.txt 2>&1; then echo "$s: frames and metrics identical at 1 and 16 threads ($(ls /tmp/det_1/frames | wc -l) frame entries)"; else echo "$s: DIFFER"; head -5 /tmp/d.txt; fi
  rm -rf /tmp/det_1 /tmp/det_16
done > $OUT/determinism.txt 2>&1
el determinism
# 3. Whole scenes at 1..16 threads.
export OPSIM=$D/opsim OP_ROOT=$PWD OP_REPS=1
OP_THREADS=1,2,4,8,16 OP_ONLY="ball_vs_spiral,sheet_on_sphere,sheet_on_box,fig_14,fig_10_,cloth_on_box,fig_13_handle,cloth 100x100,cloth 316,radius 12,radius 29,100000 torus" \
  OP_REPORT=$OUT/scenes16.md timeout 330 $D/scenes_report 2> $OUT/scenes16.log
el scenes
OP_THREADS=1,4,16 OP_ONLY="1000000 torus" OP_REPORT=$OUT/fit16.md timeout 150 $D/scenes_report 2> $OUT/fit16.log
el fit
