#!/usr/bin/env bash
# Cascade run 11: the bundled cascade (cascade-10's epoch 14) trained on with sky weighted 0.1
# in every stage's losses (--sky-weight 0.1, `cascade.sky_loss_weight`). cascade-10 bought its
# large gain on sky-scored figures at the price of near objects on things frames (ground-truth
# index 80-192 answered too far: bias -5.4 -> -6.9 % of N), which the reference's protocol,
# which does not score sky, punishes: things MAE 6.52 -> 7.54. Batch norms frozen as in
# cascade-10, Adam 2e-5 then 1e-5 for the last 5 epochs; otherwise as cascade-10 (same sets,
# losses, augmentation, 160-column window, validation frames), seed 17.
# Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/bin/omnimvs-25}
RUN=${RUN:-/work/runs/cascade-11}
INIT=${INIT:-/work/runs/c10e14.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --init "$INIT" \
  --frozen-norm-stats on \
  --optimizer adam --lr 0.00002 --lr-low 0.00001 --epochs 14 --low-lr-epochs 5 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-s104,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-steps 100 --max-val-frames 40 --seed 17 \
  --column-window 160 --photometric on --out "$RUN"
