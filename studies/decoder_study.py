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
    sgr report results/decoders                                   # then the report
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

DECODERS = ("substrate", "cppn", "fourier", "growth")
SETS = {"big": {"Climber-v2": (10, 5), "Walker-v0": (10, 10)},
        "paper": {t: (5, 5) for t in ("Walker-v0", "ObstacleTraverser-v1", "Climber-v2", "Thrower-v0")}}
RECORDS = ("config.yaml", "neat.ini", "generations.csv", "champion.json", "champion-best-ever.json")
SGR = [sys.executable, "-m", "evolve.cli"]
GENERATIONS = 100


def finished(run: Path) -> bool:
    """A run folder whose last checkpoint is its last generation and whose champion is written."""
    from evolve.records.rundir import RunDir

    if not (run / "config.yaml").is_file() or not (run / "champion.json").is_file():
        return False
    rd = RunDir(run)
    return rd.last_checkpoint_generation() == int(rd.config()["generations"])


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


def evolve(run: Path, args: list[str], workers: int) -> None:
    """Run `sgr evolve ARGS --out RUN` to its end, or resume it; nothing when it is finished."""
    if finished(run):
        return
    cmd = SGR + ["evolve", "--quiet", "--workers", str(workers)]
    cmd += ["--resume", str(run)] if (run / "config.yaml").is_file() else args + ["--out", str(run)]
    print("+", " ".join(cmd[2:]), flush=True)
    subprocess.run(cmd, check=True, cwd=ROOT)


def keep(run: Path, records: Path) -> None:
    """Copy a finished run's records into the committed folder."""
    dest = records / run.name
    dest.mkdir(parents=True, exist_ok=True)
    for name in RECORDS:
        if (run / name).is_file():
            shutil.copy2(run / name, dest / name)


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
    a = p.parse_args()
    for name, args in runs(a.sets, a.tasks, a.seeds, a.decoders):
        run = a.out / name
        if a.list:
            print(("done " if finished(run) else "     ") + name)
            continue
        evolve(run, args, a.workers)
        keep(run, a.records)


if __name__ == "__main__":
    main()
