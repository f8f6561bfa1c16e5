"""The quality-diversity study (issue 58): map-elites over the body against map-elites over behaviour
against SGR, at SGR's episode budget and twice it.

Arms, per task (Walker-v0, Climber-v2, UpStepper-v0) and seed (0-2), each the packaged map-elites
config (configs/map-elites/<task>.yaml: honest evaluation, 64 children a generation, up to 24
elites re-scored) with parents by curiosity and half the children from tournaments
(`qd.selection: curiosity`, `qd.exploit: 0.5`, docs/QD.md):

- ``body``: the archive over the body's actuator x rigid shares (10 x 10), as issue 49's;
- ``behaviour``: the archive over what the robot does, its gait frequency (0-10 Hz) x its share of
  steps touching the ground (10 x 10; tasks/behaviour.py);
- ``sgr``: SGR's packaged config for 100 generations (its episode budget: ~8,600 episodes). For
  Walker-v0 and Climber-v2 these are results/robust-fast/runs (the same config), not run again.

Every run first goes to 100 generations (SGR's budget; final selection picks a map-elites run's
champion, and the run is kept as ``<run>-g100``); then, before the next run starts, each map-elites
run is extended to 200 (twice it: `sgr evolve --resume RUN --generations 200`; the search does not
depend on the run's length, so its first 100 generations are the 100-generation run's,
tests/evolve/runs/test_map_elites_run.py).
Runs are ordinary run folders under ``--out``, run or resumed as in every study
(studies/study_runs.py), seeds outermost; finished records are copied to ``--records`` (default
runs/qd/records, beside the runs).

    python studies/qd_study.py                 # 18 map-elites runs and 3 SGR runs: ~8 h on 2 cores
    python studies/qd_study.py --commit        # the finished records, compact, into results/qd/runs
    python studies/qd_study.py --table         # docs: the table from the committed records
    python studies/qd_study.py --record        # docs/records/qd-behaviour.json: RESULTS' figures
    sgr report results/qd --replays 20 --no-gallery   # then report.md and summary.csv

What results/qd/runs keeps of a record (the tree has a budget, tests/test_tree_size.py): its config,
neat.ini and champion.json as written, champion-best-ever.json gzipped (no sgr command reads it),
generations.csv with its figures to 6 significant digits and its timings to milliseconds, and for a
run at twice the budget its archive, elites.json.gz (the 1x record's archive is the same run's at
generation 100; archive.png is drawn again by `sgr report`).
"""

from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from studies.study_runs import RECORDS, copy_record, evolve, finished, generations, keep  # noqa: E402 (after sgr's folder is on the path)

TASKS = ("Walker-v0", "Climber-v2", "UpStepper-v0")
SEARCH = {"selection": "curiosity", "exploit": 0.5}
ARCHIVES = {
    "body": {"descriptors": ["actuator", "rigid"], "resolution": [10, 10]},
    "behaviour": {"descriptors": ["gait_frequency", "contact"], "resolution": [10, 10],
                  "ranges": {"gait_frequency": [0.0, 10.0], "contact": [0.0, 1.0]}},
}
BUDGET, TWICE = 100, 200
SGR_RUNS = ROOT / "results" / "robust-fast" / "runs"
UNIFORM_RUNS = ROOT / "results" / "map-elites" / "runs"  # issue 49's: the same archive, parents uniform
ARCHIVE_RECORDS = RECORDS + ("elites.json", "archive.png")
COMMITTED = ROOT / "results" / "qd" / "runs"


def _rounded_csv(text: str) -> str:
    """generations.csv with each figure to 6 significant digits and each timing (`*_s`) to 1 ms."""
    import csv
    import io

    rows = list(csv.reader(io.StringIO(text)))
    head, out = rows[0], io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(head)
    for row in rows[1:]:
        cells = []
        for name, cell in zip(head, row, strict=True):
            try:
                x = float(cell)
            except ValueError:
                cells.append(cell)
                continue
            cells.append(cell if x.is_integer() and "." not in cell and "e" not in cell
                         else f"{x:.3f}" if name.endswith("_s") else f"{x:.6g}")
        w.writerow(cells)
    return out.getvalue()


def commit(records: Path, dest: Path = COMMITTED) -> list[str]:
    """Copy the finished records in `records` compactly into `dest` (see the module docstring);
    the names of the records copied."""
    done = []
    for rec in sorted(d for d in records.iterdir() if (d / "champion.json").is_file()):
        out = dest / rec.name
        out.mkdir(parents=True, exist_ok=True)
        for name in RECORDS:
            if name == "generations.csv":
                (out / name).write_text(_rounded_csv((rec / name).read_text()))
            elif (rec / name).is_file():
                copy_record(rec / name, out)
        if (rec / "elites.json").is_file() and not rec.name.endswith(f"-g{BUDGET}"):
            copy_record(rec / "elites.json", out, gzipped=True)
        done.append(rec.name)
    return done


