#!/usr/bin/env bash
# Cascade run 20: the coarse stage trained alone on from the bundled cascade-19 epoch 7, whose
# validation reference MAE was still falling at Adam 5e-5 when its rate dropped (epochs 4-7:
# 3.229, 3.234, 3.219, 3.163). Same settings as cascade-19 (refinement spacing 2.5, 1.5, the
# cascade-15 mix, photometric augmentation, sky weighted 0.1, frozen batch-norm statistics),
# 15 epochs of 200 steps, Adam 5e-5 for 12, then 5e-6 for 3; seed 47. Started at the end of stop
# 29 to run over several sessions.
# Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/main/target/release/omnimvs}
RUN=${RUN:-/work/runs/cascade-20}
INIT=${INIT:-/work/main/models/training/cascade-19/epoch7.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --convex-upsampling half --stage-intervals 2.5,1.5 \
  --init "$INIT" \
  --train-only coarse --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.00005 --lr-low 0.000005 --low-lr-epochs 3 --epochs 15 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-val-frames 40 --seed 47 --max-steps 200 \
  --column-window 160 --photometric on --out "$RUN"
