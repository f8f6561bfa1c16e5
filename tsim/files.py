"""Whole-or-nothing file writes, for every file sgr writes (run files, GIFs, plots, reports): a
full disk or a kill leaves the previous version of a file, or none, never a file cut short; and
writes into a folder the user named that follow none of its links. Here, in the lowest layer,
because tsim writes GIFs and the layers above write the rest."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def atomic_write(path: Path, data: bytes, inside: Path | None = None) -> None:
    """Write all of `data` or nothing: temporary file, fsync, rename.

    The temporary file is made 0600 by `mkstemp`; it gets the umask's permissions before it takes
    the file's place. The rename replaces a link at `path`, never its target.

    Args:
        path: the file to write.
        data: its bytes.
        inside: the folder the user named (a run's, a sweep's): no part of `path` below it may be a
            symbolic link (`refuse_links`), so a planted link cannot make sgr write elsewhere.

    Raises:
        SgrError: a link on the way from `inside` (nothing is written).
        OSError: the write failed, naming `path` (the previous version is kept).
    """
    path = Path(path)
    if inside is not None:
        refuse_links(path, inside)
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


def refuse_links(path: Path, inside: Path) -> Path:
    """`path`, checked on its way down from `inside`: no part of it below `inside`, `path` itself
    included, is a symbolic link.

    `inside` is the folder the user named in this command (a run, a sweep, a report's folder); a
    link within it could make sgr write or read elsewhere (a folder is data from a stranger).

    Args:
        path: a file or folder at or below `inside` (it need not exist).
        inside: the folder the user named; it may itself be a link.

    Returns:
        `path`.

    Raises:
        SgrError: naming the first link found.
    """
    from tsim.errors import SgrError

    path, inside = Path(path), Path(inside)
    try:
        parts = path.relative_to(inside).parts
    except ValueError:
        raise ValueError(f"{path} is not inside {inside}") from None
    here = inside
    for part in parts:
        here = here / part
        if here.is_symlink():
            raise SgrError(f"{here}: a symbolic link inside {inside}, which sgr does not follow (a "
                           "folder's links could make it write or read elsewhere): replace it with "
                           "the file or folder itself")
    return path


def make_folder(path: Path, inside: Path) -> Path:
    """Make folder `path` and its missing parents below `inside`, refusing every link on the way
    (`refuse_links`); returns `path`.

    Raises:
        SgrError: a link on the way, or a file where a folder belongs.
    """
    from tsim.errors import SgrError

    path, inside = Path(path), Path(inside)
    refuse_links(path, inside)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except (FileExistsError, NotADirectoryError):
        raise SgrError(f"{path}: not a folder (a file of that name, or a file on its path)") from None
    return refuse_links(path, inside)  # made by someone else between the check and mkdir


def open_no_follow(path: Path, flags: int, inside: Path | None = None) -> int:
    """`os.open(path, flags | O_NOFOLLOW | O_CLOEXEC, 0o666)` (the umask applies): a file descriptor,
    never one of a link's target, checked on its way down from `inside` when given.

    Raises:
        SgrError: `path` (or a folder on its way from `inside`) is a symbolic link.
        OSError: any other failure to open, naming `path`.
    """
    import errno

    from tsim.errors import SgrError

    if inside is not None:
        refuse_links(path.parent, inside)
    try:
        return os.open(path, flags | os.O_NOFOLLOW | os.O_CLOEXEC, 0o666)
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise SgrError(f"{path}: a symbolic link, which sgr does not follow (it could make sgr write "
                           "elsewhere): replace it with the file itself") from None
        raise
