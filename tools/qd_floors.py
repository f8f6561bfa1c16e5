"""Write evolve/methods/qd_floors.py: each task's floor, the default offset of map-elites' QD score.

A task's return has no lower bound one can derive (most rewards are the COM's progress, which
physics bounds but no formula does), so the floor is measured: the lowest return of random robots
(64 random 5x5 bodies from evogym's distribution, each driven by uniform random actions, seeded)
over the task's default episode, rounded down to a tenth, and never above 0. Run from the
repository's root:

    python tools/qd_floors.py        # ~5 min on 2 cores
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from evolve.rollout.episodes import rollout_policy  # noqa: E402
from tasks.specs import BUILTIN  # noqa: E402
from tsim import constants as C  # noqa: E402
from tsim.sampling import sample_robots  # noqa: E402

OUT = ROOT / "evolve" / "methods" / "qd_floors.py"
ROBOTS, SEED = 64, 0


class RandomActions:
    """Uniform random actions in evogym's range, from one seeded generator."""

    def __init__(self, env, seed: int):
        self.shape = (env.n_worlds, env.sim.max_actuators)
        self.rng = np.random.default_rng(seed)

    def act(self, obs: np.ndarray) -> np.ndarray:
        return self.rng.uniform(C.ACTION_MIN, C.ACTION_MAX, self.shape)


def floor_of(task: str) -> tuple[float, float]:
    """(floor, the lowest return seen) of `task`."""
    bodies = list(sample_robots(ROBOTS, (5, 5), np.random.default_rng(SEED)))
    returns = rollout_policy(task, bodies, lambda env: RandomActions(env, SEED))
    low = float(np.min(returns))
    return min(0.0, math.floor(low * 10) / 10), low


def main() -> None:
    rows = []
    for task in sorted(BUILTIN):
        floor, low = floor_of(task)
        rows.append((task, floor, low))
        print(f"{task:28s} floor {floor:6.1f}  (lowest random return {low:.4f})", flush=True)
    lines = ['"""Each task\'s floor: the default `qd.score_offset` of map-elites (written by',
             'tools/qd_floors.py; do not edit).',
             "",
             "The lowest return of 64 random 5x5 robots driven by uniform random actions over the",
             "task's default episode, rounded down to a tenth and never above 0. An elite adds",
             "max(0, fitness - floor) to the QD score, so the score never falls as elites are added.",
             '"""', "", "FLOORS: dict[str, float] = {"]
    lines += [f"    {task!r}: {floor!r},  # lowest random return {low:.4f}" for task, floor, low in rows]
    lines += ["}", ""]
    OUT.write_text("\n".join(lines))
    print(f"wrote {OUT.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
