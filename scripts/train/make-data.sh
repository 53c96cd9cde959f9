#!/usr/bin/env bash
# Generates the synthetic datasets that the bundled models were trained, validated and tested
# on (`omnimvs synth`, deterministic: a frame depends only on its set's kind, difficulty, rig,
# size, seed and index, so any subset of frames can be made again, in any order).
#
#   DATA=path/to/data scripts/train/make-data.sh [GROUP ...]
#
# GROUP is one of (default: train test; the learnt picks' sets are made, with the network's
# answers and the picks' inputs, by scripts/pick/make_data.sh):
#   train   the cascade's training and validation sets: things-s101, house-s102 (frames
#           1..500; 481..500 are the validation frames), things-hard-s103, house-hard-s104,
#           and two hard sets on the real itbt_sample rig's geometry (house-hard-itbtrig-s105,
#           things-hard-itbtrig-s106; needs ITBT=path/to/itbt_sample/config.yaml)
#   test    the held-out test sets, frames 1..20, seeds no training or tuning used:
#           test-things-s7001, test-house-s7002, test-things-hard-s7003, test-house-hard-s7004
#   tiny    the `tiny` network's sets at its input size 192x200
#   random-rigs       training sets on random rigs (`--rig random:SEED`: 2-8 cameras, 0.05-0.6 m,
#                     ds/eucm/ucm/kb4 lenses of 180-250 degrees, tilts, calibration errors),
#                     hard (per-camera gain, gamma, vignetting, blur, noise): RIGS rigs (default
#                     100, rig seeds 1001..), frames 1..6 each, things and house alternately
#   random-rigs-test  held-out random rigs (rig seeds 9101..9108, which no training set uses),
#                     frames 1..5, standard
# Environment: DATA (required), OMNIMVS (the binary; default `omnimvs` on PATH, else
# target/release/omnimvs), ITBT (for the train group). Frames already written are skipped,
# so the script can be started again after an interruption.
set -euo pipefail
: "${DATA:?set DATA to the folder that receives the datasets}"
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${OMNIMVS:-$(command -v omnimvs || echo "$root/target/release/omnimvs")}
mkdir -p "$DATA"
synth() {  # NAME KIND DIFFICULTY FRAMES SEED [more synth options]
  local name=$1 kind=$2 difficulty=$3 frames=$4 seed=$5
  shift 5
  echo "== $name ($kind, $difficulty, frames $frames, seed $seed)" >&2
  "$bin" synth --kind "$kind" --difficulty "$difficulty" --frames "$frames" --seed "$seed" \
    --out "$DATA/$name" "$@"
}
groups=("$@")
[ ${#groups[@]} -gt 0 ] || groups=(train test)
for group in "${groups[@]}"; do
  case $group in
    train)
      : "${ITBT:?set ITBT to the itbt_sample config.yaml (the rig of the itbtrig sets)}"
      synth things-s101 things standard 1..500 101
      synth house-s102 house standard 1..500 102
      synth things-hard-s103 things hard 1..400 103
      synth house-hard-s104 house hard 1..200 104
      synth house-hard-itbtrig-s105 house hard 1..200 105 --rig "$ITBT" --size 766x800
      synth things-hard-itbtrig-s106 things hard 1..200 106 --rig "$ITBT" --size 766x800
      ;;
    random-rigs)
      for i in $(seq 1 "${RIGS:-100}"); do
        kind=things
        [ $((i % 2)) -eq 0 ] && kind=house
        synth "random-rig-$((1000 + i))-$kind" "$kind" hard 1..6 $((20000 + i)) \
          --rig "random:$((1000 + i))"
      done
      ;;
    random-rigs-test)
      for i in $(seq 1 8); do
        kind=things
        [ $((i % 2)) -eq 0 ] && kind=house
        synth "test-random-rig-$((9100 + i))-$kind" "$kind" standard 1..5 $((29100 + i)) \
          --rig "random:$((9100 + i))"
      done
      ;;
    test)
      synth test-things-s7001 things standard 1..20 7001
      synth test-house-s7002 house standard 1..20 7002
      synth test-things-hard-s7003 things hard 1..20 7003
      synth test-house-hard-s7004 house hard 1..20 7004
      ;;
    tiny)
      synth things things standard 1..330 0 --rig sunny --size 192x200
      synth things-s1 things standard 1..300 1 --rig sunny --size 192x200
      synth things-s2 things standard 1..300 2 --rig sunny --size 192x200
      synth house house standard 1..130 0 --rig sunny --size 192x200
      synth house-s1 house standard 1..110 1 --rig sunny --size 192x200
      ;;
    *)
      echo "error: unknown group '$group' (train, test, tiny, random-rigs, random-rigs-test; the picks' sets: scripts/pick/make_data.sh)" >&2
      exit 2
      ;;
  esac
done
