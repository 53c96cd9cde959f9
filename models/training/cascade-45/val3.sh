#!/usr/bin/env bash
# val3.sh WEIGHTS TAG (stop 37): frames 481..500 of the three validation sets of cascade-45 (things-s101, house-s102,
# house-hard-s107) inferred by WEIGHTS and scored at 160x640 (omni_np eval-at, reference rules). Writes under ${EXP:-/work/exp}.
W=$1; TAG=$2
for s in things-s101 house-s102 house-hard-s107; do
  O=${EXP:-/work/exp}/v-$TAG-$s; rm -rf $O
  ${OMNIMVS:-/work/bin/omnimvs} infer --weights $W --frames 481..500 --out $O /work/data/$s > $O.log 2>&1 || { echo "$TAG $s FAILED"; tail -2 $O.log; continue; }
  echo "$TAG $s $(/work/venv-np/bin/python3 /work/shared/tools/omni_np.py eval-at /work/data/$s $O 481 500 160 640 | tail -1)"
done
