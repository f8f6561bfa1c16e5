"""`sgr plot`: best fitness per generation, of one run or of several side by side."""

from __future__ import annotations

import argparse
from pathlib import Path

from evolve.cli.common import output_path


def register(sub) -> argparse.ArgumentParser:
    """Add `plot` to the dispatcher's subparsers."""
    pl = sub.add_parser("plot", help="best fitness per generation; runs of one method/task averaged, or "
                                     "one line per run with --per-run")
    pl.add_argument("run_dirs", nargs="+", metavar="RUN_DIR")
    pl.add_argument("--out", help="PNG path (default: RUN_DIR/fitness.png for one run, else fitness.png in "
                                  "the folder that holds the runs, e.g. runs/fitness.png for runs/*)")
    pl.add_argument("--compare", action="store_true", help="group style even for a single run")
    pl.add_argument("--per-run", action="store_true",
                    help="one line per run (coloured by method and task) instead of a mean with a band")
    pl.set_defaults(fn=run)
    return pl


def run(args: argparse.Namespace) -> int:
    """`sgr plot`."""
    from evolve.runs.plots import plot_run, plot_runs, runs_plot_path

    if args.out:
        output_path(args.out)
    if len(args.run_dirs) == 1 and not (args.compare or args.per_run):
        out = plot_run(args.run_dirs[0], args.out or Path(args.run_dirs[0]) / "fitness.png")
    else:
        out = plot_runs(args.run_dirs, args.out or runs_plot_path(args.run_dirs), per_run=args.per_run)
    print(f"wrote {out}")
    return 0
