"""`sgr` command line: the dispatcher. Each of evolve's commands is a module of this package with
`register(subparsers)` (its options) and `run(args)`: evolve (evolve_cmd), sweep, report,
select-champion, render, plot and convert-checkpoints; the task and simulator commands (demo,
validate, bench) come from tasks/cli.py. Options shared by commands are built once in common.py.
The dispatcher lives in evolve, the only layer that may import all three."""

from __future__ import annotations

import argparse
import sys

from evolve.cli import convert_checkpoints, evolve_cmd, plot, render, report, select_champion, sweep
from evolve.cli.common import ClosedStdoutTolerant, add_trust_imports, parse_body, workers_arg
from tasks.cli import register_task_commands

__all__ = ["build_parser", "main", "parse_body", "workers_arg"]


def build_parser() -> argparse.ArgumentParser:
    """The `sgr` parser with every command."""
    p = argparse.ArgumentParser(prog="sgr", description="Batched evogym-faithful soft-robot toolkit")
    sub = p.add_subparsers(dest="cmd", required=True)
    e = evolve_cmd.register(sub)
    sw = sweep.register(sub)
    rp = report.register(sub)
    sc = select_champion.register(sub)
    r = render.register(sub)
    plot.register(sub)
    convert_checkpoints.register(sub)
    for parser in (e, sw, rp, r, sc):
        add_trust_imports(parser)
    register_task_commands(sub)
    return p


def main(argv: list[str] | None = None) -> int:
    """The `sgr` command; returns the exit code. A ValueError from a command is printed as one
    line, sgr: error: ..., on stderr with exit code 2 (argparse's own errors exit 2 as well)."""
    args = build_parser().parse_args(argv)
    if getattr(args, "trust_imports", False):
        from tasks.registry import trust_imports

        trust_imports()
    stdout, sys.stdout = sys.stdout, ClosedStdoutTolerant(sys.stdout)  # `sgr ... | head` is no error
    try:
        return args.fn(args)
    except ValueError as exc:
        print(f"sgr: error: {exc}", file=sys.stderr)
        return 2
    finally:
        sys.stdout = stdout


if __name__ == "__main__":
    sys.exit(main())
