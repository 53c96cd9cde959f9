#!/usr/bin/env bash
# pick-1's training (stop 39), the exact command: 6,000 steps of 4 bands of 64 x 640, Adam with a
# one-cycle rate to 1e-3, width 16, on 2 threads (PyTorch 2.11 on the CPU; numpy, scipy).
# Writes pick1.pt and pick1.safetensors every 1,000 steps; the last (step 6,000) is models/omnimvs-cascade-pick.safetensors.
set -euo pipefail
D=/work/data2
cd "$(dirname "$0")"
${TORCH_PY:-/work/venv-torch211/bin/python} train_pick.py 6000 \
  $D/f-things-s201.npz,$D/f-house-s202.npz,$D/f-things-hard-s203.npz,$D/f-house-hard-s207.npz \
  $D/v-things.npz,$D/v-house.npz,$D/v-hhouse.npz 16 $D/pick1.pt 2
