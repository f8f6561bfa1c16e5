"""Argument types and helpers shared by the `sgr` commands. An option that means the same thing
in two commands is built here once, so it is typed (and checked) the same way in both."""

from __future__ import annotations

import argparse
import io
import os
import re
import sys
from pathlib import Path

from tasks.cli import nonnegative, output_path, parse_body, positive
from tsim.errors import SgrError

__all__ = ["add_import_file", "add_noise", "add_trust_imports", "add_workers", "nonnegative", "noise_level",
           "output_path", "parse_body", "parse_shape", "positive", "resume_dir", "workers_arg",
           "ClosedStdoutTolerant"]


def workers_arg(text: str) -> int | str:
    """argparse type of --workers: a positive int, 'auto' or 'ray'."""
    from evolve.rollout.pool import workers_problem

    try:
        value = int(text)
    except ValueError:
        value = text
    if workers_problem(value) is not None:
        raise argparse.ArgumentTypeError(workers_problem(text))
    return value


def parse_shape(text: str, option: str = "--shape") -> tuple[int, int]:
    """A body grid's shape written RxC (rows x columns, e.g. 10x10); SgrError (one line, no usage
    text) otherwise."""
    m = re.fullmatch(r"([0-9]+)x([0-9]+)", str(text).strip().lower())  # ASCII: '²'.isdigit() is True
    if m and int(m[1]) > 0 and int(m[2]) > 0:
        return int(m[1]), int(m[2])
    raise SgrError(f"{option} {text!r}: give the body's rows x columns as RxC, e.g. 10x10")


def add_workers(parser: argparse.ArgumentParser, default: int | None, help: str) -> None:
    """--workers: rollout processes, the same type in every command."""
    parser.add_argument("--workers", type=workers_arg, default=default, help=help)


# --noise EPS: the scale of the action noise, uniform(+-EPS) added to every action, in every command
# (`report` replays at one or more levels, `render` draws one episode at one level)
noise_level = nonnegative(float)


def add_noise(parser: argparse.ArgumentParser, *, several: bool, default, help: str) -> None:
    """--noise EPS (`several`: one or more levels), the same type in every command."""
    parser.add_argument("--noise", type=noise_level, nargs="+" if several else None, default=default,
                        metavar="EPS", help=help)


TRUST_HELP = ("import the code that a run or sweep folder names (its config's imports:, the file that "
              "registered a script's task, checked against its recorded sha256); say you trust the folder")


def add_trust_imports(parser: argparse.ArgumentParser) -> None:
    """--trust-imports, for every command that reads a run or sweep folder."""
    parser.add_argument("--trust-imports", action="store_true", help=TRUST_HELP)


IMPORT_HELP = ("a copy of the script that registered the run's task (task.json): imported, as if trusted, "
               "when its sha256 is the one recorded, and no other code (repeat for more files)")


def add_import_file(parser: argparse.ArgumentParser, help: str = IMPORT_HELP) -> None:
    """--import FILE, for every command that reads a run folder: the user names the script a run's
    task.json refers to (tasks/registry.py, `name_imports`)."""
    parser.add_argument("--import", dest="import_files", action="append", metavar="FILE", default=None,
                        help=help)


def resume_dir(path: str) -> str:
    """The run directory to resume, or a ValueError a person can act on."""
    p = Path(path)
    if not p.exists():
        raise SgrError(f"{path} does not exist")
    if (p / "sweep.yaml").is_file():
        raise SgrError(f"{path} is a sweep directory, not a run: continue the sweep with "
                       f"sgr sweep --resume {path}, or one of its runs with sgr evolve --resume "
                       f"{p / 'runs' / '<run>'}")
    return path


class ClosedStdoutTolerant:
    """sys.stdout for a run: once the reader of stdout is gone (`sgr evolve ... | head -2`), the
    rest is dropped and the run goes on; that is no disk error. One line on stderr says so."""

    def __init__(self, stream):
        self.stream, self.closed_pipe = stream, False

    def _gone(self) -> None:
        if not self.closed_pipe:
            self.closed_pipe = True
            try:  # what is still buffered would fail again at exit: send fd 1 to /dev/null
                os.dup2(os.open(os.devnull, os.O_WRONLY), self.stream.fileno())
            except (OSError, ValueError, io.UnsupportedOperation):
                pass
            print("sgr: stdout was closed; the run goes on without progress lines", file=sys.stderr)

    def write(self, text: str) -> int:
        """Write through until the reader is gone, then drop."""
        if not self.closed_pipe:
            try:
                return self.stream.write(text)
            except BrokenPipeError:
                self._gone()
        return len(text)

    def flush(self) -> None:
        """Flush through until the reader is gone."""
        if not self.closed_pipe:
            try:
                self.stream.flush()
            except BrokenPipeError:
                self._gone()

    def __getattr__(self, name):
        return getattr(self.stream, name)
