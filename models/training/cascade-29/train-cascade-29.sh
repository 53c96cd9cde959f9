#!/usr/bin/env bash
# Cascade run 29: the full-resolution stage alone (`--train-only fine`: its regulariser and
# the stride-2 projection) with its outermost hypotheses stretched to the lowest and highest
# centre of the 3 x 3 pixels around each pixel (`--neighbour-extremes 0,1`, stop 33). Why: two
# thirds of the things error lies within 4 px of a depth edge, where the centres blend the
# two surfaces; the better of a pixel's answer and its 3 x 3 neighbourhood's extremes would
# halve the error (stop 32). Starts from the GPU call of stop 33 (run-b: cascade-25 epoch 4
# with the stretch, 200 steps at Adam 1e-4 on one H200, `gpu-epoch1.safetensors`).
# Adam 1e-4 for 6 epochs of 300 steps, then 2 at 1e-5; seed 89.
# Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/runs/omnimvs-c29}
RUN=${RUN:-/work/runs/cascade-29}
INIT=${INIT:-/work/main/models/training/cascade-29/gpu-epoch1.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --convex-upsampling half --stage-intervals 2.5,1.5 --neighbour-extremes 0,1 \
  --coarse-cue-oversample 2 --coarse-cue-depths 3 --coarse-cue-sgm on \
  --init "$INIT" \
  --train-only fine --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.0001 --lr-low 0.00001 --low-lr-epochs 2 --epochs 8 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-val-frames 40 --seed 89 --max-steps 300 \
  --column-window 160 --photometric on --out "$RUN"
