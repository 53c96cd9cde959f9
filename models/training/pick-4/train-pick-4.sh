#!/usr/bin/env bash
# pick-4's training (stop 40), the exact command: pick-2's inputs (../pick-1's f-*.npz: 29 channels,
# gray values at the answer and its 5 x 5 extremes) with pick-3's eleven candidates (radii 1, 2, 4,
# 7, 12), so that it costs what pick-2 costs; otherwise pick-2's run (4 bands of 64 x 640 a step,
# Adam one-cycle to 1e-3, width 16, 2 threads, sky in the loss at weight 0.25), 6,000 steps.
# Writes pick4.pt / pick4.safetensors every 1,000 steps.
set -euo pipefail
D=/work/data2
cd "$(dirname "$0")/../pick-1"
export PICK_RADII=1,2,4,7,12 PICK_DEPTH_RADII=2 PICK_ZNCC=0 SKY_WEIGHT=0.25
${TORCH_PY:-/work/venv-torch211/bin/python} train_pick.py ${STEPS:-6000} \
  $D/f-things-s201.npz,$D/f-house-s202.npz,$D/f-things-hard-s203.npz,$D/f-house-hard-s207.npz \
  $D/v-things.npz,$D/v-house.npz,$D/v-hhouse.npz 16 $D/pick4.pt 2
