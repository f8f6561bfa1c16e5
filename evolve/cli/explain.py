"""`sgr explain RUN`: what a run's champion figures are, in plain words (evolve/report/explain.py)."""

from __future__ import annotations

import argparse


def register(sub) -> argparse.ArgumentParser:
    """Add `explain` to the dispatcher's subparsers."""
    ex = sub.add_parser("explain", help="tell the story of a run's champion: the figure to quote, how "
                                        "it was chosen, on which episodes, and what each number of "
                                        "champion.json is (reads the folder, simulates nothing)")
    ex.add_argument("run_dir", metavar="RUN_DIR", help="a run folder with a champion.json")
    ex.set_defaults(fn=run)
    return ex


def run(args: argparse.Namespace) -> int:
    """`sgr explain`."""
    from evolve.report.explain import explain_run

    print(explain_run(args.run_dir))
    return 0
