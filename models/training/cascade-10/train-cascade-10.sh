#!/usr/bin/env bash
# Cascade run 10: cascade-9's epoch 1 (the bundled model, the photometric cue started at one
# correlation group's scale) trained on at a lower learning rate: cascade-9's best epoch was
# its first, at Adam 1e-4 the rest of the network drifted faster than it learnt to use the cue.
# Batch norms frozen (--frozen-norm-stats on: running statistics used and kept, scale and shift
# still learn): a first try without it lost 0.58 validation MAE in one epoch at Adam 2e-5, 0.52
# of it came back by putting the start's running statistics into that epoch's weights.
# Adam 3e-5, then 1e-5 for the last 4 epochs; the start is validated before any step, selection
# on all 40 validation frames (12 before); otherwise as cascade-9 (same sets, losses,
# augmentation, 160-column window), seed 16.
# Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/bin/omnimvs-24c}
RUN=${RUN:-/work/runs/cascade-10}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 \
  --init /work/runs/cascade-9-epoch1.safetensors \
  --frozen-norm-stats on \
  --optimizer adam --lr 0.00003 --lr-low 0.00001 --epochs 12 --low-lr-epochs 4 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-s104,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-steps 100 --max-val-frames 40 --seed 16 \
  --column-window 160 --photometric on --out "$RUN"
