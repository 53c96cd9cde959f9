#!/usr/bin/env bash
# Cascade run 42 (stop 36): cascade-40 epoch 2 grown into the half stage's learnt choice among
# the 3 x 3 coarse answers around each pixel (`--same-grid-selector on`: the selector starts at
# each pixel's own answer), the selector alone (`--train-only upsampling`), Adam 3e-3, epochs of
# 100 steps, the mix of cascade-40 (../cascade-41/gen-data.sh); seed 152. A first try at 5e-4
# left the validation unchanged to four digits after 100 steps: the neighbours start with 0.7 %
# of the weight each, and Adam's steps of about the rate move their logits by about 0.1.
# Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/bin/omnimvs}
RUN=${RUN:-/work/runs/cascade-42}
INIT=${INIT:-/work/main/models/training/cascade-40/epoch2.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --convex-upsampling half --stage-intervals 2.5,1.5 \
  --coarse-scale 2 --coarse-spheres 16 --coarse-stride4 on --same-grid-selector on \
  --coarse-cue-oversample 1 --coarse-cue-depths 3 --coarse-cue-sgm on \
  --init "$INIT" --train-only upsampling \
  --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.003 --lr-low 0.0003 --low-lr-epochs 1 --epochs 4 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-val-frames 40 --seed 152 --max-steps 100 \
  --column-window 160 --photometric on --out "$RUN"
