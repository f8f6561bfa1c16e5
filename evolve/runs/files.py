"""Reading and writing the files of runs and sweeps: whole-or-nothing writes with the user's
permissions, and YAML whose errors fit on one line."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import yaml

from tsim.errors import SgrError


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def atomic_write(path: Path, data: bytes) -> None:
    """Write all of `data` or nothing: temporary file, fsync, rename. The temporary file is made
    0600 by `mkstemp`; it gets the umask's permissions before it takes the file's place."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    try:
        os.fchmod(fd, 0o666 & ~_umask())
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
        dir_fd = os.open(path.parent, os.O_RDONLY)  # the rename itself survives a power cut
        try:
            os.fsync(dir_fd)
        finally:
            os.close(dir_fd)
    except BaseException as exc:
        Path(tmp).unlink(missing_ok=True)
        if isinstance(exc, OSError) and exc.filename is None:  # name the file (a full disk)
            raise OSError(exc.errno, exc.strerror, str(path)) from exc
        raise


def yaml_problem(exc: yaml.YAMLError) -> str:
    """One line for a YAML syntax error: what and where (PyYAML's own message spans several)."""
    mark = getattr(exc, "problem_mark", None)
    what = getattr(exc, "problem", None) or str(exc).splitlines()[0]
    return f"{what} at line {mark.line + 1}, column {mark.column + 1}" if mark else what


def read_yaml(path: Path, what: str = "file") -> object:
    """The parsed YAML file; ValueError naming the file when it is missing, not text or not YAML."""
    path = Path(path)
    if not path.is_file():
        raise SgrError(f"{what} not found: {path}")
    try:
        return yaml.safe_load(path.read_text())
    except UnicodeDecodeError:
        raise SgrError(f"{path}: not a text file") from None
    except yaml.YAMLError as exc:
        raise SgrError(f"{path}: not valid YAML: {yaml_problem(exc)}") from None
