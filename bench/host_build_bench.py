"""Host costs of a batch (issue 48): sampling bodies, building a `BatchEnv`, and `BatchEnv.step`'s
own host work, in microseconds per robot.

    python bench/host_build_bench.py [--sizes 1024 8192 65536] [--old-max 8192] [--task Walker-v0]
                                     [--step-size 8192] [--steps 10]

- sample: `sample_robots(B, (5, 5), rng)`; "old" beside it is B calls of `sample_robot` (the same
  bodies), run only for B <= --old-max.
- build: `BatchEnv(task, matrices)` from B sampled 5x5 matrices; "first" is the first build of that
  size in this process (fresh memory: page faults included), "again" the best of two more. "old
  bodies" is today's one-body-at-a-time topology (`tsim.body._build`, no cache) for the same
  matrices, B <= --old-max. On a tree without `sample_robots` (before issue 48) the script falls
  back to `sample_robot` and times that tree's `BatchEnv`: run it with PYTHONPATH on the old tree
  for the old figures side by side.
- step: `BatchEnv.step`'s host work at B = --step-size: the step with the physics kernel replaced
  by nothing (observations, rewards, termination and action handling only), per robot-step, on
  the kernel path (`tasks/kernels.py`, the default at that size) and the numpy path beside it
  (`fused=False`; a tree before issue 48 item 2 has only that one); "dropped" lets each step's
  returned arrays go, "kept" keeps them all (then every step's observation is fresh memory).

Wall and CPU (process) times are both printed: on a shared machine the CPU time is the steadier.
"""

from __future__ import annotations

import argparse
import gc
import json
import platform
import subprocess
import time

import numpy as np


def cpu_model() -> str:
    """The CPU's model name (lscpu), or the platform's processor string."""
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True, check=True).stdout
        for line in out.splitlines():
            if line.startswith("Model name:"):
                return line.split(":", 1)[1].strip()
    except (OSError, subprocess.CalledProcessError):
        pass
    return platform.processor() or "unknown"


def timed(fn) -> tuple[float, float, object]:  # noqa: ANN001
    """(wall s, cpu s, result) of one call."""
    gc.collect()
    w, c = time.perf_counter(), time.process_time()
    out = fn()
    return time.perf_counter() - w, time.process_time() - c, out


def sample(n: int, rng: np.random.Generator) -> np.ndarray:
    """n valid 5x5 bodies: batched where this tree has it, else one call per body."""
    try:
        from tsim.sampling import sample_robots
    except ImportError:
        from tsim.sampling import sample_robot
        return np.stack([sample_robot((5, 5), rng) for _ in range(n)])
    return sample_robots(n, (5, 5), rng)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[1024, 8192, 65536])
    ap.add_argument("--old-max", type=int, default=8192, help="largest B for the old paths")
    ap.add_argument("--task", default="Walker-v0")
    ap.add_argument("--step-size", type=int, default=8192, help="B for the host step figure (0: skip)")
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--json", help="also write the figures here")
    ap.add_argument("--record", metavar="PATH", help="also write a record (tasks/records.py)")
    a = ap.parse_args()

    from tasks.env import BatchEnv
    from tsim.body import _build, full_connectivity
    from tsim.sampling import sample_robot

    out: dict = {"cpu": cpu_model(), "task": a.task, "sizes": {}}
    print(f"CPU: {out['cpu']}; task {a.task}; us per robot (wall / cpu)")
    BatchEnv(a.task, list(sample(4, np.random.default_rng(1))), episode_steps=5)  # imports, specs
    for B in a.sizes:
        row: dict = {}
        w, c, mats = timed(lambda B=B: sample(B, np.random.default_rng(0)))
        row["sample"] = (w / B * 1e6, c / B * 1e6)
        if B <= a.old_max:
            rng = np.random.default_rng(0)
            w, c, old = timed(lambda B=B, rng=rng: np.stack([sample_robot((5, 5), rng) for _ in range(B)]))
            assert np.array_equal(old, mats), "the batched sampler drew other bodies"
            row["sample_old"] = (w / B * 1e6, c / B * 1e6)
        bodies = list(mats)
        w, c, env = timed(lambda bodies=bodies: BatchEnv(a.task, bodies, episode_steps=5))
        row["build_first"] = (w / B * 1e6, c / B * 1e6)
        del env
        again = []
        for _ in range(2):
            w, c, env = timed(lambda bodies=bodies: BatchEnv(a.task, bodies, episode_steps=5))
            again.append((w / B * 1e6, c / B * 1e6))
            del env
        row["build_again"] = min(again)
        if B <= a.old_max:
            w, c, _ = timed(lambda mats=mats: [_build(m, full_connectivity(m)) for m in mats])
            row["old_bodies"] = (w / B * 1e6, c / B * 1e6)
        out["sizes"][B] = row
        print(f"B = {B:>6}: " + "; ".join(f"{k} {v[0]:.2f} / {v[1]:.2f}" for k, v in row.items()), flush=True)

    if a.step_size:
        B = a.step_size
        bodies = list(sample(B, np.random.default_rng(0)))
        out["step_host"] = {"B": B}
        for path, fused in (("kernels", True), ("numpy", False)):
            try:
                env = BatchEnv(a.task, bodies, episode_steps=2 * a.steps + 2, fused=fused)
            except TypeError:  # a tree before issue 48 item 2: numpy only
                if not fused:
                    continue
                path, env = "numpy", BatchEnv(a.task, bodies, episode_steps=2 * a.steps + 2)
            env.sim.step = lambda n=1: None  # the host's share alone: no physics
            acts = np.full((B, env.sim.max_actuators), 1.1)
            env.step(acts)

            def discard(env=env, acts=acts) -> None:
                for _ in range(a.steps):
                    env.step(acts)

            # "dropped": the caller lets each step's arrays go (their memory is reused); "kept": it
            # keeps every step's (fresh memory each step, which this VM maps slowly)
            w, c, _ = timed(discard)
            row = {"dropped": (w / (B * a.steps) * 1e6, c / (B * a.steps) * 1e6)}
            w, c, _ = timed(lambda env=env, acts=acts: [env.step(acts) for _ in range(a.steps)])
            row["kept"] = (w / (B * a.steps) * 1e6, c / (B * a.steps) * 1e6)
            out["step_host"][path] = row
            print(f"BatchEnv.step host work at B = {B}, {path}: " +
                  "; ".join(f"{k} {v[0]:.3f} / {v[1]:.3f}" for k, v in row.items()) +
                  " us per robot-step (wall / cpu)", flush=True)
            del env
    if a.json:
        with open(a.json, "w") as f:
            json.dump(out, f, indent=1)
    if a.record:
        from tasks.records import figure, write_record

        figures = {f"{k}-{B}": figure(round(v[1], 2), "us per robot (CPU)")
                   for B, row in out["sizes"].items() for k, v in row.items()}
        step = out.get("step_host", {})
        for path in ("kernels", "numpy"):
            if path in step:  # the caller drops each step's arrays, as an env loop does
                figures[f"step_host_{path}-{step['B']}"] = figure(round(step[path]["dropped"][1], 3),
                                                                   "us per robot-step (CPU)")
        write_record(a.record, None, figures, task=a.task)


if __name__ == "__main__":
    main()
