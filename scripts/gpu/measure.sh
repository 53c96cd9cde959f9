#!/usr/bin/env bash
# The GPU checklist in one script, one stage per call (each stays within a few minutes), for a
# GPU machine that has the NVIDIA driver and PyTorch but no Rust toolchain: build the binaries
# elsewhere (README, "GPU procedure") and copy them, with this repository, to that machine.
#
#   scripts/gpu/measure.sh env       # driver, GPU, PyTorch, Vulkan devices
#   scripts/gpu/measure.sh data      # a synthetic dataset with exact ground truth (full size)
#   scripts/gpu/measure.sh parity    # bundled `tiny` (parity's default: the paper's network
#                                    # family) and a random paper-size network (its cost
#                                    # sharpened x100): every backend against cpu (max index
#                                    # difference < 1e-3)
#   scripts/gpu/measure.sh bench     # paper-preset forward per stage and train step, each
#                                    # backend, then PyTorch on the same GPU
#   scripts/gpu/measure.sh train     # a few hundred paper-preset training steps
#
# Environment (defaults in brackets):
#   OUT            results folder [./gpu-results]; every stage writes its log and JSON there
#   OMNIMVS_WGPU   omnimvs built with --features wgpu [./dist/omnimvs-wgpu]
#   OMNIMVS_TORCH  omnimvs built with --features libtorch [./dist/omnimvs-libtorch]; it is run
#                  with LD_LIBRARY_PATH set to this machine's torch/lib
#   BACKENDS       backends to measure ["wgpu libtorch-cuda:0"]; a backend whose binary is
#                  missing is skipped with a note
#   PRESET         paper | tiny [paper]; tiny with BACKENDS=wgpu-cpu TORCH_DEVICE=cpu is a
#                  CPU-only rehearsal of the whole script
#   TORCH_DEVICE   PyTorch's device for the comparison [cuda]
#   REPEATS        measured forward passes [5];  TRAIN_STEPS: measured train steps [5]
#   TRAIN_BACKEND  the training run's backend [the first of BACKENDS]
#   EPOCHS, STEPS_PER_EPOCH   the training run [10 x 30 = 300 steps]
#   PYTHON         [python3]
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
stage="${1:?usage: scripts/gpu/measure.sh env|data|parity|bench|train}"
out="${OUT:-$PWD/gpu-results}"
wgpu_bin="${OMNIMVS_WGPU:-$PWD/dist/omnimvs-wgpu}"
torch_bin="${OMNIMVS_TORCH:-$PWD/dist/omnimvs-libtorch}"
backends="${BACKENDS:-wgpu libtorch-cuda:0}"
preset="${PRESET:-paper}"
torch_device="${TORCH_DEVICE:-cuda}"
repeats="${REPEATS:-5}"
train_steps="${TRAIN_STEPS:-5}"
python="${PYTHON:-python3}"
data="$out/things"
mkdir -p "$out"
export OMNIMVS_CACHE_DIR="$out/cache"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$out/xdg}"
mkdir -p "$XDG_RUNTIME_DIR"

# torch/lib of this machine's PyTorch, for the libtorch binary.
torch_lib() {
    "$python" -c 'import os, torch; print(os.path.join(os.path.dirname(torch.__file__), "lib"))'
}

# Runs the binary that has backend $1, with the remaining arguments.
omnimvs_for() {
    local backend="$1"
    shift
    case "$backend" in
        libtorch*)
            [ -x "$torch_bin" ] || { echo "skipped: no libtorch binary at $torch_bin"; return 0; }
            LD_LIBRARY_PATH="$(torch_lib)${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}" "$torch_bin" "$@"
            ;;
        *)
            [ -x "$wgpu_bin" ] || { echo "skipped: no wgpu binary at $wgpu_bin"; return 0; }
            "$wgpu_bin" "$@"
            ;;
    esac
}

# Any of the binaries, for the CPU-only commands.
omnimvs_any() {
    if [ -x "$wgpu_bin" ]; then "$wgpu_bin" "$@"; else omnimvs_for libtorch "$@"; fi
}

