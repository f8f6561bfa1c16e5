"""Summarise evolution runs (per method and task: best fitness at generation 0 and at the last
generation, mean over seeds) as a markdown table, and draw the comparison plot.

    python studies/paper_results.py runs/paper/* --plot runs/paper/ot_curves.png
"""

from __future__ import annotations

import argparse
import statistics
from collections import defaultdict
from pathlib import Path

from evolve.report.plots import plot_runs, read_generations, run_labels


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--generation", type=int, default=29, help="0-based; printed 1-based")
    ap.add_argument("--plot")
    args = ap.parse_args()
    runs = [Path(r) for r in args.runs if (Path(r) / "generations.csv").is_file()]
    groups: dict[tuple[str, str], list] = defaultdict(list)
    for r in runs:
        cols = read_generations(r)
        if "best" not in cols or len(cols["best"]) == 0:
            continue
        groups[run_labels(r)].append((r.name, cols))
    print("| method | task | seeds | generations run | best @ gen 1 (mean) | best @ gen "
          f"{args.generation + 1} (mean) | per seed @ gen {args.generation + 1} | s/gen (median) | "
          "episodes/gen (mean) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for (method, task), items in sorted(groups.items()):
        g0 = [c["best"][0] for _, c in items]
        at = [c["best"][min(args.generation, len(c["best"]) - 1)] for _, c in items]
        lens = [len(c["best"]) for _, c in items]
        sgen = statistics.median(x for _, c in items for x in c["total_s"])
        eps = statistics.fmean(x for _, c in items for x in c["episodes"])
        print(f"| {method} | {task} | {len(items)} | {', '.join(map(str, lens))} | "
              f"{statistics.fmean(g0):.3f} | {statistics.fmean(at):.3f} | "
              f"{', '.join(f'{x:.2f}' for x in at)} | {sgen:.1f} | {eps:.0f} |")
    if args.plot:
        print(f"\nplot: {plot_runs(runs, args.plot)}")


if __name__ == "__main__":
    main()
