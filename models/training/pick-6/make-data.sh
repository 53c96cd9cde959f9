#!/usr/bin/env bash
# pick-6's extra data (stop 41): pick-5's recipe (../pick-5/make-data.sh: fresh frames, the bundled
# cascade's answers without its pick, pick-2's inputs, under /work/data2) on three more seeds no run
# had used: 211 (300 things frames), 212 (120 hard things frames), 213 (150 house frames).
set -euo pipefail
SETS="things:things-s211:300:211: things:things-hard-s212:120:212:hard house:house-s213:150:213:" \
  exec "$(dirname "$0")/../pick-5/make-data.sh"
