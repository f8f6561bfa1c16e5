"""Episode returns of random robots on every task, on the arch of $SGR_ARCH (one arch per process:
Taichi cannot switch), for comparing a GPU with the same machine's CPU (device/gpu_check.sh).

    SGR_ARCH=cpu  python device/arch_returns.py --out cpu.json
    SGR_ARCH=cuda python device/arch_returns.py --out gpu.json
    SGR_ARCH=cuda python device/arch_returns.py --lanes 32 --out lanes.json   # the lanes kernel
    python device/arch_returns.py --compare cpu.json gpu.json     # exit 1 when a task differs

The CPU is validated against evogym's recorded data in CI; this checks that the GPU computes the
same physics: random 5x5 robots (fixed seed) with open-loop sinusoid actions, every task, returns
and final robot positions. A GPU may order float64 sums and fuse multiply-adds differently, so
chaotic episodes can drift apart over hundreds of steps; the comparison reports the median and
largest difference per task and fails on the median, as the evogym validation does.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

MEDIAN_TOL = 1e-9  # the CPU's median |return - evogym| is <= 7e-11 on every task


def record(robots: int, steps: int, seed: int, tasks: list[str] | None = None, lanes: int = 1) -> dict:
    """{task: {"returns": [...], "final_x": [...]}} on this process's arch (every task, or
    `tasks`); `lanes` > 1: on the lanes kernel (tsim/backend/lanes.py, GPU and Vulkan only)."""
    from tasks.bench import sinusoid
    from tasks.env import BatchEnv
    from tasks.specs import TASKS
    from tsim.backend import runtime
    from tsim.sampling import sample_robots

    arch = runtime.init()
    out: dict = {"arch": arch, "robots": robots, "steps": steps, "seed": seed, "lanes": lanes, "tasks": {}}
    for task in tasks or TASKS:
        rng = np.random.default_rng(seed)
        bodies = list(sample_robots(robots, (5, 5), rng))
        t0 = time.perf_counter()
        env = BatchEnv(task, bodies, episode_steps=steps)
        if lanes > 1:
            env.sim.choose_kernel(lanes=lanes)
        A = env.sim.max_actuators
        total = np.zeros(robots)
        for t in range(steps):
            _, r, term, trunc, _ = env.step(np.repeat(sinusoid(t, A)[None, :], robots, 0))
            total += r
            if np.all(term | trunc):
                break
        x = [float(env.sim.robot_pos(w)[0].mean()) for w in range(robots)]
        out["tasks"][task] = {"returns": total.tolist(), "final_x": x, "s": time.perf_counter() - t0}
    return out


def compare(a: dict, b: dict, tol: float = MEDIAN_TOL) -> tuple[list[str], list[str]]:
    """Per-task lines (median and max |difference| of returns and final x) and failures (a
    median |return difference| above `tol`)."""
    lines, bad = [], []
    for task, ra in a["tasks"].items():
        rb = b["tasks"].get(task)
        if rb is None:
            bad.append(f"{task}: missing on {b['arch']}")
            continue
        d = np.abs(np.array(ra["returns"]) - np.array(rb["returns"]))
        dx = np.abs(np.array(ra["final_x"]) - np.array(rb["final_x"]))
        lines.append(f"{task:24s} |return diff| median {np.median(d):.2e} max {d.max():.2e}   "
                     f"|final x diff| median {np.median(dx):.2e} max {dx.max():.2e}")
        if not np.median(d) <= tol:
            bad.append(f"{task}: median |return difference| {np.median(d):.3g} > {tol:g}")
    return lines, bad


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--robots", type=int, default=16)
    p.add_argument("--steps", type=int, default=200)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--tasks", nargs="+", help="these tasks only (default: all 32)")
    p.add_argument("--lanes", type=int, default=1, help="lanes per world: > 1 runs the lanes kernel "
                   "(tsim/backend/lanes.py; GPU and Vulkan only)")
    p.add_argument("--out", help="write the record (JSON) here")
    p.add_argument("--compare", nargs=2, metavar="JSON", help="compare two records instead")
    p.add_argument("--tol", type=float, default=MEDIAN_TOL,
                   help=f"largest median |return difference| per task (default {MEDIAN_TOL:g})")
    args = p.parse_args()
    if args.compare:
        a, b = (json.loads(Path(f).read_text()) for f in args.compare)
        lines, bad = compare(a, b, args.tol)
        print(f"{a['arch']} against {b['arch']}: {a['robots']} robots x {a['steps']} steps per task")
        print("\n".join(lines))
        same = all(a["tasks"][t] == {**b["tasks"][t], "s": a["tasks"][t]["s"]} for t in a["tasks"]
                   if t in b["tasks"])
        print(f"bits: {'every return and final x identical' if same else 'not identical'}")
        print("FAILED: " + "; ".join(bad) if bad else f"{b['arch']} matches {a['arch']} on every task "
              f"(median |return difference| <= {args.tol:g})")
        return 1 if bad else 0
    rec = record(args.robots, args.steps, args.seed, args.tasks, args.lanes)
    text = json.dumps(rec)
    if args.out:
        Path(args.out).write_text(text)
    else:
        print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
