#!/usr/bin/env bash
# Cascade run 14: the bundled cascade of stop 27 (cascade-13's epoch 12 with its learnt
# upsampling on the half-resolution grid only, `convex_upsampling_full: false`) trained as a
# whole: cascade-13 trained the selectors alone on a trunk that had only ever seen bilinear
# centres; here the half- and full-resolution stages can follow the learnt centres. Batch-norm
# statistics frozen, sky weighted 0.1, Adam 2e-5 then 1e-5 for the last 3 epochs, best epoch by
# the reference protocol's validation MAE; otherwise as cascade-11 and cascade-13 (the six sets
# of ../cascade-8/gen-data.sh, losses, photometric augmentation, 160-column window, the same 40
# validation frames), seed 17.
# Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/bin/omnimvs-27d}
RUN=${RUN:-/work/runs/cascade-14}
INIT=${INIT:-/work/runs/c13e12h.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --convex-upsampling half \
  --init "$INIT" \
  --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.00002 --lr-low 0.00001 --epochs 10 --low-lr-epochs 3 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-s104,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-steps 100 --max-val-frames 40 --seed 17 \
  --column-window 160 --photometric on --out "$RUN"
