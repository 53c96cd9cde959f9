#!/usr/bin/env bash
# Cascade run 16: cascade-15's epoch 12 (the bundled default since stop 28) trained on with the
# same mix weighted toward things and the same settings, Adam 1e-5 then, for the last third of
# the epochs, 1e-6 (--lr-low's default since commit 83cff27, a tenth of --lr), seed 37.
# Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/main/target/release/omnimvs}
RUN=${RUN:-/work/runs/cascade-16}
INIT=${INIT:-/work/runs/c15e12.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --convex-upsampling half \
  --init "$INIT" \
  --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.00001 --epochs 9 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-val-frames 40 --seed 37 --max-steps 100 \
  --column-window 160 --photometric on --out "$RUN"
