#!/usr/bin/env bash
# Cascade run 47 (stop 37): cascade-46's best (cascade-45's coarse stage squeezed to 64
# channels and trained on) with the half stage's learnt choice among the 3 x 3 coarse answers
# trained alone again (`--train-only upsampling`), for coarse answers that cascade-45 and -46
# moved; the mix and validation of cascade-45. Adam 3e-3 for 3 epochs of 150 steps, then 3e-4
# for 1; seed 159. Resumable: rerun this script.
set -euo pipefail
B=${OMNIMVS:-/work/bin/omnimvs}
RUN=${RUN:-/work/runs/cascade-47}
INIT=${INIT:-/work/main/models/training/cascade-46/best.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --convex-upsampling half --stage-intervals 2.5,1.5 \
  --coarse-scale 2 --coarse-spheres 16 --coarse-stride4 on --same-grid-selector on \
  --coarse-squeeze 64 \
  --coarse-cue-oversample 1 --coarse-cue-depths 3 --coarse-cue-sgm on \
  --init "$INIT" --train-only upsampling \
  --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.003 --lr-low 0.0003 --low-lr-epochs 1 --epochs 4 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106,/work/data/house-hard-s107 \
  --val-frames 481..500 --max-val-frames 60 --seed 159 --max-steps 150 \
  --column-window 160 --photometric on --out "$RUN"
