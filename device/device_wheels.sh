#!/usr/bin/env bash
# Downloads, here, the wheels the GPU machine lacks (device/device-requirements.txt: pinned, no
# dependencies resolved there) for CPython 3.12 on x86-64 Linux into device-wheels/ (git-ignored),
# so that they travel with the working tree:  bash device/device_wheels.sh [DIR]
# taichi's C API (taichi/_lib/c_api/, 20 MB packed, never loaded by `import taichi`) is dropped from
# its wheel (device/strip_wheel.py), and every file is checked against device/device-wheels.json, the
# sizes tests/test_tree_size.py counts against the 56 MiB budget.
set -euo pipefail
cd "$(dirname "$0")/.."
DIR=${1:-device-wheels}
PY=${PY:-python3}
mkdir -p "$DIR"
grep -v '^#' device/device-requirements.txt | grep . > "$DIR/requirements.txt"
"$PY" -m pip download -q --no-deps --only-binary :all: --python-version 3.12 --implementation cp \
  --abi cp312 --abi abi3 --abi none --platform manylinux_2_27_x86_64 --platform manylinux2014_x86_64 \
  --platform any -d "$DIR" -r "$DIR/requirements.txt"
n=$(ls "$DIR"/*.whl | wc -l)
want=$(wc -l < "$DIR/requirements.txt")
[ "$n" -eq "$want" ] || { echo "device_wheels: $n wheels in $DIR for $want pins (an old version left there?)" >&2; exit 1; }
"$PY" device/strip_wheel.py "$DIR"/taichi-*.whl --symbols taichi/_lib/c_api/ taichi/examples/
"$PY" - "$DIR" <<'PY'
import json, os, sys
d = sys.argv[1]
want = json.load(open("device/device-wheels.json"))["files"]
have = {f: os.path.getsize(os.path.join(d, f)) for f in sorted(os.listdir(d))}
if have != want:
    diff = sorted(f"{f}: {have.get(f)} bytes, device/device-wheels.json says {want.get(f)}"
                  for f in set(have) | set(want) if have.get(f) != want.get(f))
    sys.exit("device_wheels: " + "; ".join(diff))
print(f"device_wheels: {len(have)} files, {sum(have.values())} bytes ({sum(have.values()) / 2**20:.1f} MiB), as device/device-wheels.json says")
PY
