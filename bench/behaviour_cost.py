"""What recording behaviour features costs (tasks/behaviour.py): one batch of random 5x5 robots driven
by a sinusoid over the task's episode, with and without `record=True`, alternated, in one process
with one Taichi thread. Prints robot-steps per second of each and the recording's share of the time.

    python bench/behaviour_cost.py                          # Walker-v0, Climber-v2, UpStepper-v0, 64 robots
    python bench/behaviour_cost.py --robots 128 --repeats 5
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("SGR_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


class Sine:
    """Every actuator at 1.1 + 0.4 sin(2 pi 4 Hz t)."""

    def __init__(self, env):
        self.env, self.t = env, 0

    def act(self, obs: np.ndarray) -> np.ndarray:
        self.t += 1
        v = 1.1 + 0.4 * math.sin(2 * math.pi * 4.0 * self.t * 0.003)
        return np.full((self.env.n_worlds, self.env.sim.max_actuators), v)


def main() -> None:
    from evolve.rollout.episodes import rollout_policy
    from tasks.env import BatchEnv
    from tsim.sampling import sample_robots

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", nargs="+", default=["Walker-v0", "Climber-v2", "UpStepper-v0"])
    ap.add_argument("--robots", type=int, default=64)
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    bodies = list(sample_robots(a.robots, (5, 5), np.random.default_rng(0)))
    print(f"{'task':14s} {'robots':>6s} {'plain steps/s':>14s} {'recorded steps/s':>17s} {'cost':>6s}")
    for task in a.tasks:
        steps = BatchEnv(task, bodies[:1]).episode_steps
        rollout_policy(task, bodies, Sine, record=True)  # warm-up: the kernels compile
        times = {False: [], True: []}
        for _ in range(a.repeats):
            for record in (False, True):
                t0 = time.perf_counter()
                rollout_policy(task, bodies, Sine, record=record)
                times[record].append(time.perf_counter() - t0)
        plain, rec = min(times[False]), min(times[True])
        print(f"{task:14s} {a.robots:6d} {a.robots * steps / plain:14,.0f} {a.robots * steps / rec:17,.0f} "
              f"{100 * (rec - plain) / plain:5.1f}%", flush=True)


if __name__ == "__main__":
    main()
