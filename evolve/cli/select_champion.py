"""`sgr select-champion`: a finished run's champion chosen afresh among its final elites."""

from __future__ import annotations

import argparse

from evolve.cli.common import add_workers, positive, resume_dir


def register(sub) -> argparse.ArgumentParser:
    """Add `select-champion` to the dispatcher's subparsers."""
    sc = sub.add_parser("select-champion",
                        help="choose a finished run's champion afresh among its final elites by many "
                             "perturbed episodes (the final_selection config key, after the fact)")
    sc.add_argument("run_dir", metavar="RUN_DIR", help="a finished run folder")
    sc.add_argument("--candidates", type=positive(int), help="top final elites scored, besides the "
                                                                "best-ever genome (default: the run's, "
                                                                "else auto: sized by the run's length)")
    sc.add_argument("--episodes", type=positive(int), help="perturbed episodes per candidate (default: "
                                                           "the run's, else auto)")
    sc.add_argument("--statistic", help="mean, min, median or qNN (default mean)")
    sc.add_argument("--tolerance", type=float, help="a candidate passes if its score is at least its "
                                                    "nominal return less TOLERANCE x it (default 0.05)")
    sc.add_argument("--rank", choices=("min", "score", "pooled"),
                    help="among candidates that pass the test: the best min(score, nominal return), the best "
                         "score, or the best mean of score and confirmation by their episodes "
                         "(default min)")
    sc.add_argument("--confirm", type=int, help="fresh perturbed episodes per candidate that judge the "
                                                "test again (default 0: off)")
    sc.add_argument("--holdout", type=positive(int), help="fresh perturbed episodes of the champion alone "
                                                          "that give its fitness (default: as --episodes)")
    add_workers(sc, 1, "rollout processes (default 1)")
    sc.set_defaults(fn=run)
    return sc


def run(args: argparse.Namespace) -> int:
    """`sgr select-champion`."""
    from evolve.runs.experiment import select_finished_run
    from evolve.runs.final_selection import describe, explain

    given = {k: v for k, v in (("candidates", args.candidates), ("episodes", args.episodes),
                               ("statistic", args.statistic), ("tolerance", args.tolerance),
                               ("rank", args.rank), ("confirm", args.confirm),
                               ("holdout", args.holdout)) if v is not None}
    champ = select_finished_run(resume_dir(args.run_dir), given, args.workers)
    print(f"{args.run_dir}: {describe(champ)}")
    print(f"{args.run_dir}: {explain(champ)}")
    return 0
