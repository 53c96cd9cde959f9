#!/usr/bin/env bash
# pick-2's training (stop 39), the exact command (stopped after its step-5,000 weights for the session's time; those are bundled): pick-1's (../pick-1/train-pick-1.sh: the same data,
# 6,000 steps of 4 bands of 64 x 640, Adam one-cycle to 1e-3, width 16, 2 threads) with the sky in
# the loss at weight 0.25 (target index 0), because pick-1 moved sky pixels next to objects onto
# them. Writes pick2.pt / pick2.safetensors every 1,000 steps; the last is
# models/omnimvs-cascade-pick.safetensors.
set -euo pipefail
D=/work/data2
cd "$(dirname "$0")/../pick-1"
SKY_WEIGHT=0.25 ${TORCH_PY:-/work/venv-torch211/bin/python} train_pick.py 6000 \
  $D/f-things-s201.npz,$D/f-house-s202.npz,$D/f-things-hard-s203.npz,$D/f-house-hard-s207.npz \
  $D/v-things.npz,$D/v-house.npz,$D/v-hhouse.npz 16 $D/pick2.pt 2
