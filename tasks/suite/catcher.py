"""Catcher-v0: catch a soft 3x2 package that falls from high up, bouncing off two fixed pegs, and
keep it from dropping; the package and pegs are added in code and placed anew at every reset.

Placement: evogym draws `offsetx = randint(-6, 4)`, then `offsety = randint(0, 5)` from Python's
global `random` at construction and at every reset (its `reset(seed=)` seeds nothing) and rebuilds
the world. We draw the same two calls from each world's own `random.Random` stream at every reset
of that world (task state `offset`), so a world seeded with s gets the placement evogym uses after
`random.seed(s); env.reset()` (its first episode): the recorded cases are replayed this way. The
pegs (all fixed) differ between the worlds of a batch, so they are simulated objects whose points
are all fixed rather than shared terrain.

Reward: how much the x distance between the robot's and the package's COMs shrank; while the
package is below y = 0.5, plus ten times its vertical progress. Only instability ends an episode.
"""

from __future__ import annotations

import random

import numpy as np

from tasks import observations as O
from tasks.spec import AddedObject, Measure, TaskSpec

# grid cells with offset (0, 0); the drawn offset is added to each
CELLS = {"package": (21, 41), "peg1": (17, 39), "peg2": (19, 25)}
OBJECTS = (AddedObject("package", "package.json", CELLS["package"], per_world=True),
           AddedObject("peg1", "peg.json", CELLS["peg1"], per_world=True),
           AddedObject("peg2", "peg.json", CELLS["peg2"], per_world=True))


def draw_offset(rng: random.Random) -> dict[str, np.ndarray]:
    """One episode's placement offset (voxels), drawn as evogym draws it."""
    ox = rng.randint(-6, 4)
    oy = rng.randint(0, 5)
    return {"offset": np.array([ox, oy], dtype=np.int64)}


def placement(state: dict[str, np.ndarray]) -> dict[str, tuple[int, int]]:
    """Cells of the package and both pegs for one world's drawn offset."""
    ox, oy = (int(v) for v in state["offset"])
    return {name: (x + ox, y + oy) for name, (x, y) in CELLS.items()}


def reward(before: Measure, after: Measure) -> np.ndarray:
    """Shrinking x distance between robot and package; below y = 0.5, ten times the package's
    vertical progress on top."""
    p0, p1 = before.objects["package"], after.objects["package"]
    r = np.abs(before.com[:, 0] - p0[:, 0]) - np.abs(after.com[:, 0] - p1[:, 0])
    return np.where(p1[:, 1] < 5.0 * 0.1, r + 10 * (p1[:, 1] - p0[:, 1]), r)


SPEC = TaskSpec(
    name="Catcher-v0", world="Walker-v0.json", origin=(22, 1), paper_steps=400, evogym_steps=400,
    observation=(O.object_offset("package"), O.VCOM, O.object_vcom("package"),
                 O.object_orientation("package"), O.POINTS),
    reward=reward, tracked=("package",), state=draw_offset, objects=OBJECTS, placement=placement,
    reads_points=False)
