"""The body-decoder study (issue 47): every body decoder of SGR, with the packaged honest evaluation.

Two sets of runs, each decoder x task x seed, 100 generations, the packaged configs
(configs/sgr/<task>.yaml: `robust` and `final_selection` as packaged), the decoder chosen with
``--body-decoder``:

- ``big``: Climber-v2 at 10 rows x 5 columns and Walker-v0 at 10x10, the largest bodies their
  worlds admit (results/big/README.md);
- ``paper``: the paper's four tasks (Walker-v0, ObstacleTraverser-v1, Climber-v2, Thrower-v0) at 5x5.

Runs are ordinary run folders ``<decoder>-<task>-<RxC>-s<seed>`` under ``--out``; the script is
idempotent: a finished run is skipped, an unfinished one resumed (``sgr evolve --resume``), so after
a kill it goes on where it stood. Each finished run's records (config.yaml, neat.ini,
generations.csv, champion.json, champion-best-ever.json) are copied to ``--records``. The order is
set by set, then seed by seed, so a partial study has every decoder of the first seeds of the
first set.

    python studies/decoder_study.py                               # all of it: many hours on 2 cores
    python studies/decoder_study.py --sets big --tasks Climber-v2 # one task of one set
    python studies/decoder_study.py --list                        # the runs, in order, and which are done
    python studies/decoder_study.py --table                       # docs/RESULTS.md's tables, from the records
    python studies/decoder_study.py --pictures                    # results/decoders/bodies.png
    sgr report results/decoders --replays 20                      # then the report
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from studies.study_runs import champion_grid, evolve, finished, keep  # noqa: E402 (after sgr's folder is on the path)

DECODERS = ("substrate", "cppn", "fourier", "growth")
SETS = {"big": {"Climber-v2": (10, 5), "Walker-v0": (10, 10)},
        "paper": {t: (5, 5) for t in ("Walker-v0", "ObstacleTraverser-v1", "Climber-v2", "Thrower-v0")}}
GENERATIONS = 100


def runs(sets: list[str], tasks: list[str] | None, seeds: list[int], decoders: list[str]):
    """(name, evolve arguments) of every run, in the study's order."""
    for s in sets:
        for seed in seeds:
            for task, (rows, cols) in SETS[s].items():
                if tasks and task not in tasks:
                    continue
                for decoder in decoders:
                    args = ["--task", task, "--seed", str(seed), "--shape", f"{rows}x{cols}",
                            "--generations", str(GENERATIONS)]
                    if decoder != "substrate":  # the default: a run of today's code is the same run
                        args += ["--body-decoder", decoder]
                    yield f"{decoder}-{task}-{rows}x{cols}-s{seed}", args


def _records(records: Path, decoder: str, task: str, shape: tuple[int, int], seeds: list[int]) -> list[Path]:
    return [records / f"{decoder}-{task}-{shape[0]}x{shape[1]}-s{seed}" for seed in seeds]


def table(records: Path, sets: list[str], seeds: list[int], decoders: list[str]) -> str:
    """docs/RESULTS.md's tables of the study, from the committed records alone: per set, a row per
    task and a column per decoder, each cell the champions' mean return under uniform(+-1e-3) noise
    (20 replays, the verdict's) over seeds, how many hold and the seconds per generation
    (`studies.big_study.arm_cell`); then a row per decoder of its champions' body measures, the
    mean over every champion of the set."""
    from studies.big_study import arm_cell

    out = []
    for s in sets:
        out += [f"**{s}**", "", "| task | " + " | ".join(decoders) + " |", "|---" * (len(decoders) + 1) + "|"]
        for task, shape in SETS[s].items():
            cells = [arm_cell(_records(records, d, task, shape, seeds)) for d in decoders]
            out.append(f"| {task} ({shape[0]}x{shape[1]}) | " + " | ".join(cells) + " |")
        out += ["", body_table(records, s, seeds, decoders), ""]
    return "\n".join(out)


MEASURED = ("symmetry_lr", "symmetry_tb", "irregularity", "boundaries", "actuator", "fill")


def body_table(records: Path, s: str, seeds: list[int], decoders: list[str]) -> str:
    """A row per decoder: the mean of each body measure (`MEASURED`) over its champions of set `s`,
    and the mean final body diversity of their runs (generations.csv's last `body_diversity`)."""
    import json
    import math
    import statistics

    from evolve.methods.body_measures import measures
    from evolve.report.plots import read_generations

    lines = ["| decoder | champions | " + " | ".join(MEASURED) + " | final diversity |",
             "|---" * (len(MEASURED) + 3) + "|"]
    for d in decoders:
        folders = [f for task, shape in SETS[s].items() for f in _records(records, d, task, shape, seeds)
                   if (f / "champion.json").is_file()]
        if not folders:
            continue
        ms = [measures(json.loads((f / "champion.json").read_text())["body"]) for f in folders]
        div = [read_generations(f).get("body_diversity", [math.nan])[-1] for f in folders]
        div = [x for x in div if math.isfinite(x)]
        cells = [f"{statistics.fmean(m[k] for m in ms):.2f}" for k in MEASURED]
        diversity = f"{statistics.fmean(div):.3f}" if div else "-"
        lines.append(f"| {d} | {len(ms)} | " + " | ".join(cells) + f" | {diversity} |")
    return "\n".join(lines)


def pictures(records: Path, out: Path, sets: list[str], seeds: list[int], decoders: list[str]) -> Path:
    """One picture of every champion body of the study: a row per set, task and seed, a column per
    decoder, each labelled with its fitness; a run not finished yet is left blank."""
    grid = [[(_records(records, d, task, SETS[s][task], [seed])[0],
              f"{task} {SETS[s][task][0]}x{SETS[s][task][1]} s{seed}\n{d}") for d in decoders]
            for s in sets for task in SETS[s] for seed in seeds]
    return champion_grid(grid, out)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sets", nargs="+", default=list(SETS), choices=list(SETS))
    p.add_argument("--tasks", nargs="+", default=None)
    p.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    p.add_argument("--decoders", nargs="+", default=list(DECODERS))
    p.add_argument("--out", type=Path, default=ROOT / "runs" / "decoders")
    p.add_argument("--records", type=Path, default=ROOT / "results" / "decoders" / "runs")
    p.add_argument("--workers", type=int, default=1)
    p.add_argument("--list", action="store_true", help="print the runs in order and which are finished")
    p.add_argument("--table", action="store_true", help="only print the study's tables from RECORDS")
    p.add_argument("--pictures", action="store_true", help="only draw RECORDS/../bodies.png")
    a = p.parse_args()
    if a.table:
        print(table(a.records, a.sets, a.seeds, a.decoders))
        return
    if a.pictures:
        print(pictures(a.records, a.records.parent / "bodies.png", a.sets, a.seeds, a.decoders))
        return
    for name, args in runs(a.sets, a.tasks, a.seeds, a.decoders):
        run = a.out / name
        if a.list:
            print(("done " if finished(run) else "     ") + name)
            continue
        evolve(run, args, a.workers)
        keep(run, a.records)


if __name__ == "__main__":
    main()
