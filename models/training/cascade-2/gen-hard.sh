#!/usr/bin/env bash
# Hard training data (--difficulty hard: harder textures, thin/concave shapes, falloff lights,
# per-camera exposure/gamma/vignetting/blur/noise) and hard test sets (seeds used nowhere else).
# Resumable: synth skips frames already written.
set -euo pipefail
B=/work/bin/omnimvs
cd /work/data
$B synth --kind things --difficulty hard --frames 1..20 --out test-things-hard-s7003 --seed 7003
$B synth --kind house  --difficulty hard --frames 1..20 --out test-house-hard-s7004  --seed 7004
$B synth --kind things --difficulty hard --frames 1..400 --out things-hard-s103 --seed 103 &
$B synth --kind house  --difficulty hard --frames 1..200 --out house-hard-s104  --seed 104
wait
echo GEN-HARD-DONE
