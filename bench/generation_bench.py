"""Seconds per generation of an evolution method at full size (not run by CI).

    python bench/generation_bench.py --config configs/sgr/Walker-v0.yaml --generations 4
    python bench/generation_bench.py --shape 10x10          # the same config at another body size

Prints build / sim / neat / total seconds per generation (median over the generations after the
first, which also pays the one-off Taichi compile) and simulated robot-steps per second.
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from pathlib import Path

from evolve.cli.common import parse_shape, workers_arg
from evolve.runs.experiment import Experiment
from tasks.specs import task_spec

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--config", default=str(ROOT / "configs/sgr/Walker-v0.yaml"))
    ap.add_argument("--generations", type=int, default=4)
    ap.add_argument("--pop", type=int)
    ap.add_argument("--workers", type=workers_arg,
                    help="rollout processes (default: the config's, auto = all CPUs)")
    ap.add_argument("--shape", type=parse_shape, help="robot_shape RxC (default: the config's)")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--record", metavar="PATH", help="also write a record (tasks/records.py)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        flags = {"generations": args.generations, "pop_size": args.pop, "workers": args.workers,
                 "robot_shape": list(args.shape) if args.shape else None}
        exp = Experiment.create(args.config, f"{tmp}/run", {k: v for k, v in flags.items() if v is not None},
                                quiet=True)
        rows = []
        t0 = time.perf_counter()
        for _ in range(args.generations):
            rows.append(exp.search.step())
        wall = time.perf_counter() - t0
        exp.close()
    cfg = exp.cfg
    steps = cfg.episode_steps or task_spec(cfg.task).paper_steps
    timed = rows[1:] or rows
    med = {k: statistics.median(r[k] for r in timed) for k in ("build_s", "sim_s", "neat_s", "total_s")}
    robot_steps = sum(r["episodes"] for r in timed) * steps  # upper bound: early terminations stop sooner
    out = {"config": args.config, "method": cfg.method, "task": cfg.task, "pop": cfg.pop_size,
           "shape": list(cfg.robot_shape),
           "workers": exp.pool.workers,
           "steps": steps, "generations": args.generations, "first_generation_s": rows[0]["total_s"],
           **{f"median_{k}": v for k, v in med.items()},
           "robot_steps_per_s": robot_steps / sum(r["sim_s"] for r in timed), "wall_s": wall}
    if args.record:
        from tasks.records import figure, write_record

        write_record(args.record, None, {"generation": figure(round(med["total_s"], 2), "s per generation")},
                     **{k: out[k] for k in ("config", "method", "task", "pop", "shape", "workers", "steps")})
    if args.json:
        print(json.dumps(out))
    else:
        print(f"{cfg.method} {cfg.task} {'x'.join(map(str, cfg.robot_shape))} "
              f"pop {cfg.pop_size} x {steps} steps, "
              f"{exp.pool.workers} workers: median "
              f"{med['total_s']:.2f} s/generation (decode {med['build_s']:.2f}, sim {med['sim_s']:.2f}, "
              f"neat {med['neat_s']:.2f}); first generation {rows[0]['total_s']:.1f} s; "
              f"{out['robot_steps_per_s']:.0f} robot-steps/s")


if __name__ == "__main__":
    main()