# Runs a stage's command, its output also going to $out/<name>.log.
logged() {
    local name="$1"
    shift
    echo "== $name: $*"
    "$@" 2>&1 | tee "$out/$name.log"
}

# Runs a command while sampling the GPU's used memory every 100 ms (the same measure for every
# backend and PyTorch, CUDA context included); prints the peak. No-op without nvidia-smi.
with_gpu_memory() {
    local name="$1"
    shift
    if ! command -v nvidia-smi >/dev/null; then
        "$@"
        return
    fi
    nvidia-smi --query-gpu=memory.used --format=csv,noheader,nounits -lms 100 \
        >"$out/$name-gpu-memory.csv" 2>/dev/null &
    local sampler=$!
    local status=0
    "$@" || status=$?
    kill "$sampler" 2>/dev/null || true
    wait "$sampler" 2>/dev/null || true
    echo "peak GPU memory used (nvidia-smi, whole device): $(sort -n "$out/$name-gpu-memory.csv" | tail -1) MiB" \
        | tee -a "$out/$name.log"
    return "$status"
}

# A file-name-safe form of a backend name (libtorch-cuda:0 -> libtorch-cuda-0).
safe() { echo "${1//:/-}"; }

case "$stage" in
env)
    {
        date -u
        uname -a
        nvidia-smi || echo "nvidia-smi: not available"
        "$python" -c 'import torch; print("torch", torch.__version__, "CUDA", torch.version.cuda, "available", torch.cuda.is_available())' \
            || echo "PyTorch: not available"
        ls /usr/share/vulkan/icd.d /etc/vulkan/icd.d 2>/dev/null || echo "no Vulkan ICD files"
        for b in $backends; do
            echo "-- $b"
            omnimvs_for "$b" --version
        done
    } 2>&1 | tee "$out/env.log"
    ;;
data)
    if [ "$preset" = tiny ]; then size=(--size 192x200); else size=(); fi
    logged data omnimvs_any synth --kind things --frames 1..40 --seed 7 --out "$data" "${size[@]}"
    ;;
parity)
    [ -d "$data" ] || { echo "run the data stage first" >&2; exit 1; }
    for b in $backends; do
        s="$(safe "$b")"
        logged "parity-bundled-$s" omnimvs_for "$b" parity "$data" --frame 1 --backends "cpu,$b" \
            --weights tiny --json "$out/parity-bundled-$s.json"
        logged "parity-random-$preset-$s" omnimvs_for "$b" parity "$data" --frame 1 \
            --backends "cpu,$b" --weights random --preset "$preset" --cost-scale 100 \
            --json "$out/parity-random-$preset-$s.json"
    done
    ;;
bench)
    for b in $backends; do
        s="$(safe "$b")"
        with_gpu_memory "bench-$preset-$s" logged "bench-$preset-$s" omnimvs_for "$b" bench \
            --preset "$preset" --backend "$b" --repeats "$repeats" --train-steps "$train_steps" \
            --json "$out/bench-$preset-$s.json"
    done
    with_gpu_memory "bench-$preset-pytorch-$torch_device" logged "bench-$preset-pytorch-$torch_device" \
        "$python" "$root/scripts/net_parity/bench_torch.py" "$preset" "$repeats" \
        --device "$torch_device" --train-steps "$train_steps"
    ;;
train)
    [ -d "$data" ] || { echo "run the data stage first" >&2; exit 1; }
    b="${TRAIN_BACKEND:-${backends%% *}}"
    run="$out/train-$preset-$(safe "$b")"
    rm -rf "$run"
    logged "train-$preset-$(safe "$b")" omnimvs_for "$b" train --data "$data" --preset "$preset" \
        --backend "$b" --out "$run" --epochs "${EPOCHS:-10}" --max-steps "${STEPS_PER_EPOCH:-30}" \
        --val-frames 37..40 --max-val-frames 2
    cat "$run/metrics.jsonl"
    ;;
*)
    echo "unknown stage $stage: env, data, parity, bench or train" >&2
    exit 2
    ;;
esac
