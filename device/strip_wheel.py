"""Drop folders a wheel carries but sgr never loads, so that the device wheels fit the 64 MiB a
device machine receives (tests/test_tree_size.py): rewrites WHEEL in place without the entries under
each PREFIX and without their RECORD lines; the other entries keep their bytes, names, dates and
order, so the result is the same file every time. A wheel with nothing to drop is left untouched.

    python device/strip_wheel.py device-wheels/taichi-1.7.4-*.whl taichi/_lib/c_api/

taichi/_lib/c_api/ (55 MB unpacked, 20 MB packed) is taichi's C API for ahead-of-time modules:
`import taichi` loads taichi/_lib/core/ and the LLVM runtimes of taichi/_lib/runtime/ only.
taichi/examples/ is never imported. `--symbols` strips the symbol tables of the wheel's shared
libraries (taichi_python: 34.4 -> 29.8 MB packed; its dynamic symbols, which the loader and
Python's import use, stay): issue 34's 56 MiB budget.
"""

from __future__ import annotations

import base64
import hashlib
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path


def strip(wheel: Path, prefixes: list[str], symbols: bool = False) -> int:
    """Remove the entries under `prefixes` from `wheel`, and with `symbols` the symbol tables of its
    shared libraries (`strip --strip-unneeded`: what a dynamic loader needs stays; their RECORD
    lines get the new hash and size); returns how many entries were removed or changed."""
    with zipfile.ZipFile(wheel) as src:
        infos = src.infolist()
        drop = [i for i in infos if i.filename.startswith(tuple(prefixes))]
        changed = {}
        if symbols:
            for i in infos:
                if i.filename.endswith(".so") and i not in drop:
                    data = src.read(i)
                    new = _strip_symbols(data)
                    if new != data:
                        changed[i.filename] = new
        if not drop and not changed:
            return 0
        tmp = wheel.with_suffix(".tmp")
        with zipfile.ZipFile(tmp, "w") as dst:
            for info in infos:
                if info in drop:
                    continue
                data = changed.get(info.filename) or src.read(info)
                if info.filename.endswith(".dist-info/RECORD"):
                    lines = data.decode().splitlines(keepends=True)
                    data = "".join(_record_line(ln, changed) for ln in lines
                                   if not ln.startswith(tuple(prefixes))).encode()
                dst.writestr(info, data, compress_type=info.compress_type, compresslevel=9)
    tmp.replace(wheel)
    return len(drop) + len(changed)


def _strip_symbols(data: bytes) -> bytes:
    """The shared library `data` without its symbol tables and debug sections (binutils' strip)."""
    with tempfile.TemporaryDirectory() as d:
        f = Path(d) / "lib.so"
        f.write_bytes(data)
        subprocess.run(["strip", "--strip-unneeded", str(f)], check=True)
        return f.read_bytes()


def _record_line(line: str, changed: dict[str, bytes]) -> str:
    """A RECORD line (path,sha256=...,size), with the new hash and size if its file changed."""
    path = line.split(",", 1)[0]
    if path not in changed:
        return line
    digest = base64.urlsafe_b64encode(hashlib.sha256(changed[path]).digest()).rstrip(b"=").decode()
    return f"{path},sha256={digest},{len(changed[path])}\n"


def main() -> int:
    args = sys.argv[1:]
    symbols = "--symbols" in args
    args = [a for a in args if a != "--symbols"]
    if len(args) < 1 or (len(args) < 2 and not symbols):
        print("usage: strip_wheel.py WHEEL [--symbols] PREFIX...", file=sys.stderr)
        return 2
    wheel = Path(args[0])
    if not zipfile.is_zipfile(wheel):
        print(f"strip_wheel: {wheel}: not a wheel", file=sys.stderr)
        return 1
    before = wheel.stat().st_size
    n = strip(wheel, args[1:], symbols)
    print(f"strip_wheel: {wheel.name}: {n} entries dropped or stripped, "
          f"{before} -> {wheel.stat().st_size} bytes")
    return 0


if __name__ == "__main__":
    sys.exit(main())
