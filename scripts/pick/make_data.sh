#!/usr/bin/env bash
# The learnt picks' data: frames the cascade never trained on, the bundled cascade's answers on
# them, and the inputs a pick reads; resumable (a step whose output exists is skipped).
#
#   DATA=DIR scripts/pick/make_data.sh first  [SET ...]
#   DATA=DIR scripts/pick/make_data.sh second [SET ...]
#
# first   for each set: its frames (`omnimvs synth`, deterministic per seed and frame; frames
#         already written are kept), the cascade's answers without a pick (`omnimvs infer
#         --pick off` into DATA/out-SET), then pick_inputs.py's inputs: DATA/f-SET.npz; the
#         validation frames 481..500 likewise into DATA/v-things.npz, v-house.npz, v-hhouse.npz.
#         What a first pick trains on (train.sh's default PREFIX f).
# second  for each set: the first pick's answers on DATA/FROM-SET.npz and the inputs for them
#         (second_inputs.py): DATA/TO-SET.npz, and the validation files VFROM-* -> VTO-*. What
#         a second pick trains on (train.sh PREFIX=s). Needs `first`'s outputs (the spread is
#         read from DATA/out-SET).
# SET     training sets (default: all ten below); the validation sets are always made.
#
# Sets (name: kind, difficulty, frames, seed):
#   things-s201 (things, standard, 1..150, 201)   house-s202 (house, standard, 1..100, 202)
#   things-hard-s203 (things, hard, 1..60, 203)   house-hard-s207 (house, hard, 1..60, 207)
#   things-s208 (things, standard, 1..300, 208)   things-hard-s209 (things, hard, 1..120, 209)
#   house-s210 (house, standard, 1..150, 210)     things-s211 (things, standard, 1..300, 211)
#   things-hard-s212 (things, hard, 1..120, 212)  house-s213 (house, standard, 1..150, 213)
#   validation, frames 481..500: things-s101 (things, standard, 101) -> things,
#   house-s102 (house, standard, 102) -> house, house-hard-s107 (house, hard, 107) -> hhouse
# 1,510 training frames in all (1,050 things, 460 house); pick_inputs.py writes about 7 MB a
# frame, and takes about a second a frame per process.
#
# Environment:
#   DATA     required: the folder of the datasets and of everything this script writes
#   OMNIMVS  the binary (default: `omnimvs` on PATH, else target/release/omnimvs)
#   PY       the Python interpreter (default python3): numpy, scipy, pillow, pyyaml; PyTorch
#            for `second`
#   JOBS     Python processes at a time (default 2)
#   PICK     `second`: the first pick's weights (.safetensors or .pt; default the bundled
#            models/omnimvs-cascade-pick.safetensors)
#   FROM, TO, VFROM, VTO
#            `second`: the prefixes read and written (default f -> s and v -> sv); a third
#            pick's data: FROM=s TO=t VFROM=sv VTO=tv PICK=<the second pick>
#   PICK_DEPTH_RADII, PICK_ZNCC, PICK_RADII
#            the layout of the inputs (pick_inputs.py) and of the first pick's candidates
#            (defaults: the bundled picks')
#
# The bundled picks' data (then scripts/pick/train.sh, whose header has the commands):
#   DATA=$D scripts/pick/make_data.sh first
#   DATA=$D PICK=$D/pick6.safetensors scripts/pick/make_data.sh second
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
usage() { awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0" >&2; exit 2; }
[ $# -ge 1 ] || usage
mode=$1
shift
case $mode in first | second) ;; *) usage ;; esac
if [ -z "${DATA:-}" ]; then
  echo "error: set DATA to the folder of the pick's data" >&2
  usage
fi
bin=${OMNIMVS:-$(command -v omnimvs || echo "$root/target/release/omnimvs")}
PY=${PY:-python3}
JOBS=${JOBS:-2}
mkdir -p "$DATA"
DATA=$(cd "$DATA" && pwd)

# name:kind:difficulty:frames:seed
all_sets="things-s201:things:standard:150:201 house-s202:house:standard:100:202
things-hard-s203:things:hard:60:203 house-hard-s207:house:hard:60:207
things-s208:things:standard:300:208 things-hard-s209:things:hard:120:209
house-s210:house:standard:150:210 things-s211:things:standard:300:211
things-hard-s212:things:hard:120:212 house-s213:house:standard:150:213"
# name:kind:difficulty:seed:short name
val_sets="things-s101:things:standard:101:things house-s102:house:standard:102:house
house-hard-s107:house:hard:107:hhouse"

