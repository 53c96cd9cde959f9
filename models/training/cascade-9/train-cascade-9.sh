#!/usr/bin/env bash
# Cascade run 9: cascade-8's epoch 1 (cascade-7's best grown into the photometric cue, 100
# steps) with the cue's weights started at the scale of one correlation group (init_cue.py
# with alphas 1.9, 1.0, 0.9 from the cue_scale example on validation frames 481-483 of
# things-s101 and house-s102), then trained as cascade-8 (same sets, losses, Adam 1e-4, then
# 3e-5, photometric augmentation, 160-column window, 12 validation frames, seed 15):
#   python3 init_cue.py /work/runs/init/cascade-8-epoch1.safetensors \
#     /work/runs/init/cascade-9-init.safetensors 1.9 1.0 0.9
# Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/bin/omnimvs-cue2}
RUN=${RUN:-/work/runs/cascade-9}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 \
  --init /work/runs/init/cascade-9-init.safetensors \
  --optimizer adam --lr 0.0001 --lr-low 0.00003 --epochs 30 --low-lr-epochs 8 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-s104,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-steps 100 --max-val-frames 12 --seed 15 \
  --column-window 160 --photometric on --out "$RUN"
