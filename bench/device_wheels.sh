#!/usr/bin/env bash
# Downloads, here, the wheels the GPU machine lacks (bench/device-requirements.txt: pinned, no
# dependencies resolved there) for CPython 3.12 on x86-64 Linux into device-wheels/ (git-ignored),
# so that they travel with the working tree:  bash bench/device_wheels.sh [DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
DIR=${1:-device-wheels}
PY=${PY:-python3}
mkdir -p "$DIR"
grep -v '^#' bench/device-requirements.txt | grep . > "$DIR/requirements.txt"
"$PY" -m pip download -q --no-deps --only-binary :all: --python-version 3.12 --implementation cp \
  --abi cp312 --abi abi3 --abi none --platform manylinux_2_27_x86_64 --platform manylinux2014_x86_64 \
  --platform any -d "$DIR" -r "$DIR/requirements.txt"
n=$(ls "$DIR"/*.whl | wc -l)
want=$(wc -l < "$DIR/requirements.txt")
[ "$n" -eq "$want" ] || { echo "device_wheels: $n wheels in $DIR for $want pins (an old version left there?)" >&2; exit 1; }
du -sh "$DIR"
