#!/usr/bin/env bash
# How good the coarse stage has to be (stop 34): the bundled network run by `--example
# cascade_seeded` with its half stage centred on seeds from coarse_seeds.py (the truth at the
# coarse grid; the network's own coarse answer with its misses over T replaced by the truth).
# Needs a `cascade_dump` of the bundled network's things and house validation frames 481-490.
# Usage: coarse_bound.sh THINGS_DUMP HOUSE_DUMP WORK_DIR   (output: coarse_bound.txt here)
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/../../.." && pwd)
PY=${PY:-/work/venv-np/bin/python3}
W=$ROOT/models/training/cascade-25/epoch4.safetensors
EX=$ROOT/target/release/examples/cascade_seeded
mkdir -p "$3"
run() {  # DATASET DUMP NAME [T [P]]
  "$PY" "$HERE/coarse_seeds.py" "$1" "$2" 481 490 "$3/$4" "${@:5}"
  echo "== $1, half stage centred on $4 (the first line: the network as it is)"
  "$EX" "$W" "$1" "$3/$4" 481 490 2>/dev/null | grep -A3 'final answer' | sed -n 2,3p
}
{
  run /work/data/things-s101 "$1" "$3" truth
  run /work/data/things-s101 "$1" "$3" fix5 5
  run /work/data/things-s101 "$1" "$3" fix5-half 5 0.5
  run /work/data/things-s101 "$1" "$3" fix5-quarter 5 0.25
  run /work/data/things-s101 "$1" "$3" fix10 10
  run /work/data/things-s101 "$1" "$3" fix20 20
  run /work/data/things-s101 "$1" "$3" fix20-half 20 0.5
  run /work/data/house-s102 "$2" "$3" house-truth
  run /work/data/house-s102 "$2" "$3" house-fix20 20
} 2>&1 | tee "$HERE/coarse_bound.txt"
