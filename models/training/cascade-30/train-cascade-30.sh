#!/usr/bin/env bash
# Cascade run 30: the full-resolution stage alone (`--train-only fine`: its regulariser and the
# stride-2 projection) with its outermost hypotheses stretched to the lowest and highest centre
# of the 9 x 9 pixels around each pixel (`--neighbour-extremes 0,4`, stop 33). Why
# (`../cascade-29/hyp_study.py`, `hyp_radii.txt`): with radius 1 (cascade-29) the best of the
# full stage's hypotheses is within 1 index unit of the truth at only 41.5 % of the pixels
# within 4 px of a depth edge, and 500 steps did not teach the stage to use them; with radius 4
# the best of its hypotheses would answer with a mean error of 3.54 index units over all
# pixels (the network 7.54, on things validation frames 481-490), if the stage could pick it.
# Starts from the bundled cascade-25 epoch 4. Adam 1e-4 for 6 epochs of 300 steps, then 2 at
# 1e-5; seed 97. Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/runs/omnimvs-c29}
RUN=${RUN:-/work/runs/cascade-30}
INIT=${INIT:-/work/main/models/training/cascade-25/epoch4.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --convex-upsampling half --stage-intervals 2.5,1.5 --neighbour-extremes 0,4 \
  --coarse-cue-oversample 2 --coarse-cue-depths 3 --coarse-cue-sgm on \
  --init "$INIT" \
  --train-only fine --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.0001 --lr-low 0.00001 --low-lr-epochs 2 --epochs 8 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-val-frames 40 --seed 97 --max-steps 300 \
  --column-window 160 --photometric on --out "$RUN"
