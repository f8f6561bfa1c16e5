"""The MAP-Elites comparison (issue 49): map-elites with SGR genomes against SGR's champion.

Per task (Walker-v0, Climber-v2) and seed (0-2): `sgr evolve --method map-elites --task T --seed S`
with the packaged config (configs/map-elites/<task>.yaml: the honest evaluation, an archive over
actuator x rigid shares, about the episodes of SGR's 100 generations). SGR's side is the packaged
honest evaluation's 100-generation runs in results/robust-fast/runs (`sgr-<task>-s<seed>`).

Runs are ordinary run folders ``map-elites-<task>-s<seed>`` under ``--out``, run or resumed as in
every study (studies/study_runs.py), seeds outermost; each finished run's records (with its
elites.json and archive.png) are copied to ``--records``.

    python studies/map_elites_study.py                 # all six runs: ~2-3 h on 2 busy cores
    python studies/map_elites_study.py --table         # docs/RESULTS.md's table, from the records
    sgr report results/map-elites --replays 20         # then the report (archives included)
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from studies.study_runs import RECORDS, evolve, finished, keep  # noqa: E402 (after sgr's folder is on the path)

TASKS = ("Walker-v0", "Climber-v2")
SGR_RUNS = ROOT / "results" / "robust-fast" / "runs"


def archive_cell(folders: list[Path]) -> str:
    """Coverage and QD score of the runs' archives at their last generation, mean ± sd over seeds."""
    from evolve.report.plots import read_generations

    last = [read_generations(d) for d in folders if (d / "generations.csv").is_file()]
    if not last:
        return "-"

    def spread(key: str, fmt: str) -> str:
        xs = [float(g[key][-1]) for g in last]
        sd = statistics.stdev(xs) if len(xs) > 1 else 0.0
        return f"{statistics.fmean(xs):{fmt}} ± {sd:{fmt}}"

    return f"coverage {spread('coverage', '.2f')}, QD score {spread('qd_score', '.1f')}"


def table(records: Path, seeds: list[int], tasks: list[str]) -> str:
    """A row per task: the best elite's and SGR's champion's mean return under uniform(±1e-3)
    noise (20 replays, the verdict's; mean ± sd over seeds, each seed's, how many hold, s/gen:
    `studies.big_study.arm_cell`) and the archives' coverage and QD score."""
    from studies.big_study import arm_cell

    lines = ["| task | map-elites: best elite | its archives | SGR: champion (robust-fast) |",
             "|---|---|---|---|"]
    for task in tasks:
        mine = [records / f"map-elites-{task}-s{s}" for s in seeds]
        sgr = [SGR_RUNS / f"sgr-{task}-s{s}" for s in seeds]
        lines.append(f"| {task} | {arm_cell(mine)} | {archive_cell(mine)} | {arm_cell(sgr)} |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", nargs="+", default=list(TASKS))
    ap.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    ap.add_argument("--out", type=Path, default=ROOT / "runs" / "map-elites")
    ap.add_argument("--records", type=Path, default=ROOT / "results" / "map-elites" / "runs")
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--table", action="store_true", help="only print the comparison's table from RECORDS")
    a = ap.parse_args()
    if a.table:
        print(table(a.records, a.seeds, a.tasks))
        return
    for seed in a.seeds:
        for task in a.tasks:
            run = a.out / f"map-elites-{task}-s{seed}"
            evolve(run, ["--method", "map-elites", "--task", task, "--seed", str(seed)], a.workers)
            if finished(run):
                keep(run, a.records, RECORDS + ("elites.json", "archive.png"))


if __name__ == "__main__":
    main()
