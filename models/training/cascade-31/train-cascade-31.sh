#!/usr/bin/env bash
# Cascade run 31: the half-resolution stage alone (`--train-only mid`: its regulariser) with its
# outermost hypotheses stretched to the lowest and highest centre of the 9 x 9 half-grid pixels
# around each pixel (`--neighbour-extremes 4,0`, stop 33). Why: cascade-30 stretched the full
# stage's over 9 x 9 full-grid pixels, where the best of its hypotheses would halve the error,
# and 900 steps left it short of the bundled network (validation 3.232 -> 3.038 against 2.959):
# the full stage's stride-2 evidence is weak (its answer is 4 % better than its centre). The
# half stage reads the stride-4 features, with 8 hypotheses and twice the channels.
# Starts from the bundled cascade-25 epoch 4. Adam 1e-4 for 6 epochs of 300 steps, then 2 at
# 1e-5; seed 101. Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/runs/omnimvs-c29}
RUN=${RUN:-/work/runs/cascade-31}
INIT=${INIT:-/work/main/models/training/cascade-25/epoch4.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --convex-upsampling half --stage-intervals 2.5,1.5 --neighbour-extremes 4,0 \
  --coarse-cue-oversample 2 --coarse-cue-depths 3 --coarse-cue-sgm on \
  --init "$INIT" \
  --train-only mid --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.0001 --lr-low 0.00001 --low-lr-epochs 2 --epochs 8 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-val-frames 40 --seed 101 --max-steps 300 \
  --column-window 160 --photometric on --out "$RUN"
