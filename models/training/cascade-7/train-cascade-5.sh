#!/usr/bin/env bash
# Cascade run 5: cascade-4's best (epoch 13) trained on at a lower learning rate (Adam 1e-4, then
# 3e-5 for the last 10 epochs), same six sets, photometric augmentation, 12 validation frames.
# Resumable: rerun this script.
set -euo pipefail
RUN=/work/runs/cascade-5
if [ -f "$RUN/train_config.json" ]; then
  exec /work/bin/omnimvs-train5 train --resume "$RUN"
fi
exec /work/bin/omnimvs-train5 train --preset cascade --context-pairs 2 --stage-gates on \
  --init /work/runs/init/cascade-4-best.safetensors \
  --optimizer adam --lr 0.0001 --lr-low 0.00003 --epochs 30 --low-lr-epochs 10 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-s104,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-steps 100 --max-val-frames 12 --seed 15 \
  --column-window 160 --photometric on --out "$RUN"