def config(arm: str, task: str, folder: Path) -> Path:
    """The arm's config for `task`, written into `folder`: the packaged config with the arm's
    archive (map-elites) or SGR's budget of 100 generations (sgr)."""
    method = "sgr" if arm == "sgr" else "map-elites"
    packaged = ROOT / "configs" / method / f"{task}.yaml"
    raw = yaml.safe_load(packaged.read_text())
    raw["neat_config"] = str((packaged.parent / raw["neat_config"]).resolve())
    if arm == "sgr":
        raw["generations"] = BUDGET
    else:
        raw["qd"] = {**raw["qd"], **ARCHIVES[arm], **SEARCH}
        raw["generations"] = BUDGET
    folder.mkdir(parents=True, exist_ok=True)
    out = folder / f"{arm}-{task}.yaml"
    out.write_text(yaml.safe_dump(raw, sort_keys=False))
    return out


def sgr_run(records: Path, task: str, seed: int) -> Path:
    """SGR's run of `task` and `seed`: robust-fast's where it has one, else this study's."""
    known = SGR_RUNS / f"sgr-{task}-s{seed}"
    return known if known.is_dir() else records / f"sgr-{task}-s{seed}"


def run_arm(arm: str, task: str, seed: int, out: Path, records: Path, workers: int, twice: bool) -> None:
    """One arm's run: to SGR's budget (kept as ``<run>-g100`` for map-elites), or with `twice`
    extended to twice it (map-elites only; SGR's runs stop at its budget)."""
    run = out / f"{arm}-{task}-s{seed}"
    if arm == "sgr":
        if twice or (SGR_RUNS / f"sgr-{task}-s{seed}").is_dir():
            return
        evolve(run, ["--config", str(config(arm, task, out / "configs")), "--seed", str(seed)], workers)
        if finished(run):
            keep(run, records)
        return
    snapshot = out / f"{run.name}-g{BUDGET}"
    if not twice:
        if not snapshot.is_dir():
            evolve(run, ["--config", str(config(arm, task, out / "configs")), "--seed", str(seed)], workers)
            if finished(run) and generations(run) == BUDGET:
                shutil.copytree(run, snapshot, ignore=shutil.ignore_patterns("checkpoints"))
        if snapshot.is_dir():
            keep(snapshot, records, ARCHIVE_RECORDS)
        return
    if not snapshot.is_dir():
        return  # (its first part is not done)
    evolve(run, [], workers, to=TWICE)
    if finished(run):
        keep(run, records, ARCHIVE_RECORDS)


def best_under_noise(run: Path) -> float | None:
    """The best noisy score among the run's final-selection candidates: the mean return of 32
    episodes under the run's noise (uniform ±1e-3) of each of its best elites (map-elites) or final
    genomes (SGR), passing the holds rule or not; None without a final selection."""
    import json

    f = run / "champion.json"
    if not f.is_file():
        return None
    selection = json.loads(f.read_text()).get("selection")
    return max(float(c["score"]) for c in selection["candidates"]) if selection else None


def _spread(xs: list[float], digits: int = 2) -> str:
    import statistics

    if not xs:
        return "-"
    sd = statistics.stdev(xs) if len(xs) > 1 else 0.0
    each = " / ".join(f"{x:.{digits}f}" for x in xs)
    return f"{statistics.fmean(xs):.{digits}f} ± {sd:.{digits}f} ({each})"


def cells(runs: list[Path]) -> dict[str, str]:
    """A table's cells for an arm's runs (those finished): its champions' verdicts (20 replays under
    uniform ±1e-3, `studies.big_study.arm_cell`), the best candidate under noise, and for an archive
    its coverage and QD score at the run's last generation."""
    from evolve.report.plots import read_generations
    from studies.big_study import arm_cell

    have = [d for d in runs if (d / "champion.json").is_file()]
    out = {"n": f"{len(have)}", "champion": arm_cell(have) if have else "-",
           "best": _spread([b for d in have if (b := best_under_noise(d)) is not None])}
    gens = [read_generations(d) for d in have if (d / "generations.csv").is_file()]
    if gens and "coverage" in gens[0]:
        out["coverage"] = _spread([100 * float(g["coverage"][-1]) for g in gens], 1)
        out["qd_score"] = _spread([float(g["qd_score"][-1]) for g in gens], 1)
    return out