chosen=()
if [ $# -eq 0 ]; then
  for s in $all_sets; do chosen+=("$s"); done
else
  for want in "$@"; do
    found=""
    for s in $all_sets; do [ "${s%%:*}" = "$want" ] && found=$s; done
    [ -n "$found" ] || { echo "error: unknown set '$want' (see the sets above)" >&2; exit 2; }
    chosen+=("$found")
  done
fi

# At most JOBS Python processes in the background; a failed one stops the script.
pids=()
spawn() {
  "$@" &
  pids+=($!)
  if [ ${#pids[@]} -ge "$JOBS" ]; then
    wait "${pids[0]}"
    pids=("${pids[@]:1}")
  fi
}
finish() {
  for p in ${pids[@]+"${pids[@]}"}; do wait "$p"; done
  pids=()
}

# DATASET A B: the frames, then the cascade's answers in DATA/out-<OUT>.
answers() {
  local ds=$1 a=$2 b=$3 out=$4 kind=$5 difficulty=$6 seed=$7
  if [ ! -f "$DATA/$out/done" ]; then
    "$bin" synth --kind "$kind" --difficulty "$difficulty" --frames "$a..$b" --seed "$seed" \
      --out "$DATA/$ds" > "$DATA/$ds.synth.log" 2>&1
    "$bin" infer --pick off --frames "$a..$b" --out "$DATA/$out" "$DATA/$ds" > "$DATA/$out.log" 2>&1
    touch "$DATA/$out/done"
  fi
}

inputs() {  # DATASET OUTDIR A B DST
  [ -f "$5" ] || "$PY" "$here/pick_inputs.py" "$@"
}

second() {  # SRC DATASET OUTDIR A B DST
  [ -f "$6" ] || "$PY" "$here/second_inputs.py" "$1" "$2" "$3" "$4" "$5" "$PICK" "$6"
}

case $mode in
  first)
    if [ ! -x "$bin" ]; then
      echo "error: no omnimvs binary at '$bin' (build it with 'cargo build --release' or set OMNIMVS)" >&2
      exit 1
    fi
    for s in $val_sets; do
      IFS=: read -r ds kind difficulty seed short <<< "$s"
      answers "$ds" 481 500 "out-val-$ds" "$kind" "$difficulty" "$seed"
      spawn inputs "$DATA/$ds" "$DATA/out-val-$ds" 481 500 "$DATA/v-$short.npz"
    done
    for s in "${chosen[@]}"; do
      IFS=: read -r ds kind difficulty n seed <<< "$s"
      answers "$ds" 1 "$n" "out-$ds" "$kind" "$difficulty" "$seed"
      spawn inputs "$DATA/$ds" "$DATA/out-$ds" 1 "$n" "$DATA/f-$ds.npz"
    done
    finish
    ;;
  second)
    PICK=${PICK:-$root/models/omnimvs-cascade-pick.safetensors}
    FROM=${FROM:-f}; TO=${TO:-s}; VFROM=${VFROM:-v}; VTO=${VTO:-sv}
    [ -f "$PICK" ] || { echo "error: no first pick at $PICK" >&2; exit 1; }
    for s in $val_sets; do
      IFS=: read -r ds kind difficulty seed short <<< "$s"
      src=$DATA/$VFROM-$short.npz
      [ -f "$src" ] || { echo "error: no $src (run 'make_data.sh first' before)" >&2; exit 1; }
      spawn second "$src" "$DATA/$ds" "$DATA/out-val-$ds" 481 500 "$DATA/$VTO-$short.npz"
    done
    for s in "${chosen[@]}"; do
      IFS=: read -r ds kind difficulty n seed <<< "$s"
      src=$DATA/$FROM-$ds.npz
      [ -f "$src" ] || { echo "error: no $src (run 'make_data.sh first' before)" >&2; exit 1; }
      spawn second "$src" "$DATA/$ds" "$DATA/out-$ds" 1 "$n" "$DATA/$TO-$ds.npz"
    done
    finish
    ;;
esac
echo "done: $DATA" >&2
