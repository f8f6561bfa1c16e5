"""evogym's robot-steps/s on given bodies, one core (run with the evogym venv of
shared/tools/setup_evogym.sh; imports nothing from sgr, so sgr never depends on evogym).

    python bench/evogym_body_speed.py BODIES.npy TASK STEPS

BODIES.npy is an (N, h, w) int array of evogym voxel codes. Every body gets a fresh env and the
same sinusoidal open-loop actions as `tasks.bench.sinusoid`; the first step (construction work)
is not timed. Prints robot-steps/s last.
"""

import sys
import time

import evogym.envs  # noqa: F401  (registers the tasks)
import gymnasium as gym
import numpy as np


def main() -> None:
    bodies = np.load(sys.argv[1], allow_pickle=False)
    task, steps = sys.argv[2], int(sys.argv[3])
    total_t, total_steps = 0.0, 0
    for body in bodies:
        env = gym.make(task, body=body)
        env.reset(seed=0)
        na = env.action_space.shape[0]
        phase = 2 * np.pi * np.arange(na) / max(na, 1)
        env.step(np.ones(na))
        t0 = time.perf_counter()
        for t in range(steps):
            _, _, term, _, _ = env.step(1.1 + 0.5 * np.sin(2 * np.pi * t / 20 + phase))
            total_steps += 1
            if term:
                break
        total_t += time.perf_counter() - t0
        env.close()
    print(f"{total_steps / total_t:.1f}")


if __name__ == "__main__":
    main()
