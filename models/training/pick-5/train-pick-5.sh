#!/usr/bin/env bash
# pick-5's training (stop 41), the exact command: pick-2's layout, loss and sky weight
# (../pick-2/train-pick-2.sh; the bundled pick's cost at inference) on more than twice its frames:
# pick-1's 370 (seeds 201-203, 207) and make-data.sh's 570 (seeds 208-210), 940 in all, 8,000 steps
# of 4 bands of 64 x 640, Adam one-cycle to 1e-3 run to its end (pick-2 stopped at step 5,000 of
# 6,000), width 16, 2 threads. Writes pick5.pt / pick5.safetensors every 1,000 steps; resumes
# from pick5.pt.ckpt when started again.
set -euo pipefail
D=/work/data2
cd "$(dirname "$0")/../pick-1"
SKY_WEIGHT=0.25 ${TORCH_PY:-/work/venv-torch211/bin/python} train_pick.py ${STEPS:-8000} \
  $D/f-things-s201.npz,$D/f-things-s208.npz,$D/f-house-s202.npz,$D/f-house-s210.npz,$D/f-things-hard-s203.npz,$D/f-things-hard-s209.npz,$D/f-house-hard-s207.npz \
  $D/v-things.npz,$D/v-house.npz,$D/v-hhouse.npz 16 $D/pick5.pt 2
