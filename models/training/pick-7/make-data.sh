#!/usr/bin/env bash
# pick-7's extra data (stop 42): the coarse modes' channels and candidates
# (`crates/omnimvs-net/examples/pick_modes_data.rs`, the bundled cascade without its pick) of every
# frame pick-6 trained on (../pick-1 and ../pick-5 / ../pick-6's make-data.sh made them and the
# other inputs, f-*.npz) and of the validation frames, as m-*.npz (pack_modes.py) under
# /work/data2. Resumable: a packed set is skipped, and a frame already written too.
set -euo pipefail
X=${MODES_DATA:-/work/main/target/release/examples/pick_modes_data}
P=${PY:-/work/venv-np/bin/python3}
S=$(cd "$(dirname "$0")" && pwd)/pack_modes.py
D=/work/data2
K=${K:-3}
cd $D
run() {  # DATASET A B DST
  [ -f $4 ] && return
  $X $1 $2 $3 raw-$(basename $4 .npz) $K > raw-$(basename $4 .npz).log 2>&1
  $P $S raw-$(basename $4 .npz) $2 $3 $K $4 && rm -r raw-$(basename $4 .npz)
}
run /work/data/things-s101 481 500 mv-things.npz
run /work/data/house-s102 481 500 mv-house.npz
run /work/data/house-hard-s107 481 500 mv-hhouse.npz
for s in things-s201:150 house-s202:100 things-hard-s203:60 house-hard-s207:60 things-s208:300 \
  things-hard-s209:120 house-s210:150 things-s211:300 things-hard-s212:120 house-s213:150; do
  IFS=: read -r d n <<< "$s"
  run $D/$d 1 $n m-$d.npz
done
echo DATA-DONE
