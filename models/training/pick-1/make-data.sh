#!/usr/bin/env bash
# pick-1's data (stop 39): fresh frames of seeds no run had used (201-207), the bundled cascade's
# answers on them (`cascade-25` epoch 4, the binary of commit f4287c5), then the pick's inputs
# (pick_inputs.py) for those and for the validation frames 481-500 of things-s101, house-s102 and
# house-hard-s107 (the sets of cascade-45's validation). Writes under /work/data2.
set -euo pipefail
B=${OMNIMVS:-/work/bin/omnimvs-39}
P=${PY:-/work/venv-np/bin/python3}
S=$(cd "$(dirname "$0")" && pwd)/pick_inputs.py
D=/work/data2
mkdir -p $D && cd $D
$B synth --kind things --frames 1..150 --out things-s201 --seed 201
$B synth --kind house --frames 1..100 --out house-s202 --seed 202
$B synth --kind things --difficulty hard --frames 1..60 --out things-hard-s203 --seed 203
$B synth --kind house --difficulty hard --frames 1..60 --out house-hard-s207 --seed 207
for s in things-s201:150 house-s202:100 things-hard-s203:60 house-hard-s207:60; do
  n=${s#*:}; d=${s%:*}
  $B infer --frames 1..$n --out $D/out-$d $D/$d > $D/out-$d.log 2>&1
  $P $S $D/$d $D/out-$d 1 $n $D/f-$d.npz
done
for s in things-s101:things house-s102:house house-hard-s107:hhouse; do
  d=${s%:*}; t=${s#*:}
  $B infer --frames 481..500 --out $D/out-val-$d /work/data/$d > $D/out-val-$d.log 2>&1
  $P $S /work/data/$d $D/out-val-$d 481 500 $D/v-$t.npz
done
