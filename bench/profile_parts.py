"""Where an env step's time goes: each kernel part's share, measured by compiling it out.

    python bench/profile_parts.py [--cases 5x128 5x16 12x16] [--steps 50] [--repeats 3]

Case NxB: B random N x N bodies (seed 0) on Walker-v0, one Taichi thread. For every part the step
kernel is compiled without it (SGR_PROFILE_SKIP, in a fresh process without Taichi's offline cache)
and the share is 1 - t_without / t_with of the kernel's time per env step. Leaving a part out
changes the motion (no contacts, no constraints), so shares are estimates: they stay within a few
per cent over repeats. "python" is the env step's time outside `BatchSim.step` (observations,
rewards, actions, the kernel call's argument handling). Medians over --repeats processes.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

PARTS = {
    "pairs": "robot self and object contact pairs (box tests, exact tests, forces)",
    "terrain": "robot-terrain contacts (grid cells, exact tests, forces)",
    "contacts": "all contacts, AABBs included",
    "constraints": "edge and rigid-voxel constraint passes",
}


def child(size: int, robots: int, steps: int) -> dict:
    """Seconds per env step: the whole step and `BatchSim.step` inside it."""
    import numpy as np

    from tasks.bench import sinusoid
    from tasks.env import BatchEnv
    from tsim.sampling import sample_robots

    rng = np.random.default_rng(0)
    bodies = list(sample_robots(robots, (size, size), rng))
    env = BatchEnv("Walker-v0", bodies, episode_steps=steps + 2)
    A = env.sim.max_actuators
    env.step(np.ones((robots, A)))
    inner = [0.0]
    step = env.sim.step

    def timed() -> None:
        t = time.perf_counter()
        step()
        inner[0] += time.perf_counter() - t

    env.sim.step = timed
    acts = [sinusoid(t, A)[None, :].repeat(robots, 0) for t in range(steps)]
    t0 = time.perf_counter()
    for t in range(steps):
        env.step(acts[t])
    wall = time.perf_counter() - t0
    return {"step_s": wall / steps, "kernel_s": inner[0] / steps}


def measure(size: int, robots: int, steps: int, skip: str) -> dict:
    env = {**os.environ, "SGR_THREADS": "1", "SGR_PROFILE_SKIP": skip}
    out = subprocess.run([sys.executable, __file__, "--child", str(size), str(robots), str(steps)],
                         env=env, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", nargs="+", default=["5x128", "5x16", "12x16"])
    ap.add_argument("--steps", type=int, default=50)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--child", nargs=3, type=int, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        print(json.dumps(child(*args.child)))
        return
    for case in args.cases:
        size, robots = (int(x) for x in case.split("x"))
        runs = {skip: [measure(size, robots, args.steps, skip) for _ in range(args.repeats)]
                for skip in ["", *PARTS]}
        base_k = statistics.median(r["kernel_s"] for r in runs[""])
        base_s = statistics.median(r["step_s"] for r in runs[""])
        py = statistics.median(r["step_s"] - r["kernel_s"] for r in runs[""])
        print(f"{size}x{size}, {robots} robots: {base_s * 1e3:.2f} ms per env step "
              f"({robots / base_s:.0f} robot-steps/s), {base_k / robots / 30 * 1e6:.2f} us per "
              f"robot-substep in the kernel")
        for skip, what in PARTS.items():
            k = statistics.median(r["kernel_s"] for r in runs[skip])
            print(f"  {skip:<12} {100 * (1 - k / base_k):5.1f} % of the kernel  ({what})")
        print(f"  {'python':<12} {100 * py / base_s:5.1f} % of the env step "
              f"({py * 1e3:.2f} ms per step)")


if __name__ == "__main__":
    main()
