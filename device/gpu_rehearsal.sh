#!/usr/bin/env bash
# Rehearses device/gpu_check.sh here, on the CPU, as the GPU machine would run it: a fresh Python
# 3.12 environment holding only the device image's packages (no taichi, neat-python, gymnasium),
# the carried wheels installed offline, the GPU arch replaced by the CPU and small sizes.
#   bash device/gpu_rehearsal.sh          (~5 min on 2 cores; downloads the image's packages once)
# Not in the test suite: building the environment downloads ~150 MB and takes minutes, which the
# suite's 10-minute budget on CI's 2 cores cannot spare. Its last run is recorded in
# docs/BENCHMARKS.md ("Running on a GPU").
set -euo pipefail
cd "$(dirname "$0")/.."
# the first Python 3.12 that runs (pyenv's shim is on the PATH but fails where 3.12 is not selected)
if [ -z "${PY312:-}" ]; then
  for c in $(command -v python3.12) "$(pyenv root 2>/dev/null || echo ~/.pyenv)"/versions/3.12*/bin/python3.12; do
    if [ -x "$c" ] && "$c" -c 'import sys; assert sys.version_info[:2] == (3, 12)' 2>/dev/null; then PY312=$c; break; fi
  done
fi
[ -x "${PY312:-}" ] || { echo "gpu_rehearsal: no Python 3.12 (pyenv install 3.12)"; exit 1; }
ENV=${ENV_DIR:-${TMPDIR:-/tmp}/sgr-device-env}
if [ ! -x "$ENV/bin/python" ]; then
  "$PY312" -m venv "$ENV"
  # the device image's packages that sgr may touch (its full list: .library/device/KINDS.md)
  "$ENV/bin/pip" install -q numpy scipy matplotlib pillow pyyaml imageio rich tqdm pytest
fi
[ -d device-wheels ] || PY="$ENV/bin/python" bash device/device_wheels.sh
if "$ENV/bin/python" -c "import taichi" 2>/dev/null; then echo "gpu_rehearsal: $ENV has taichi: not the device image"; exit 1; fi
OUT=${OUT:-gpu-rehearsal} PY="$ENV/bin/python" PIP_NO_INDEX=1 SGR_ARCH_GPU=cpu SIZES=${SIZES:-64} \
  ROBOTS=${ROBOTS:-2} STEPS=${STEPS:-20} DATA=${DATA:-tests/data/returns} bash device/gpu_check.sh
