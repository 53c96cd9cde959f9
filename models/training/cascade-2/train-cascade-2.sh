#!/usr/bin/env bash
# Cascade run 2: fine-tuning of cascade-1's best weights (epoch 22, validation MAE 11.27) on the
# standard sets plus the --difficulty hard sets, with the per-camera photometric augmentation,
# at a lower learning rate (fresh Adam). Resumable: rerun this script.
set -euo pipefail
RUN=/work/runs/cascade-2
if [ -f "$RUN/train_config.json" ]; then
  exec /work/bin/omnimvs-train train --resume "$RUN"
fi
exec /work/bin/omnimvs-train train --preset cascade --init /work/runs/init/cascade-1-e22.safetensors \
  --optimizer adam --lr 0.0003 --lr-low 0.0001 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-s104 \
  --val-frames 481..500 --epochs 100 --max-steps 100 --max-val-frames 6 --seed 12 \
  --column-window 160 --photometric on --out "$RUN"
