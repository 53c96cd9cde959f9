#!/usr/bin/env bash
# pick-6's training (stop 41), the exact command: pick-5 (../pick-5/train-pick-5.sh, its step-8,000
# weights /work/data2/pick5.pt) trained on with make-data.sh's 570 more frames (seeds 211-213;
# 1,510 frames in all), 3,000 steps of pick-5's settings at a lower peak rate (Adam one-cycle to
# 3e-4: PICK_LR), from pick-5's weights (PICK_INIT). Writes pick6.pt / pick6.safetensors every
# 1,000 steps; resumes from pick6.pt.ckpt when started again.
set -euo pipefail
D=/work/data2
cd "$(dirname "$0")/../pick-1"
PICK_INIT=$D/pick5.pt PICK_LR=3e-4 SKY_WEIGHT=0.25 ${TORCH_PY:-/work/venv-torch211/bin/python} train_pick.py ${STEPS:-3000} \
  $D/f-things-s201.npz,$D/f-things-s208.npz,$D/f-things-s211.npz,$D/f-house-s202.npz,$D/f-house-s210.npz,$D/f-house-s213.npz,$D/f-things-hard-s203.npz,$D/f-things-hard-s209.npz,$D/f-things-hard-s212.npz,$D/f-house-hard-s207.npz \
  $D/v-things.npz,$D/v-house.npz,$D/v-hhouse.npz 16 $D/pick6.pt 2
