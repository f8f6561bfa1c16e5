"""Traverser-v0: walk right from a raised ledge across a pit filled with 27 loose rigid blocks
(added in code, as evogym's task does) to a lower ledge; the robot sees the floor 5 voxels either
side, over the ground and every block as they move; +2 and the end past x = 59 voxels."""

from __future__ import annotations

from tasks import observations as O
from tasks.spec import AddedObject, TaskSpec
from tasks.suite._common import dx

# (cell x, cell y, side) of each block in evogym's order: block_k is the k-th
BLOCKS: tuple[tuple[int, int, int], ...] = (
    (20, 1, 3), (24, 1, 3), (27, 1, 2), (31, 1, 3), (34, 1, 3), (38, 1, 2), (41, 1, 3), (45, 1, 3),
    (21, 4, 3), (24, 4, 2), (26, 4, 1), (29, 4, 2), (31, 4, 3), (34, 4, 2), (36, 4, 2), (40, 4, 3),
    (43, 4, 2), (46, 4, 3),
) + tuple((x, 7, 2) for x in range(20, 45, 3))

OBJECTS = tuple(AddedObject(f"block_{k}", f"rigid_{n}x{n}.json", (x, y))
                for k, (x, y, n) in enumerate(BLOCKS))
SIGHT = ("ground",) + tuple(o.name for o in OBJECTS)

SPEC = TaskSpec(
    name="Traverser-v0", world="Traverser-v0.json", origin=(1, 9), paper_steps=600,
    evogym_steps=600,
    observation=(O.VCOM, O.ORIENTATION, O.POINTS, O.floor_sight(5, SIGHT)),
    reward=dx, goal=(59, 2.0), objects=OBJECTS, reads_points=False)
