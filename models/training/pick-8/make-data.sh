#!/usr/bin/env bash
# pick-8's data (stop 42): second_inputs.py over pick-1's 370 training frames and the 60
# validation frames (ALL=1: and pick-6's other 1,140), bundled pick-6 (/work/data2/pick6.pt) first;
# s-*.npz / sv-*.npz under /work/data2, two sets at a time. Resumable: a written set is skipped.
# Stop 43 (pick-9's data, ../pick-9/make-data.sh): FROM / VFROM name the sets read (default f / v),
# TO / VTO the sets written (default s / sv), PICKW the pick applied (default pick6.pt).
set -euo pipefail
P=${TORCH_PY:-/work/venv-torch211/bin/python}
S=$(cd "$(dirname "$0")" && pwd)/second_inputs.py
D=/work/data2
FROM=${FROM:-f}; VFROM=${VFROM:-v}; TO=${TO:-s}; VTO=${VTO:-sv}; PICKW=${PICKW:-pick6.pt}
run() {  # NAME DATASET OUTDIR A B DST   (NAME and DST without their set prefix)
  case $1 in v-*) src=$VFROM-${1#v-}; dst=$VTO-${6#sv-} ;; *) src=$FROM-$1; dst=$TO-$6 ;; esac
  [ -f $D/$dst ] || $P $S $D/$src.npz $2 $3 $4 $5 $D/$PICKW $D/$dst
}
( run v-things /work/data/things-s101 $D/out-val-things-s101 481 500 sv-things.npz
  run things-s201 $D/things-s201 $D/out-things-s201 1 150 things-s201.npz
  run things-hard-s203 $D/things-hard-s203 $D/out-things-hard-s203 1 60 things-hard-s203.npz ) &
( run v-house /work/data/house-s102 $D/out-val-house-s102 481 500 sv-house.npz
  run v-hhouse /work/data/house-hard-s107 $D/out-val-house-hard-s107 481 500 sv-hhouse.npz
  run house-s202 $D/house-s202 $D/out-house-s202 1 100 house-s202.npz
  run house-hard-s207 $D/house-hard-s207 $D/out-house-hard-s207 1 60 house-hard-s207.npz ) &
wait
# Stop 42's second phase: pick-5 and pick-6's frames (seeds 208-213), so the second pick trains on
# the 1,510 frames the first did.
if [ "${ALL:-0}" = 1 ]; then
  ( for s in things-s208:300 house-s210:150 things-hard-s212:120; do
      IFS=: read -r n c <<< "$s"; run $n $D/$n $D/out-$n 1 $c $n.npz; done ) &
  ( for s in things-s211:300 house-s213:150 things-hard-s209:120; do
      IFS=: read -r n c <<< "$s"; run $n $D/$n $D/out-$n 1 $c $n.npz; done ) &
  wait
fi
echo DATA-DONE
