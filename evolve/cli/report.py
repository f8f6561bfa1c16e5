"""`sgr report`: one report (table, summary CSV, curves, report.html) of a sweep or of run folders."""

from __future__ import annotations

import argparse

from evolve.cli.common import add_noise, positive
from evolve.rollout.robust import MAX_EPISODES


def register(sub) -> argparse.ArgumentParser:
    """Add `report` to the dispatcher's subparsers."""
    rp = sub.add_parser("report", help="a run's or a sweep's table (with the authors' figures), summary CSV "
                                       "and curves")
    rp.add_argument("dir", metavar="DIR", nargs="+",
                    help="a run directory, a sweep directory or any folder with runs at any depth below it "
                         "(several: one report); what is not a run is skipped and named")
    rp.add_argument("--out", help="report path (default DIR/report.md); summary.csv, curves.png beside it")
    rp.add_argument("--no-robustness", action="store_true",
                    help="skip replaying each champion under action noise")
    add_noise(rp, several=True, default=[1e-9, 1e-3],
              help="noise levels: each champion replayed with uniform(+-EPS) added to every "
                   "action (default 1e-9 1e-3)")
    rp.add_argument("--replays", type=positive(int, MAX_EPISODES), default=10, metavar="N",
                    help="replays per champion and noise level (default 10)")
    rp.add_argument("--no-gallery", action="store_true",
                    help="no champion GIFs (gallery/) in report.html")
    rp.add_argument("--pool", metavar="KEY[,KEY]",
                    help="average runs that differ in these settings (shape, pop, generations, steps, "
                         "evaluation, selection, precision, arch, start; all: every one of them); by "
                         "default only runs that differ in their seed alone are averaged")
    rp.set_defaults(fn=run)
    return rp


def run(args: argparse.Namespace) -> int:
    """`sgr report`."""
    from evolve.report.groups import parse_pool
    from evolve.report.report import write_report

    out = write_report(args.dir, args.out, robustness=not args.no_robustness, levels=args.noise,
                       replays=args.replays, gallery=not args.no_gallery, pool=parse_pool(args.pool),
                       say=print)
    print(f"wrote {out}, {out.parent / 'report.html'}, {out.parent / 'summary.csv'} and "
          f"{out.parent / 'curves.png'}" + ("" if args.no_gallery else f" and {out.parent / 'gallery'}/"))
    return 0
