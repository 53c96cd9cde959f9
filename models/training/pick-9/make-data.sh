#!/usr/bin/env bash
# pick-9's data (stop 43): a third pick's, run after pick-6 and pick-8b. pick-8's second_inputs.py
# applied to pick-8's data (s-*.npz: pick-6's answers and the inputs for them) with pick-8b's
# weights (/work/data2/pick8b.pt) gives pick-8b's answers and the inputs for them: t-*.npz (and
# tv-*.npz for validation) under /work/data2, two sets at a time. pick-1's 370 training frames
# only (the disk). Resumable: a written set is skipped.
set -euo pipefail
P=${TORCH_PY:-/work/venv-torch211/bin/python}
S=$(cd "$(dirname "$0")/../pick-8" && pwd)/second_inputs.py
D=/work/data2
run() {  # NAME DATASET OUTDIR A B DST
  [ -f $6 ] || $P $S $D/$1.npz $2 $3 $4 $5 $D/pick8b.pt $6
}
( run sv-things /work/data/things-s101 $D/out-val-things-s101 481 500 $D/tv-things.npz
  run s-things-s201 $D/things-s201 $D/out-things-s201 1 150 $D/t-things-s201.npz
  run s-things-hard-s203 $D/things-hard-s203 $D/out-things-hard-s203 1 60 $D/t-things-hard-s203.npz ) &
( run sv-house /work/data/house-s102 $D/out-val-house-s102 481 500 $D/tv-house.npz
  run sv-hhouse /work/data/house-hard-s107 $D/out-val-house-hard-s107 481 500 $D/tv-hhouse.npz
  run s-house-s202 $D/house-s202 $D/out-house-s202 1 100 $D/t-house-s202.npz
  run s-house-hard-s207 $D/house-hard-s207 $D/out-house-hard-s207 1 60 $D/t-house-hard-s207.npz ) &
wait
echo DATA-DONE
