"""evogym's spread under +-1e-5 and +-1e-4 action changes, beside its recorded +-1e-6 one (not run by CI).

    SGR_THREADS=1 python studies/perturbed_spread.py OUT.json     # ~6 minutes on 2 shared cores

evogym32 records its reruns at +-1e-9 and +-1e-6 only. Our f64 reproduces evogym's runs to ~1e-14,
so it stands in for evogym here. Per task of tests/data/evogym32 and per d: the median over the 24
robots of the larger of the +d and -d reruns' largest COM deviation over the episode from
evogym's recorded run (as `parity.harness.chaos_check`'s floor), all reruns of a task in one batch.
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np

from tasks.env import BatchEnv
from tasks.specs import TASKS
from tsim.backend import runtime

FOLDER = "tests/data/evogym32"
DELTAS = (1e-5, -1e-5, 1e-4, -1e-4)


def spread(task: str) -> dict:
    """{"floor_1e-5": ..., "floor_1e-4": ...} of one task."""
    z = np.load(f"{FOLDER}/returns_{task}.npz", allow_pickle=False)
    bodies, n_act, steps = list(z["body"]), z["n_act"], int(z["steps"])
    B, K = len(bodies), len(DELTAS)
    seeds = [int(s) for s in z["reset_seed"]] * K if "reset_seed" in z.files else None
    env = BatchEnv(task, bodies * K, episode_steps=steps, passive_ok=True, seeds=seeds)
    com = np.full((K * B, steps + 1, 2), np.nan)
    com[:, 0] = env.sim.robot_com()
    acts = z["actions"]
    for t in range(steps):
        live = ~env.terminated
        _, _, term, _, _ = env.step([acts[i % B, t, :n_act[i % B]] + DELTAS[i // B] for i in range(K * B)])
        com[live, t + 1] = env.sim.robot_com()[live]
        if term.all():
            break
    run = z["steps_run"]
    dev = np.array([[np.nanmax(np.linalg.norm(com[k * B + i, :run[i] + 1] - z["com"][i, :run[i] + 1], axis=1))
                     for i in range(B)] for k in range(K)])
    return {"floor_1e-5": float(np.median(np.maximum(dev[0], dev[1]))),
            "floor_1e-4": float(np.median(np.maximum(dev[2], dev[3])))}


def main() -> None:
    runtime.init(precision="f64")
    index = json.load(open(f"{FOLDER}/index.json"))
    out = {}
    for task in [t for t in index["all_tasks"] if t in TASKS]:
        t0 = time.time()
        out[task] = spread(task)
        print(task, out[task], f"{time.time() - t0:.1f}s", flush=True)
    if len(sys.argv) > 1:
        with open(sys.argv[1], "w") as f:
            json.dump(out, f, indent=1)


if __name__ == "__main__":
    main()
