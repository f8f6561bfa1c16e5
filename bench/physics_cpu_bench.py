"""Physics robot-steps per CPU second on one Taichi thread, in this process's precision (not run by CI).

    SGR_PRECISION=f32 python bench/physics_cpu_bench.py [--size 5] [--robots 64] [--steps 200]

Walker-v0, `--robots` random n x n bodies (seed 0), sinusoidal actions, `BatchSim.step` only (no
observations or rewards), compilation excluded. Prints one JSON line: robot-steps per CPU second of
this process (`time.process_time`) and per wall-clock second. Why CPU time: on a machine shared with
other jobs, wall-clock figures of the same run vary by 2x (docs/BENCHMARKS.md), while a process's
own CPU time is only disturbed through shared caches and cores; run builds side by side,
alternating, and compare medians.
"""

from __future__ import annotations

import argparse
import json
import os
import time

os.environ["SGR_THREADS"] = "1"  # before Taichi starts (at the imports below)

import numpy as np  # noqa: E402

from tasks.bench import sinusoid  # noqa: E402
from tasks.env import BatchEnv  # noqa: E402
from tsim.backend import runtime  # noqa: E402
from tsim.sampling import sample_robots  # noqa: E402


def main() -> None:
    """Time `--steps` physics steps of `--robots` random bodies and print the rates."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=5)
    ap.add_argument("--robots", type=int, default=64)
    ap.add_argument("--steps", type=int, default=200)
    a = ap.parse_args()
    rng = np.random.default_rng(0)
    bodies = list(sample_robots(a.robots, (a.size, a.size), rng))
    env = BatchEnv("Walker-v0", bodies, episode_steps=a.steps + 1)
    n_act = env.sim.max_actuators
    env.step(np.ones((a.robots, n_act)))  # compiles the kernel (or loads it from Taichi's cache)
    acts = [sinusoid(t, n_act)[None, :].repeat(a.robots, 0) for t in range(a.steps)]
    c0, w0 = time.process_time(), time.perf_counter()
    for t in range(a.steps):
        env.sim.set_actions(acts[t])
        env.sim.step()
    c1, w1 = time.process_time(), time.perf_counter()
    n = a.robots * a.steps
    print(json.dumps({"precision": runtime.precision(), "size": a.size, "robots": a.robots,
                      "steps": a.steps, "cpu_robot_steps_per_s": round(n / (c1 - c0)),
                      "wall_robot_steps_per_s": round(n / (w1 - w0))}))


if __name__ == "__main__":
    main()
