#!/usr/bin/env bash
# Cascade run 18: the whole network at a wider refinement spacing, --stage-intervals 2.5,1.5
# (hypotheses 2.5 and 1.5 index units apart, reach +-8.75 and +-3, against 2 and 1 before),
# chosen on the validation frames (things-s101 and house-s102 481..500) with the weights as they
# were: the full-resolution stage's +-2 reach was too narrow for the half stage's answer
# (../cascade-17/val-variants.txt). Starts from cascade-17's best (the coarse stage trained
# alone); every weight trains so the refinement stages learn the new spacing. Same data mix as
# cascade-15 (things weighted), frozen batch-norm statistics, sky weighted 0.1, photometric
# augmentation, 160-column window, 40 validation frames, best epoch by the reference
# protocol's MAE; Adam 2e-5, then 2e-6 for the last third; seed 41.
# Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/main/target/release/omnimvs}
RUN=${RUN:-/work/runs/cascade-18}
INIT=${INIT:-/work/main/models/training/cascade-17/epoch8.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --convex-upsampling half --stage-intervals 2.5,1.5 \
  --init "$INIT" \
  --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.00002 --lr-low 0.000002 --epochs 15 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-val-frames 40 --seed 41 --max-steps 100 \
  --column-window 160 --photometric on --out "$RUN"
