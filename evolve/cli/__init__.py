"""`sgr` command line: the dispatcher. Each of evolve's commands is a module of this package with
`register(subparsers)` (its options) and `run(args)`: evolve (evolve_cmd), sweep, report,
select-champion, explain, render, plot, migrate (alias: convert-checkpoints) and decode; the task and
simulator commands (demo, bench) come from tasks/cli.py, and validate from parity/cli.py.
Options shared by commands are built once in common.py. The dispatcher lives in evolve, the only
layer that may import them all."""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
import traceback

from evolve.cli import decode, evolve_cmd, explain, migrate, plot, render, report, select_champion, sweep
from evolve.cli.common import (
    IMPORT_HELP,
    ClosedStdoutTolerant,
    add_import_file,
    add_trust_imports,
    parse_body,
    workers_arg,
)
from parity import cli as parity_cli
from tasks.cli import register_task_commands
from tsim.errors import SgrError, printable

__all__ = ["build_parser", "main", "parse_body", "workers_arg"]


def build_parser() -> argparse.ArgumentParser:
    """The `sgr` parser with every command."""
    p = argparse.ArgumentParser(prog="sgr", description="Batched evogym-faithful soft-robot toolkit")
    p.add_argument("--debug", action="store_true", help="show the traceback of every error")
    sub = p.add_subparsers(dest="cmd", required=True, metavar="COMMAND",
                           help="one of the commands below; sgr COMMAND --help says what it takes")
    e = evolve_cmd.register(sub)
    sw = sweep.register(sub)
    rp = report.register(sub)
    sc = select_champion.register(sub)
    explain.register(sub)
    r = render.register(sub)
    plot.register(sub)
    migrate.register(sub)
    dc = decode.register(sub)
    for parser in (e, sw, rp, r, sc, dc):
        add_trust_imports(parser)
    add_import_file(e, IMPORT_HELP + "; with --method, a module of your own that registers the method "
                       "(docs/EVOLVE.md \"Adding a method\"), imported and named in the run's imports:")
    for parser in (rp, r, sc, dc):  # the commands that read one run's task.json
        add_import_file(parser)
    register_task_commands(sub)
    parity_cli.register(sub)
    for parser in sub.choices.values():  # `sgr evolve ... --debug` as well as `sgr --debug evolve ...`
        parser.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                            help="show the traceback of every error")
    return p


def main(argv: list[str] | None = None) -> int:
    """The `sgr` command; returns the exit code. Bad input (SgrError, tsim/errors.py) is printed as
    one line, sgr: error: ..., on stderr with exit code 2 (argparse's own errors exit 2 as well).
    Another ValueError (bad input from code that does not say SgrError yet, or a bug), a file that
    cannot be read or written (OSError: its path and why), an input nested too deeply to parse
    (RecursionError) or too large for memory (MemoryError) is that line plus the path of a file
    holding its full traceback, exit 2; any other exception (a bug, or bad input no check caught)
    is one line naming its type, with the traceback's file, exit 1, but for a user's task module
    that raised (its traceback shows the user's code). `--debug` lets every exception through with
    its traceback."""
    args = build_parser().parse_args(argv)
    trusted = None  # --trust-imports holds for this command only, also when main() runs in-process
    if getattr(args, "trust_imports", False):
        from tasks.registry import imports_trusted, trust_imports

        trusted = imports_trusted()
        trust_imports()
    named = None  # --import FILE: for this command only too
    stdout, sys.stdout = sys.stdout, ClosedStdoutTolerant(sys.stdout)  # `sgr ... | head` is no error
    try:
        if getattr(args, "import_files", None):
            from tasks.registry import name_imports

            named = name_imports(())  # (what was named before: restored below)
            name_imports(args.import_files)
        return args.fn(args)
    except SgrError as exc:
        if args.debug:
            raise
        print(f"sgr: error: {printable(exc)}", file=sys.stderr)
        return 2
    except (ValueError, OSError, RecursionError, MemoryError) as exc:
        if args.debug:
            raise
        print(f"sgr: error: {_one_line(exc)} (full traceback: {_write_traceback(exc)})", file=sys.stderr)
        return 2
    except Exception as exc:  # noqa: BLE001 (the last resort: one line, the traceback in a file)
        from tasks.registry import TaskModuleError

        if args.debug or isinstance(exc, TaskModuleError):  # a user's task module: its traceback
            raise
        print(f"sgr: error: unexpected {type(exc).__name__}: {_one_line(exc)} (full traceback: "
              f"{_write_traceback(exc)}; --debug shows it here)", file=sys.stderr)
        return 1
    finally:
        sys.stdout = stdout
        if named is not None:
            from tasks.registry import name_imports

            name_imports(named)
        if trusted is not None:
            from tasks.registry import trust_imports

            trust_imports(trusted)


def _one_line(exc: BaseException, most: int = 300) -> str:
    """`exc` as the error line says it: a file's path and why for an OSError, a word for a too deep
    or too large input, else its message; on one line, cut at `most` characters (an error may
    quote an input)."""
    if isinstance(exc, OSError) and exc.filename is not None:  # a rename's: its target
        text = f"{exc.filename2 if exc.filename2 is not None else exc.filename}: {exc.strerror or exc}"
    elif isinstance(exc, RecursionError):
        text = f"an input is nested too deeply to read ({exc})"
    elif isinstance(exc, MemoryError):
        text = f"not enough memory ({exc or 'the input asks for more than this machine has'})"
    else:
        text = str(exc) or type(exc).__name__
    text = printable(" ".join(text.split()))  # a name from a folder may hold terminal escapes
    return text if len(text) <= most else text[:most] + " ..."


def _write_traceback(exc: BaseException) -> str:
    """Write `exc`'s traceback (with its notes and causes) to a new file in the temporary folder;
    returns its path."""
    fd, path = tempfile.mkstemp(prefix=f"sgr-error-{time.strftime('%Y%m%d-%H%M%S')}-", suffix=".txt")
    with os.fdopen(fd, "w") as f:
        f.write("".join(traceback.format_exception(exc)))
    return path


if __name__ == "__main__":
    sys.exit(main())
