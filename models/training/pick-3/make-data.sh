#!/usr/bin/env bash
# pick-3's data (stop 40): pick-1's frames and the bundled cascade's answers on them (../pick-1/make-data.sh
# made both, under /work/data2), with pick-3's wider inputs (PICK_DEPTH_RADII=2,12 PICK_ZNCC=5 of
# ../pick-1/pick_inputs.py): g-*.npz beside pick-1's f-*.npz and v-*.npz. Two sets at a time.
set -euo pipefail
P=${PY:-/work/venv-np/bin/python3}
S=$(cd "$(dirname "$0")/../pick-1" && pwd)/pick_inputs.py
D=/work/data2
export PICK_DEPTH_RADII=2,12 PICK_ZNCC=5
run() { "$P" "$S" "$@"; }
run $D/things-s201 $D/out-things-s201 1 150 $D/g-things-s201.npz &
run $D/house-s202 $D/out-house-s202 1 100 $D/g-house-s202.npz
run $D/things-hard-s203 $D/out-things-hard-s203 1 60 $D/g-things-hard-s203.npz
wait
run $D/house-hard-s207 $D/out-house-hard-s207 1 60 $D/g-house-hard-s207.npz &
run /work/data/things-s101 $D/out-val-things-s101 481 500 $D/gv-things.npz
run /work/data/house-s102 $D/out-val-house-s102 481 500 $D/gv-house.npz
wait
run /work/data/house-hard-s107 $D/out-val-house-hard-s107 481 500 $D/gv-hhouse.npz
