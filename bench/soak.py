"""Soak test: memory and checkpoint size over a long run (a benchmark, not run by CI).

    python bench/soak.py --method sgr --generations 1000
    python bench/soak.py --method nested --generations 1000 --csv soak-nested.csv

Runs `--generations` generations of a method with a small population and short episodes through
the project's own machinery (`Experiment.create` + `run_all`, a run directory with a checkpoint
every `--every` generations) and records every `--every` generations: the resident memory of this
process (VmRSS in /proc/self/status) and of the rollout worker processes (when `--workers` > 1),
the size of the checkpoint just written, the seconds per generation over the window, the number
of live Python objects and, for the nested baseline, the number of inner controller populations.
Prints a table, writes it as CSV and reports the growth after generation 100,
(value at the end - value at 100) / value at 100, for memory and checkpoint size (target < 10 %).

Defaults: sgr and direct pop 16; nested pop 8 with inner_pop_size 8 and inner_generations 1;
20-step episodes; Walker-v0; one worker (rollouts in this process). `--set key=value` sets any
other config key (YAML value, e.g. `--set inner_keep_generations=null`).
"""

from __future__ import annotations

import argparse
import csv
import gc
import tempfile
import time
from pathlib import Path

import yaml

from evolve.cli.common import workers_arg
from evolve.runs.experiment import Experiment

ROOT = Path(__file__).resolve().parent.parent

DEFAULTS = {"sgr": {"pop_size": 16}, "direct": {"pop_size": 16},
            "nested": {"pop_size": 8, "inner_pop_size": 8, "inner_generations": 1}}
COLUMNS = ["generation", "rss_mib", "workers_rss_mib", "total_rss_mib", "checkpoint_kib", "s_per_gen",
           "py_objects", "mean_connections", "inner_populations"]


def rss_mib(pid: int | str = "self") -> float:
    """Resident set size of a process (VmRSS), MiB; 0 when it has gone."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return 0.0


def write_config(args: argparse.Namespace, path: Path) -> Path:
    src = Path(args.config or ROOT / f"configs/{args.method}/{args.task}.yaml")
    raw = yaml.safe_load(src.read_text())
    for key in ("neat_config", "controller_neat_config"):
        if key in raw:
            raw[key] = str((src.parent / raw[key]).resolve())
    raw.update(DEFAULTS.get(raw["method"], {}))
    flags = {"pop_size": args.pop, "inner_pop_size": args.inner_pop_size,
             "inner_generations": args.inner_generations}
    raw.update({k: v for k, v in flags.items() if v is not None})
    raw.update(generations=args.generations, episode_steps=args.episode_steps, seed=args.seed,
               checkpoint_every=args.every, workers=args.workers, render_champion=False)
    for item in args.set:
        key, _, value = item.partition("=")
        raw[key] = yaml.safe_load(value)
    path.write_text(yaml.safe_dump(raw, sort_keys=False))
    return path


def growth(rows: list[dict], key: str, start: int = 100) -> float | None:
    base = next((r[key] for r in rows if r["generation"] == start), None)
    if base is None or not base or rows[-1]["generation"] <= start:
        return None
    return (rows[-1][key] - base) / base


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--method", choices=sorted(DEFAULTS), default="sgr")
    ap.add_argument("--task", default="Walker-v0")
    ap.add_argument("--config", help="YAML config (default configs/<method>/<task>.yaml)")
    ap.add_argument("--generations", type=int, default=1000)
    ap.add_argument("--every", type=int, default=50, help="measure and checkpoint every N generations")
    ap.add_argument("--pop", type=int)
    ap.add_argument("--inner-pop-size", type=int)
    ap.add_argument("--inner-generations", type=int)
    ap.add_argument("--episode-steps", type=int, default=20)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=workers_arg, default=1)
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--out", help="folder for the config, run directory and CSV (default: temporary)")
    ap.add_argument("--csv", help="CSV path (default: <out>/soak.csv)")
    args = ap.parse_args()

    tmp = None if args.out else tempfile.TemporaryDirectory(prefix="soak-")
    out = Path(args.out or tmp.name)
    out.mkdir(parents=True, exist_ok=True)
    cfg_path = write_config(args, out / "config.yaml")
    exp = Experiment.create(str(cfg_path), str(out / "run"), {}, quiet=True)
    rows: list[dict] = []
    clock = {"t": time.perf_counter(), "gen": 0}
    print(f"{exp.cfg.method} {exp.cfg.task} pop {exp.cfg.pop_size}, "
          f"{exp.cfg.episode_steps}-step episodes, {args.generations} generations, "
          f"workers {exp.pool.workers}; run directory {out / 'run'}", flush=True)
    header = ("gen", "RSS MiB", "workers", "total", "ckpt KiB", "s/gen", "objects", "conns", "inner")
    print("{:>6} {:>8} {:>8} {:>8} {:>9} {:>7} {:>9} {:>6} {:>6}".format(*header), flush=True)

    def measure(e: Experiment) -> None:
        g = e.search.generation
        if g % args.every and g != args.generations:
            return
        now = time.perf_counter()
        ckpt = e.run.ckpt_dir / f"gen-{g:05d}.json.gz"
        workers = sum(rss_mib(p.pid) for p in e.pool._procs)
        pop = e.search.population.values()
        inner = getattr(e.problem, "inner", None)
        row = {"generation": g, "rss_mib": rss_mib(), "workers_rss_mib": workers,
               "total_rss_mib": rss_mib() + workers,
               "checkpoint_kib": ckpt.stat().st_size / 1024 if ckpt.is_file() else float("nan"),
               "s_per_gen": (now - clock["t"]) / max(1, g - clock["gen"]),
               "py_objects": len(gc.get_objects()),
               "mean_connections": sum(len(x.connections) for x in pop) / max(1, len(pop)),
               "inner_populations": "" if inner is None else len(inner)}
        rows.append(row)
        print(f"{g:>6} {row['rss_mib']:8.1f} {workers:8.1f} {row['total_rss_mib']:8.1f} "
              f"{row['checkpoint_kib']:9.1f} {row['s_per_gen']:7.3f} {row['py_objects']:>9} "
              f"{row['mean_connections']:6.1f} {row['inner_populations']:>6}", flush=True)
        clock.update(t=time.perf_counter(), gen=g)

    t0 = time.perf_counter()
    try:
        exp.run_all(after_generation=measure)
    finally:
        exp.close()
    wall = time.perf_counter() - t0
    csv_path = Path(args.csv) if args.csv else out / "soak.csv"
    with csv_path.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=COLUMNS, lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
    print(f"{args.generations} generations in {wall:.0f} s: {wall / args.generations:.3f} s/generation; "
          f"CSV {csv_path}")
    for key, name in (("total_rss_mib", "RSS"), ("checkpoint_kib", "checkpoint size")):
        gr = growth(rows, key)
        verdict = "n/a (run ends before generation 100)" if gr is None else \
            f"{gr:+.1%} ({'within' if gr < 0.10 else 'OVER'} the target of < 10 %)"
        print(f"growth of {name} after generation 100: {verdict}")
    if tmp is not None:
        tmp.cleanup()


if __name__ == "__main__":
    main()
