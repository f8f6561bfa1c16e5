"""Drop folders a wheel carries but sgr never loads, so that the device wheels fit the 64 MiB a
device machine receives (tests/test_tree_size.py): rewrites WHEEL in place without the entries under
each PREFIX and without their RECORD lines; the other entries keep their bytes, names, dates and
order, so the result is the same file every time. A wheel with nothing to drop is left untouched.

    python bench/strip_wheel.py device-wheels/taichi-1.7.4-*.whl taichi/_lib/c_api/

taichi/_lib/c_api/ (55 MB unpacked, 20 MB packed) is taichi's C API for ahead-of-time modules:
`import taichi` loads taichi/_lib/core/ and the LLVM runtimes of taichi/_lib/runtime/ only.
"""

from __future__ import annotations

import sys
import zipfile
from pathlib import Path


def strip(wheel: Path, prefixes: list[str]) -> int:
    """Remove the entries under `prefixes` from `wheel`; returns how many were removed."""
    with zipfile.ZipFile(wheel) as src:
        infos = src.infolist()
        drop = [i for i in infos if i.filename.startswith(tuple(prefixes))]
        if not drop:
            return 0
        tmp = wheel.with_suffix(".tmp")
        with zipfile.ZipFile(tmp, "w") as dst:
            for info in infos:
                if info in drop:
                    continue
                data = src.read(info)
                if info.filename.endswith(".dist-info/RECORD"):
                    lines = data.decode().splitlines(keepends=True)
                    data = "".join(ln for ln in lines if not ln.startswith(tuple(prefixes))).encode()
                dst.writestr(info, data, compress_type=info.compress_type, compresslevel=9)
    tmp.replace(wheel)
    return len(drop)


def main() -> int:
    if len(sys.argv) < 3:
        print("usage: strip_wheel.py WHEEL PREFIX...", file=sys.stderr)
        return 2
    wheel = Path(sys.argv[1])
    if not zipfile.is_zipfile(wheel):
        print(f"strip_wheel: {wheel}: not a wheel", file=sys.stderr)
        return 1
    before = wheel.stat().st_size
    n = strip(wheel, sys.argv[2:])
    print(f"strip_wheel: {wheel.name}: {n} entries dropped, {before} -> {wheel.stat().st_size} bytes")
    return 0


if __name__ == "__main__":
    sys.exit(main())
