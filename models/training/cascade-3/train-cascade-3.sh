#!/usr/bin/env bash
# Cascade run 3: cascade-2's best (epoch 14) fine-tuned with data on the real itbt_sample rig's
# geometry added (hard house and things, 766x800), photometric augmentation on.
# Resumable: rerun this script.
set -euo pipefail
RUN=/work/runs/cascade-3
if [ -f "$RUN/train_config.json" ]; then
  exec /work/bin/omnimvs-train train --resume "$RUN"
fi
exec /work/bin/omnimvs-train train --preset cascade --init /work/runs/init/cascade-2-best.safetensors \
  --optimizer adam --lr 0.0003 --lr-low 0.0001 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-s104,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --epochs 100 --max-steps 100 --max-val-frames 6 --seed 13 \
  --column-window 160 --photometric on --out "$RUN"
