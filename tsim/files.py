"""Whole-or-nothing file writes, for every file sgr writes (run files, GIFs, plots, reports): a
full disk or a kill leaves the previous version of a file, or none, never a file cut short. Here, in
the lowest layer, because tsim writes GIFs and the layers above write the rest."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path


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
