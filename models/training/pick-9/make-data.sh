#!/usr/bin/env bash
# pick-9's data (stop 43): a third pick's, run after pick-6 and pick-8b. pick-8's make-data.sh with
# pick-8b's weights applied to pick-8's data (s-*.npz / sv-*.npz: pick-6's answers and the inputs
# for them): pick-8b's answers and the inputs for them, t-*.npz / tv-*.npz under /work/data2.
# pick-1's 370 training frames only (the disk: no ALL=1). Resumable: a written set is skipped.
set -euo pipefail
FROM=s VFROM=sv TO=t VTO=tv PICKW=pick8b.pt ALL=0 exec "$(dirname "$0")/../pick-8/make-data.sh"
