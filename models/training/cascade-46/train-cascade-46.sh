#!/usr/bin/env bash
# Cascade run 46 (stop 37): cascade-45's best with the coarse stage's evidence squeezed to 64
# channels before its first 3x3 convolution (`--coarse-squeeze 64`: a truncated SVD of that
# layer, the coarse stage's largest), the coarse stage trained on alone (`--train-only
# coarse`) so that it makes up what the rank-64 layer left out; the mix and validation of
# cascade-45 (hard house frames of the published rig in both). Adam 3e-5 for 2 epochs of 200
# steps, then 3e-6 for 1; seed 158. Resumable: rerun this script.
set -euo pipefail
B=${OMNIMVS:-/work/bin/omnimvs}
RUN=${RUN:-/work/runs/cascade-46}
INIT=${INIT:-/work/main/models/training/cascade-45/best.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --convex-upsampling half --stage-intervals 2.5,1.5 \
  --coarse-scale 2 --coarse-spheres 16 --coarse-stride4 on --same-grid-selector on \
  --coarse-squeeze 64 \
  --coarse-cue-oversample 1 --coarse-cue-depths 3 --coarse-cue-sgm on \
  --init "$INIT" --train-only coarse \
  --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.00003 --lr-low 0.000003 --low-lr-epochs 1 --epochs 3 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106,/work/data/house-hard-s107 \
  --val-frames 481..500 --max-val-frames 60 --seed 158 --max-steps 200 \
  --column-window 160 --photometric on --out "$RUN"
