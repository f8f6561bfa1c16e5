"""`sgr plot`: best fitness per generation, of one run or of several side by side."""

from __future__ import annotations

import argparse
from pathlib import Path

from evolve.cli.common import output_path


def register(sub) -> argparse.ArgumentParser:
    """Add `plot` to the dispatcher's subparsers."""
    pl = sub.add_parser("plot", help="best fitness (and species, body diversity) per generation; comparable "
                                     "runs averaged, or one line per run with --per-run; one row per task")
    pl.add_argument("run_dirs", nargs="+", metavar="RUN_DIR",
                    help="run folders, or folders with runs at any depth below; files and other folders "
                         "(fitness.png, report.md, gallery/, a decoded champion) are skipped and named")
    pl.add_argument("--out", help="PNG path (default: RUN_DIR/fitness.png for one run, else fitness.png in "
                                  "the folder that holds the runs, e.g. runs/fitness.png for runs/*)")
    pl.add_argument("--compare", action="store_true", help="group style even for a single run")
    pl.add_argument("--per-run", action="store_true",
                    help="one line per run (coloured by its group) instead of a mean with a band")
    pl.add_argument("--pool", metavar="KEY[,KEY]",
                    help="average runs that differ in these settings (shape, pop, generations, steps, "
                         "evaluation, selection, precision, arch, start; all: every one of them); by "
                         "default only runs that differ in their seed alone are averaged")
    pl.set_defaults(fn=run)
    return pl


def run(args: argparse.Namespace) -> int:
    """`sgr plot`."""
    from evolve.report.groups import find_runs, parse_pool
    from evolve.report.plots import plot_run, plot_runs, runs_plot_path
    from tsim.errors import SgrError

    pool = parse_pool(args.pool)
    if args.out:
        output_path(args.out)
    paths = args.run_dirs
    one = Path(paths[0])
    if len(paths) == 1 and not (args.compare or args.per_run) and (
            (one / "generations.csv").is_file() or not one.is_dir() or not find_runs(one, False)[0]):
        out = plot_run(one, args.out or one / "fitness.png", diversity=True)  # (names what is missing)
    else:
        runs, skipped = find_runs(paths, need_config=False)
        for s in skipped:
            print(f"skipped {s.line()}")
        if not runs:
            raise SgrError("no run to plot: " + "; ".join(s.line() for s in skipped))
        out = plot_runs(runs, args.out or runs_plot_path(runs), per_run=args.per_run, pool=pool)
    print(f"wrote {out}")
    return 0