def table(records: Path, seeds: list[int], tasks: list[str]) -> str:
    """The study's table, from the committed records alone: per task and arm, at SGR's budget
    (map-elites: its ``-g100`` records) and at twice it."""
    lines = ["| task | arm | budget | runs | champion under ±1e-3 (verdict) | best candidate under ±1e-3 | "
             "coverage % | QD score |", "|---" * 8 + "|"]
    for task in tasks:
        for arm in ("sgr", "body, uniform (issue 49)", "body", "behaviour"):
            for budget, suffix in (("1x", f"-g{BUDGET}"), ("2x", "")):
                if arm.startswith("body, uniform"):  # issue 49's runs: uniform parents, 1x only
                    old = [UNIFORM_RUNS / f"map-elites-{task}-s{s}" for s in seeds]
                    if budget == "2x" or not any(d.is_dir() for d in old):
                        continue
                    runs = old
                elif arm == "sgr":
                    if budget == "2x":
                        continue
                    runs = [sgr_run(records, task, s) for s in seeds]
                else:
                    runs = [records / f"{arm}-{task}-s{s}{suffix}" for s in seeds]
                c = cells(runs)
                lines.append(f"| {task} | {arm} | {budget} | {c['n']} of {len(seeds)} | {c['champion']} | "
                             f"{c['best']} | {c.get('coverage', '-')} | {c.get('qd_score', '-')} |")
    return "\n".join(lines)


def record(records: Path, seeds: list[int], tasks: list[str]) -> dict:
    """docs/records/qd-behaviour.json: the figures of docs/RESULTS.md's table, from the committed
    records alone (each champion's verdict: 20 replays under uniform ±1e-3, as the table's)."""
    import datetime
    import statistics
    import subprocess

    from evolve.records.replay import judge
    from evolve.report.plots import read_generations

    def noisy(runs: list[Path]) -> float:
        return statistics.fmean(judge(d).noisy_mean for d in runs)

    def coverage(runs: list[Path]) -> float:
        return statistics.fmean(100 * float(read_generations(d)["coverage"][-1]) for d in runs)

    figures: dict[str, dict] = {}
    unit = f"mean over seeds {', '.join(map(str, seeds))} of the champion's return under uniform(±1e-3)"
    for task in tasks:
        arm = {a: [records / f"{a}-{task}-s{s}-g{BUDGET}" for s in seeds] for a in ARCHIVES}
        twice = {a: [records / f"{a}-{task}-s{s}" for s in seeds] for a in ARCHIVES}
        sgr = noisy([sgr_run(records, task, s) for s in seeds])
        figures[f"{task}-sgr-noise"] = {"value": round(sgr, 6), "unit": unit + ", SGR at 100 generations"}
        for a, runs in arm.items():
            mean = noisy(runs)
            figures[f"{task}-{a}-noise"] = {
                "value": [round(mean, 6), round(mean / sgr, 6)],
                "unit": unit + f", the {a} map at SGR's budget; its ratio to SGR's"}
        figures[f"{task}-coverage"] = {"value": [round(coverage(arm[a]), 6) for a in ("behaviour", "body")],
                                       "unit": "% of cells filled at SGR's budget, behaviour / body map"}
        figures[f"{task}-twice-noise"] = {"value": [round(noisy(twice[a]), 6) for a in ("behaviour", "body")],
                                          "unit": unit + ", at twice SGR's budget, behaviour / body map"}
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip()
    return {"name": "qd-behaviour", "figures": figures,
            "machine": "2-vCPU shared VMs (AMD EPYC, then Intel Xeon), two or three runs at a time",
            "commit": commit, "date": datetime.date.today().isoformat(),
            "command": "python studies/qd_study.py && python studies/qd_study.py --commit && "
                       "python studies/qd_study.py --record",
            "source": "docs/RESULTS.md 'Today'; results/qd/runs (champions replayed 20 times under "
                      "uniform(±1e-3), `evolve.records.replay.judge`)"}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", nargs="+", default=list(TASKS))
    ap.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    ap.add_argument("--arms", nargs="+", default=["behaviour", "body", "sgr"])
    ap.add_argument("--out", type=Path, default=ROOT / "runs" / "qd")
    # (the records stay beside the runs until the study is done: what results/ keeps of them is
    # chosen then, within the tree's budget)
    ap.add_argument("--records", type=Path, default=ROOT / "runs" / "qd" / "records")
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--table", action="store_true", help="only print the study's table (committed records)")
    ap.add_argument("--commit", action="store_true",
                    help="only copy the finished records into results/qd/runs")
    ap.add_argument("--record", action="store_true",
                    help="only write docs/records/qd-behaviour.json from the committed records")
    a = ap.parse_args()
    if a.table:
        print(table(COMMITTED, a.seeds, a.tasks))
        return
    if a.record:
        import json

        out = ROOT / "docs" / "records" / "qd-behaviour.json"
        out.write_text(json.dumps(record(COMMITTED, a.seeds, a.tasks), indent=1, ensure_ascii=False) + "\n")
        print(f"wrote {out}")
        return
    if a.commit:
        print("committed:", " ".join(commit(a.records)) or "none")
        return
    for seed in a.seeds:
        for task in a.tasks:
            for arm in a.arms:  # each run to SGR's budget, then on to twice it while its checkpoint is here
                for twice in (False, True):
                    run_arm(arm, task, seed, a.out, a.records, a.workers, twice)


if __name__ == "__main__":
    main()
