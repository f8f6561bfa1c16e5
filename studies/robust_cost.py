"""Robust evaluation designs side by side: what a generation costs, and whether the champion holds.

Every design is one run of the same config (task, population, seed) but for its `robust` key; all
run in this one process and are stepped in turn, one generation each, so that they share the
machine's load alike (each search keeps its own Python `random` state: NeatSearch swaps it in).
Prints, per design, the median seconds per generation and its ratio to the nominal design, the
episodes per generation, and at the end (`--select`) the champion chosen by final selection and
its return under uniform(+-1e-3) action noise over `--replays` episodes as a share of its
noise-free return (>= 90 %: it holds).

    python studies/robust_cost.py --task Walker-v0 --pop 128 --generations 10
    python studies/robust_cost.py --generations 30 --select --out /tmp/pilot   # the pilot of #33
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from pathlib import Path

NOISE = {"action_noise": "uniform", "action_scale": 0.001, "offset": 0.0, "statistic": "mean"}
DESIGNS = {
    "nominal": None,
    "k4": {"episodes": 4, **NOISE, "reevaluate": True},  # results/robust: 4 episodes, elites again
    "acc1": {"episodes": 1, **NOISE, "reevaluate": True, "accumulate": True},
    "race16": {"episodes": 1, **NOISE, "reevaluate": True, "accumulate": True, "race": 16},
    "race8x2": {"episodes": 2, **NOISE, "reevaluate": True, "accumulate": True, "race": 8},
    "settle8": {"episodes": 1, **NOISE, "reevaluate": True, "accumulate": True, "settle": 8},
    "race8settle8": {"episodes": 1, **NOISE, "reevaluate": True, "accumulate": True, "race": 8, "settle": 8},
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", default="Walker-v0")
    ap.add_argument("--method", default="sgr")
    ap.add_argument("--pop", type=int, default=128)
    ap.add_argument("--generations", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", default="2")
    ap.add_argument("--designs", default="nominal,k4,acc1,race16")
    ap.add_argument("--select", action="store_true", help="final selection and noisy replays at the end")
    ap.add_argument("--replays", type=int, default=20)
    ap.add_argument("--out", default=None, help="folder for the runs (default: a temporary one)")
    args = ap.parse_args()

    from evolve.records.replay import replay_champion
    from evolve.runs.experiment import Experiment
    from evolve.runs.final_selection import FinalSelection, select_champion

    out = Path(args.out or tempfile.mkdtemp(prefix="robust-cost-"))
    names = args.designs.split(",")
    workers = int(args.workers) if args.workers.isdigit() else args.workers
    exps, times = {}, {n: [] for n in names}
    for n in names:
        cfg = {"method": args.method, "task": args.task, "pop_size": args.pop, "seed": args.seed,
               "generations": args.generations, "render_champion": False, "workers": workers,
               "robust": DESIGNS[n], "final_selection": None}
        exps[n] = Experiment.from_config(cfg, out / n, quiet=True)
    print(f"{args.method} {args.task} pop {args.pop}, {args.generations} generations, workers {workers}; "
          f"runs in {out}", flush=True)
    for g in range(args.generations):
        line = []
        for n in names:
            exp = exps[n]
            t0 = time.perf_counter()
            row = exp.search.step()
            times[n].append(time.perf_counter() - t0)
            exp.run.append_row({**row, "generation": row["generation"] + 1})
            line.append(f"{n} {times[n][-1]:5.2f} s {row['episodes']:>4} ep best {row['best']:6.3f}")
        print(f"gen {g + 1:>3}  " + "  |  ".join(line), flush=True)
    base = statistics.median(times["nominal"]) if "nominal" in times else None
    summary = {}
    for n in names:
        med = statistics.median(times[n])
        rows = exps[n].run.path / "generations.csv"
        eps = [int(r.split(",")[7]) for r in rows.read_text().splitlines()[1:]]
        summary[n] = {"median_s": med, "ratio": med / base if base else None,
                      "episodes_per_gen": statistics.mean(eps)}
        print(f"{n:>8}: median {med:6.2f} s/gen" + (f" = {med / base:4.2f}x nominal" if base else "")
              + f", {statistics.mean(eps):6.1f} episodes/gen", flush=True)
    if args.select:
        for n in names:
            exp = exps[n]
            champ = select_champion(exp, FinalSelection(candidates=16, episodes=32))  # as measured
            exp.run.save_checkpoint(exp.search.generation, exp.state())
            total = replay_champion(exp.run.path, args.replays, 1e-3)
            nominal, noisy = float(total[0]), float(total[1:].mean())
            summary[n].update({"score": champ["fitness"], "nominal": nominal, "noisy_mean": noisy,
                               "kept": noisy / nominal if nominal > 0 else None})
            print(f"{n:>8}: champion score {champ['fitness']:.3f}, nominal {nominal:.3f}, "
                  f"+-1e-3 mean {noisy:.3f} ({100 * noisy / nominal:.0f} % kept)", flush=True)
    for exp in exps.values():
        exp.close()
    (out / "summary.json").write_text(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main()
