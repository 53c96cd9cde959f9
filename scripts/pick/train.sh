#!/usr/bin/env bash
# Trains a learnt pick with train_pick.py on data that make_data.sh wrote; resumable.
#
#   DATA=DIR OUT=FILE.pt scripts/pick/train.sh [--option VALUE ...]
#
# Options (flag or environment variable; a flag wins):
#   --data DIR       DATA     required: the folder of the pick's data (make_data.sh's DATA)
#   --out FILE.pt    OUT      required: the weights written every 1,000 steps: FILE.pt (PyTorch),
#                             FILE.safetensors (for `omnimvs infer --pick`), FILE.pt.ckpt (to
#                             resume: run the same command again after an interruption)
#   --steps N        STEPS    steps of the one-cycle schedule (default 3000)
#   --lr X           LR       its peak rate (default 1e-3)
#   --init FILE      INIT     start from a pick's weights (.pt or .safetensors; default: a
#                             fresh pick)
#   --width N        WIDTH    the U-Net's width (default 16)
#   --sets "A B ..." SETS     training sets, in order (the order decides which frames a step
#                             draws); default: the ten sets of the bundled picks, as below
#   --prefix P       PREFIX   training files are DATA/P-SET.npz (default f: the network's
#                             answers; s: the first pick's, for a second pick; t: a third's)
#   --vprefix P      VPREFIX  validation files DATA/P-things.npz, P-house.npz, P-hhouse.npz
#                             (default: v for prefix f, sv for s, tv for t)
#   --sky-weight W   SKY_WEIGHT  weight of sky pixels in the loss (default 0.25)
#   --threads N      THREADS  PyTorch's CPU threads (default 2)
#   --python PY      PY       the Python interpreter, with PyTorch, numpy and scipy (default python3)
# train_pick.py's other options pass through the environment: PICK_RADII, PICK_DEPTH_RADII,
# PICK_ZNCC, PICK_MODES, PICK_NEW_BIAS, PICK_NEW_INPUT_SCALE, PICK_TEACHER, PICK_TEACHER_WIDTH,
# PICK_DISTILL.
#
# The bundled picks, from the data of `scripts/pick/make_data.sh first` and `... second`
# (2 threads on a CPU; about 50, 18, 24 and 25 minutes on 2 cores):
#
#   # models/omnimvs-cascade-pick.safetensors (pick-6): pick-5, 8,000 steps on 940 frames ...
#   DATA=$D OUT=$D/pick5.pt STEPS=8000 LR=1e-3 \
#     SETS="things-s201 things-s208 house-s202 house-s210 things-hard-s203 things-hard-s209 house-hard-s207" \
#     scripts/pick/train.sh
#   # ... then 3,000 more on all 1,510 at a peak of 3e-4: $D/pick6.safetensors
#   DATA=$D OUT=$D/pick6.pt STEPS=3000 LR=3e-4 INIT=$D/pick5.pt scripts/pick/train.sh
#
#   # models/omnimvs-cascade-pick2.safetensors (pick-8b), on the first pick's answers
#   # (`PICK=$D/pick6.safetensors scripts/pick/make_data.sh second`, or the bundled pick-6):
#   # pick-8, 3,000 steps from pick-6's weights on 970 frames ...
#   DATA=$D OUT=$D/pick8.pt PREFIX=s STEPS=3000 LR=3e-4 INIT=$D/pick6.pt \
#     SETS="things-s201 house-s202 things-hard-s203 house-hard-s207 things-s208 things-s211" \
#     scripts/pick/train.sh
#   # ... then 3,000 more on all 1,510 at a peak of 2e-4: $D/pick8b.safetensors
#   DATA=$D OUT=$D/pick8b.pt PREFIX=s STEPS=3000 LR=2e-4 INIT=$D/pick8.pt \
#     SETS="things-s201 house-s202 things-hard-s203 house-hard-s207 things-s208 things-s211 house-s210 house-s213 things-hard-s209 things-hard-s212" \
#     scripts/pick/train.sh
#
# Every run seeds its random draws with 0, so these repeat the recorded runs' draws; PyTorch's
# arithmetic may differ in the last bits between versions and thread counts. The order of
# pick-8's six sets was not recorded; the order above is the one pick-8b's list begins with.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
usage() { awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0" >&2; exit 2; }
while [ $# -gt 0 ]; do
  [ $# -ge 2 ] || usage
  case $1 in
    --data) DATA=$2 ;;
    --out) OUT=$2 ;;
    --steps) STEPS=$2 ;;
    --lr) LR=$2 ;;
    --init) INIT=$2 ;;
    --width) WIDTH=$2 ;;
    --sets) SETS=$2 ;;
    --prefix) PREFIX=$2 ;;
    --vprefix) VPREFIX=$2 ;;
    --sky-weight) SKY_WEIGHT=$2 ;;
    --threads) THREADS=$2 ;;
    --python) PY=$2 ;;
    *) echo "error: unknown option '$1'" >&2; usage ;;
  esac
  shift 2
done
if [ -z "${DATA:-}" ] || [ -z "${OUT:-}" ]; then
  echo "error: set DATA (the pick's data folder) and OUT (the weights, FILE.pt)" >&2
  usage
fi
case $OUT in
  *.pt) ;;
  *) echo "error: OUT must end in .pt (FILE.safetensors is written beside it)" >&2; exit 2 ;;
esac
STEPS=${STEPS:-3000}
LR=${LR:-1e-3}
WIDTH=${WIDTH:-16}
PREFIX=${PREFIX:-f}
case $PREFIX in
  f) VPREFIX=${VPREFIX:-v} ;;
  *) VPREFIX=${VPREFIX:-${PREFIX}v} ;;
esac
SETS=${SETS:-"things-s201 things-s208 things-s211 house-s202 house-s210 house-s213 things-hard-s203 things-hard-s209 things-hard-s212 house-hard-s207"}
THREADS=${THREADS:-2}
PY=${PY:-python3}
train=""
for s in $SETS; do
  f=$DATA/$PREFIX-$s.npz
  [ -f "$f" ] || { echo "error: no $f (scripts/pick/make_data.sh writes it)" >&2; exit 1; }
  train+="$f,"
done
val=""
for s in things house hhouse; do
  f=$DATA/$VPREFIX-$s.npz
  [ -f "$f" ] || { echo "error: no $f (scripts/pick/make_data.sh writes it)" >&2; exit 1; }
  val+="$f,"
done
if [ -n "${INIT:-}" ]; then
  [ -f "$INIT" ] || { echo "error: no initial weights at $INIT" >&2; exit 1; }
  export PICK_INIT=$INIT
else
  unset PICK_INIT
fi
export PICK_LR=$LR SKY_WEIGHT=${SKY_WEIGHT:-0.25}
mkdir -p "$(dirname "$OUT")"
echo "train_pick.py $STEPS (${SETS// /, }) width $WIDTH, peak rate $LR, init ${INIT:-none} -> $OUT" >&2
exec "$PY" "$here/train_pick.py" "$STEPS" "${train%,}" "${val%,}" "$WIDTH" "$OUT" "$THREADS"
