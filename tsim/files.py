"""Whole-or-nothing file writes, for every file sgr writes (run files, GIFs, plots, reports): a
full disk or a kill leaves the previous version of a file, or none, never a file cut short; writes
into a folder the user named that follow none of its links; and the one reader of the files of a
folder sgr did not make (a run, a sweep, a reference set): regular files only, never through a link
inside the folder, never more than a cap. Here, in the lowest layer, because tsim writes GIFs and
the layers above write and read the rest."""

from __future__ import annotations

import errno
import os
import stat
import tempfile
import zlib
from pathlib import Path

from tsim.errors import SgrError, printable

MiB = 1 << 20
CONFIG_CAP = 16 * MiB  # a YAML, INI or JSON file of settings (config.yaml, neat.ini, task.json, ...)
RECORD_CAP = 256 * MiB  # a record that grows with a run: champion.json, elites.json, generations.csv
CHECKPOINT_CAP = 1024 * MiB  # a gzipped checkpoint, and again once uncompressed (the largest seen: ~53 MB)
_KINDS = {stat.S_IFIFO: "a FIFO", stat.S_IFCHR: "a character device", stat.S_IFBLK: "a block device",
          stat.S_IFSOCK: "a socket", stat.S_IFDIR: "a folder"}


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
            raise SgrError(f"{here}: a symbolic link, which sgr does not follow inside a folder ({inside}: "
                           "its links could make sgr write or read elsewhere): replace it with the file "
                           "or folder itself")
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


def _open_regular(path: Path, follow: bool) -> int:
    """A read-only descriptor of `path`, SgrError naming it unless it is a regular file (and, unless
    `follow`, not a symbolic link). Never blocks: O_NONBLOCK makes opening a FIFO return at once."""
    flags = os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC | (0 if follow else os.O_NOFOLLOW)
    try:
        fd = os.open(path, flags)
    except OSError as exc:
        if exc.errno == errno.ELOOP and not follow and path.is_symlink():
            raise SgrError(f"{printable(path)}: a symbolic link, which sgr does not follow inside a folder"
                           ) from None
        if exc.errno in (errno.ENXIO, errno.EOPNOTSUPP):  # a socket
            raise SgrError(f"{printable(path)}: not a regular file (a socket)") from None
        raise
    mode = os.fstat(fd).st_mode
    if not stat.S_ISREG(mode):
        os.close(fd)
        kind = _KINDS.get(stat.S_IFMT(mode), "not a file")
        raise SgrError(f"{printable(path)}: not a regular file ({kind})")
    return fd


def _over(path: Path, cap: int, after: str = "") -> SgrError:
    size = f"{cap / MiB:g} MiB" if cap >= MiB else f"{cap} bytes"
    return SgrError(f"{printable(path)}: over {size}{after}, more than sgr reads in such a file")


def read_bytes(path: str | Path, cap: int, *, follow: bool = False) -> bytes:
    """The bytes of a file of a folder sgr did not make: a regular file of at most `cap` bytes.

    Args:
        path: the file.
        cap: the most bytes read: checked against its size before reading, and again while reading
            (a file that grows).
        follow: read through a symbolic link (a file the user names, a git-annex data set);
            otherwise a link is refused, as a link inside a run folder may point anywhere.

    Returns:
        The whole file.

    Raises:
        SgrError: in one line naming the file, when it is not a regular file (a FIFO, a device, a
            socket, a folder), a link (unless `follow`) or over `cap` bytes.
        OSError: when it is missing or cannot be read.
    """
    path = Path(path)
    fd = _open_regular(path, follow)
    try:
        if os.fstat(fd).st_size > cap:
            raise _over(path, cap)
        chunks, got = [], 0
        while got <= cap:
            chunk = os.read(fd, min(cap + 1 - got, 16 * MiB))
            if not chunk:
                break
            chunks.append(chunk)
            got += len(chunk)
        if got > cap:
            raise _over(path, cap)
        return b"".join(chunks)
    except OSError as exc:
        if exc.filename is None:  # name the file
            raise OSError(exc.errno, exc.strerror, str(path)) from exc
        raise
    finally:
        os.close(fd)


def read_head(path: str | Path, n: int, *, follow: bool = False) -> bytes:
    """The first `n` bytes (or fewer) of a regular file of a folder sgr did not make; SgrError or
    OSError as `read_bytes`."""
    path = Path(path)
    fd = _open_regular(path, follow)
    try:
        return os.read(fd, n)
    finally:
        os.close(fd)


def read_text(path: str | Path, cap: int, *, follow: bool = False) -> str:
    """`read_bytes` decoded as UTF-8 (UnicodeDecodeError when it is not text)."""
    return read_bytes(path, cap, follow=follow).decode()


def read_gzip(path: str | Path, cap: int = CHECKPOINT_CAP, *, follow: bool = False) -> bytes:
    """The uncompressed bytes of a gzip file (one member) of a folder sgr did not make: at most `cap`
    bytes read, and at most `cap` once uncompressed (a small file that would inflate to gigabytes
    is refused without filling the memory).

    Raises:
        SgrError: as `read_bytes`, when it inflates past `cap`, or is not gzip.
        EOFError: when it is cut short.
    """
    inflate = zlib.decompressobj(16 + zlib.MAX_WBITS)
    try:  # one byte past the cap at most: then it is refused, and nothing more is inflated
        data = inflate.decompress(read_bytes(path, cap, follow=follow), cap + 1)
    except zlib.error as exc:
        raise SgrError(f"{printable(path)}: not gzip ({exc})") from None
    if len(data) > cap:
        raise _over(path, cap, " once uncompressed")
    if not inflate.eof:
        raise EOFError(f"{path}: cut short")
    return data
