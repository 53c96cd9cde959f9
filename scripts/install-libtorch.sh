#!/usr/bin/env bash
# Installs the one dependency of the `libtorch` feature: PyTorch 2.9.0 (the version burn 0.22's
# tch crate is written against) from PyPI, in a virtual environment.
#
#   scripts/install-libtorch.sh [VENV]        # default VENV: $OMNIMVS_TORCH_VENV or .venv-torch
#   TORCH_VERSION=2.11.0 scripts/install-libtorch.sh VENV
#
# A binary must be built against the libtorch it runs with: one built against 2.9 loads 2.11's
# libraries but fails at its first tensor ("Cannot access data pointer of Tensor that doesn't
# have storage"). To run on a machine whose PyTorch is another version (the GPU machines carry
# 2.11), install that version here with TORCH_VERSION; scripts/cargo-libtorch.sh then builds
# against it (tch's version check bypassed: its C++ wrapper compiles against 2.11 unchanged).
#
# The PyPI wheel for Linux x86_64 is the CUDA 12.8 build (about 6 GB with its nvidia-* wheels):
# the same libtorch serves the CPU (`--backend libtorch`) and NVIDIA GPUs
# (`--backend libtorch-cuda`). Then build with scripts/cargo-libtorch.sh.
set -euo pipefail
venv="${1:-${OMNIMVS_TORCH_VENV:-.venv-torch}}"
python="${PYTHON:-python3}"
if [ ! -x "$venv/bin/python" ]; then
    "$python" -m venv "$venv"
fi
"$venv/bin/python" -m pip install --upgrade pip >/dev/null
"$venv/bin/python" -m pip install "torch==${TORCH_VERSION:-2.9.0}"
"$venv/bin/python" - <<'PY'
import os, torch
print(f"torch {torch.__version__} in {os.path.dirname(torch.__file__)}")
print(f"CUDA build {torch.version.cuda}, CUDA available here: {torch.cuda.is_available()}")
PY
echo "installed; build with: OMNIMVS_TORCH_VENV=$venv scripts/cargo-libtorch.sh build --release"
