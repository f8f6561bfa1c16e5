"""`BatchEnv.step`'s own host work on every task (issue 48 item 2): observations, rewards,
termination and actions, with the physics replaced by nothing, in microseconds per robot-step.

    python bench/env_host_tasks.py [--robots 8192] [--steps 20] [--tasks T ...] [--record PATH]

One process, task after task: B random 5x5 robots (`sample_robots`, seed 0), one warm-up step
(compiling the kernels), then --steps steps whose returned arrays are dropped; wall and process
CPU time per robot-step. `--fused 0` times the numpy path (the kernels' oracle) instead.
"""

from __future__ import annotations

import argparse
import gc
import time

import numpy as np


def host_us(task: str, bodies: list, steps: int, fused: bool) -> tuple[float, float]:
    """(wall, CPU) microseconds per robot-step of `BatchEnv.step` less the physics."""
    from tasks.env import BatchEnv

    env = BatchEnv(task, bodies, episode_steps=steps + 2, fused=fused)
    env.sim.step = lambda n=1: None  # the host's share alone
    acts = np.full((env.n_worlds, env.sim.max_actuators), 1.1)
    env.step(acts)
    gc.collect()
    w, c = time.perf_counter(), time.process_time()
    for _ in range(steps):
        env.step(acts)
    n = env.n_worlds * steps
    return (time.perf_counter() - w) / n * 1e6, (time.process_time() - c) / n * 1e6


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robots", type=int, default=8192)
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--tasks", nargs="+", default=None, help="default: sgr's 32 tasks")
    ap.add_argument("--fused", type=int, default=1, choices=(0, 1))
    ap.add_argument("--record", metavar="PATH", help="also write a record (tasks/records.py)")
    a = ap.parse_args()

    from tasks.records import cpu_model
    from tasks.specs import BUILTIN
    from tsim.sampling import sample_robots

    bodies = list(sample_robots(a.robots, (5, 5), np.random.default_rng(0)))
    tasks = a.tasks or sorted(BUILTIN)
    print(f"{cpu_model()}; B = {a.robots}; {'kernel' if a.fused else 'numpy'} path; "
          "us per robot-step (wall / cpu)")
    out = {}
    for task in tasks:
        out[task] = host_us(task, bodies, a.steps, bool(a.fused))
        print(f"{task:<24} {out[task][0]:8.3f} {out[task][1]:8.3f}", flush=True)
    cpu = [v[1] for v in out.values()]
    print(f"range over {len(out)} tasks: {min(cpu):.2f}-{max(cpu):.2f} us per robot-step (CPU)")
    if a.record:
        from tasks.records import figure, write_record

        figures = {t: figure(round(v[1], 2), "us per robot-step (CPU)") for t, v in out.items()}
        figures["range"] = figure([round(min(cpu), 2), round(max(cpu), 2)], "us per robot-step (CPU)")
        write_record(a.record, None, figures, robots=a.robots, fused=bool(a.fused))


if __name__ == "__main__":
    main()
