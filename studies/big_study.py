"""The bigger-bodies study (issue 36): SGR above 5x5, against direct NEAT, and genomes that grow.

Per task, at the largest body its world admits (Walker-v0 10x10; Thrower-v0 6 rows x 9 columns, its
package sits on a 7th row; Climber-v2 10 rows x 5 columns, its channel is 5 cells wide), per seed,
all with the packaged configs' honest evaluation (configs/sgr/<task>.yaml, configs/direct/...):

- ``sgr-<task>-<RxC>-s<seed>``: SGR at the big size, 100 generations;
- ``direct-<task>-<RxC>-s<seed>``: direct NEAT at the big size, 100 generations;
- ``sgr-<task>-5x5-g50-s<seed>`` then ``sgr-<task>-5x5to<RxC>-s<seed>``: SGR at 5x5 for 50
  generations, then the same population at the big size for 50 more (``sgr evolve --from``);
- ``decoded-<task>-<RxC>-s<seed>``: the 5x5 champion of ``results/robust-fast/runs/sgr-<task>-s<seed>``
  (100 generations of the same evaluation) decoded at the big size, no further evolution
  (``sgr decode``).

Every run is an ordinary run folder under ``--out``; the script is idempotent: a finished run is
skipped, an unfinished one resumed (``sgr evolve --resume``), so after a kill it goes on where it
stood. Each finished run's records (config.yaml, neat.ini, generations.csv, champion.json,
champion-best-ever.json) are copied to ``--records``, the decoded champions written there directly.
Seeds go outermost, so a partial study has every arm of the first seeds.

    python studies/big_study.py                                   # all of it: hours on 2 cores
    python studies/big_study.py --tasks Walker-v0 --seeds 0       # one seed of one task
    python studies/big_study.py --decode-only                     # only the decoded champions (minutes)
    python studies/big_study.py --pictures                        # results/big/bodies.png from the records
    python studies/big_study.py --table                           # docs/RESULTS.md's table from them

The decoded champions are committed with the rest (champion.json of a 10x10 body is ~2.5 KB: the
controller is recorded as its genome's decoding); decoding is exact, so --decode-only remakes them
bit for bit from the committed 5x5 records.
    sgr report results/big                                         # then the report
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from studies.study_runs import SGR, champion_grid, evolve, keep  # noqa: E402 (after sgr's folder is on the path)

SHAPES = {"Walker-v0": (10, 10), "Thrower-v0": (6, 9), "Climber-v2": (10, 5)}


def study(task: str, seed: int, out: Path, records: Path, workers: int, decode_only: bool = False) -> None:
    rows, cols = SHAPES[task]
    size = f"{rows}x{cols}"
    common = ["--task", task, "--seed", str(seed)]
    source = ROOT / "results" / "robust-fast" / "runs" / f"sgr-{task}-s{seed}"
    decoded = records / f"decoded-{task}-{size}-s{seed}"
    if (source / "champion.json").is_file() and not (decoded / "champion.json").is_file():
        print(f"+ decode {source.name} --shape {size}", flush=True)
        subprocess.run(SGR + ["decode", str(source), "--shape", size, "--out", str(decoded)], check=False,
                       cwd=ROOT)
    if decode_only:
        return
    for method in ("sgr", "direct"):
        run = out / f"{method}-{task}-{size}-s{seed}"
        evolve(run, common + ["--method", method, "--shape", size, "--generations", "100"], workers)
        keep(run, records)
    small = out / f"sgr-{task}-5x5-g50-s{seed}"
    evolve(small, common + ["--generations", "50"], workers)
    keep(small, records)
    grown = out / f"sgr-{task}-5x5to{size}-s{seed}"
    evolve(grown, ["--from", str(small), "--shape", size, "--generations", "100"], workers)
    keep(grown, records)


ARMS = (  # (column title, folder name pattern: {task}, {size}, {seed})
    ("SGR at the big size, 100 gens", "sgr-{task}-{size}-s{seed}"),
    ("direct NEAT at the big size, 100 gens", "direct-{task}-{size}-s{seed}"),
    ("SGR 5x5 for 50, then the big size for 50", "sgr-{task}-5x5to{size}-s{seed}"),
    ("its 5x5 champion at 50", "sgr-{task}-5x5-g50-s{seed}"),
    ("5x5 champion (100 gens) decoded, no evolution", "decoded-{task}-{size}-s{seed}"),
    ("5x5 champion, 100 gens (robust-fast)", str(ROOT / "results" / "robust-fast" / "runs")
     + "/sgr-{task}-s{seed}"),
)


def arm_cell(folders: list[Path]) -> str:
    """One table cell: the champions' mean return under uniform(+-1e-3) action noise (20 replays,
    the verdict's, `evolve.records.replay.judge`), mean +- sd over seeds, then each seed's, how many
    hold, and each seed's median seconds per generation (generations.csv; per seed, since seeds
    may run on different machines; none for a decoded one, nor for robust-fast's runs, timed on
    another machine two at a time)."""
    import statistics

    import numpy as np

    from evolve.records.replay import judge
    from evolve.report.plots import read_generations

    have = [d for d in folders if (d / "champion.json").is_file()]
    if not have:
        return "-"
    verdicts = [judge(d) for d in have]
    means = [v.noisy_mean for v in verdicts]
    sd = statistics.stdev(means) if len(means) > 1 else 0.0
    text = f"{statistics.fmean(means):.2f} ± {sd:.2f} ({' / '.join(f'{m:.2f}' for m in means)})"
    text += f"; holds {sum(v.holds for v in verdicts)} of {len(verdicts)}"
    secs = [float(np.median(read_generations(d)["total_s"])) for d in have
            if (d / "generations.csv").is_file() and ROOT / "results" / "robust-fast" not in d.parents]
    if secs:
        text += f"; {' / '.join(f'{x:.1f}' for x in secs)} s/gen"
    return text


def table(records: Path, seeds: list[int], tasks: list[str]) -> str:
    """docs/RESULTS.md's table of the study: a row per task, a column per arm (`ARMS`), from the
    committed records alone."""
    lines = ["| task (big size) | " + " | ".join(t for t, _ in ARMS) + " |",
             "|---" * (len(ARMS) + 1) + "|"]
    for task in tasks:
        rows, cols = SHAPES[task]
        size = f"{rows}x{cols}"
        cells = [arm_cell([records / pat.format(task=task, size=size, seed=s) for s in seeds])
                 for _, pat in ARMS]
        lines.append(f"| {task} ({size}) | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def pictures(records: Path, out: Path, seeds: list[int], tasks: list[str]) -> Path:
    """One picture of every champion body of the study: a row per task and seed, a column per arm
    (`ARMS`), each labelled with its fitness; an arm not run yet is left blank."""
    short = ("SGR big", "direct big", "5x5 -> big", "5x5 at 50", "5x5 decoded", "5x5 (100 gens)")
    grid = [[(records / pat.format(task=task, size="x".join(map(str, SHAPES[task])), seed=seed),
              f"{task} s{seed}\n{short[c]}") for c, (_, pat) in enumerate(ARMS)]
            for task in tasks for seed in seeds]
    return champion_grid(grid, out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", nargs="+", default=list(SHAPES), choices=list(SHAPES))
    ap.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    ap.add_argument("--out", type=Path, default=ROOT / "runs" / "big")
    ap.add_argument("--records", type=Path, default=ROOT / "results" / "big" / "runs")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--pictures", action="store_true", help="only draw RECORDS/../bodies.png")
    ap.add_argument("--decode-only", action="store_true", help="only decode the 5x5 champions")
    ap.add_argument("--table", action="store_true", help="only print the study's table from RECORDS")
    a = ap.parse_args()
    if a.table:
        print(table(a.records, a.seeds, a.tasks))
        return
    if a.pictures:
        print(pictures(a.records, a.records.parent / "bodies.png", a.seeds, a.tasks))
        return
    a.out.mkdir(parents=True, exist_ok=True)
    for seed in a.seeds:
        for task in a.tasks:
            study(task, seed, a.out.resolve(), a.records.resolve(), a.workers, a.decode_only)


if __name__ == "__main__":
    main()
