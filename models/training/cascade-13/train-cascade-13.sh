#!/usr/bin/env bash
# Cascade run 13: learnt (convex) upsampling between the stages (--convex-upsampling on,
# `cascade.convex_upsampling`: each finer pixel weighs the 3x3 coarser answers around its
# parent by the matching evidence at each of them), grown from the bundled cascade
# (cascade-11 epoch 14), training the two selectors only (--train-only upsampling: every other
# weight and batch-norm statistic stays as loaded). Why: on things validation frames the half stage's bilinear
# centre is within its reach (+-7) of the truth at 63 % of the pixels, one of the 3x3 coarse
# pixels around it at 83 %; the full stage's at 50 %, one of the 2x2 half-resolution pixels
# around it at 62 % (`--example cascade_modes`). Same data, losses, augmentation, window and
# validation frames as cascade-11; Adam 1e-3, then 2e-4 for the last 4 epochs; seed 17.
# Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/bin/omnimvs-26}
RUN=${RUN:-/work/runs/cascade-13}
INIT=${INIT:-/work/runs/c11e14.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --convex-upsampling on --train-only upsampling \
  --init "$INIT" \
  --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.001 --lr-low 0.0002 --epochs 12 --low-lr-epochs 4 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-s104,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-steps 100 --max-val-frames 40 --seed 17 \
  --column-window 160 --photometric on --out "$RUN"
