#!/usr/bin/env bash
# Cascade run 38: cascade-37 epoch 6 (the coarse stage on the half-resolution grid over 16
# spheres, trained alone for 1,200 steps) grown into the stride-4 correlation at the coarse
# stage's samples (`--coarse-stride4 on`: the stride-8 features blur a depth edge over about
# two pixels of that grid, and cascade-37 still missed by over 20 at a third of the pixels
# whose 4 x 4 output block holds an edge; the new inputs start at zero weights), then the
# coarse stage trained alone again (`--train-only coarse`). Adam 1e-4 for 6 epochs of 200
# steps, then 1e-5 for 2; seed 137.
# Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/runs/omnimvs-c38}
RUN=${RUN:-/work/runs/cascade-38}
INIT=${INIT:-/work/main/models/training/cascade-37/epoch6.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --convex-upsampling half --stage-intervals 2.5,1.5 \
  --coarse-scale 2 --coarse-spheres 16 --coarse-stride4 on \
  --coarse-cue-oversample 1 --coarse-cue-depths 3 --coarse-cue-sgm on \
  --init "$INIT" \
  --train-only coarse --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.0001 --lr-low 0.00001 --low-lr-epochs 2 --epochs 8 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-val-frames 40 --seed 137 --max-steps 200 \
  --column-window 160 --photometric on --out "$RUN"
