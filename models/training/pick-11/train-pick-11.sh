#!/usr/bin/env bash
# pick-11's training (stop 45), the exact commands: does the pick gain from width? pick-6's data
# (1,510 frames, f-*.npz) and settings (Adam one-cycle to 3e-4, sky weight 0.25), 3,000 steps:
#   wide:    from pick-6 grown to width 24 (widen.py: answers as pick-6 at step 0);
#   control: from pick-6 at its own width 16, the same 3,000 steps (what more steps alone give).
# Writes /work/data2/pick11-MODE.pt / .safetensors every 1,000 steps; resumes from its .ckpt.
set -euo pipefail
D=/work/data2
MODE=${1:-wide}
cd "$(dirname "$0")"
PY=${TORCH_PY:-/work/venv-torch211/bin/python}
case "$MODE" in
  wide) W=24; [ -f $D/pick11-init.pt ] || $PY widen.py $D/pick6.pt 24 $D/pick11-init.pt; INIT=$D/pick11-init.pt ;;
  control) W=16; INIT=$D/pick6.pt ;;
  *) echo "usage: $0 wide|control" >&2; exit 2 ;;
esac
cd ../pick-1
PICK_INIT=$INIT PICK_LR=3e-4 SKY_WEIGHT=0.25 $PY train_pick.py ${STEPS:-3000} \
  $D/f-things-s201.npz,$D/f-things-s208.npz,$D/f-things-s211.npz,$D/f-house-s202.npz,$D/f-house-s210.npz,$D/f-house-s213.npz,$D/f-things-hard-s203.npz,$D/f-things-hard-s209.npz,$D/f-things-hard-s212.npz,$D/f-house-hard-s207.npz \
  $D/v-things.npz,$D/v-house.npz,$D/v-hhouse.npz $W $D/pick11-$MODE.pt 2
