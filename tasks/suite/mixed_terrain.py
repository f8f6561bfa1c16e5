"""Tasks whose terrain is one object mixing fixed (material 5) and soft voxels: the simulator runs
it as a free object whose fixed corners never move (tsim's fixed points), so its soft parts sag
and give under the robot.

BridgeWalker-v0: walk right over a soft bridge between fixed posts; +1 and the end past x = 60
voxels. CaveCrawler-v0: crawl right through a low cave with soft stalactites and a soft bump,
seeing the cave's floor and ceiling; +1 and the end past x = 69 voxels. Climber-v1: climb a
vertical pipe with soft wall patches; +1 and the end above y = 65 voxels.
"""

from __future__ import annotations

import numpy as np

from tasks import observations as O
from tasks.spec import Measure, TaskSpec
from tasks.suite._common import dx


def climb(before: Measure, after: Measure) -> np.ndarray:
    """Upward progress of the robot's COM."""
    return (after.com - before.com)[:, 1]


def top_of_pipe(before: Measure, after: Measure) -> tuple[np.ndarray, np.ndarray]:
    """+1 and the end once the COM is above y = 65 voxels (evogym writes 65 * 0.1)."""
    return np.ones(len(after.com)), after.com[:, 1] > 65 * 0.1


BRIDGE_WALKER = TaskSpec(
    name="BridgeWalker-v0", world="BridgeWalker-v0.json", origin=(2, 5), paper_steps=500,
    evogym_steps=500, observation=(O.VCOM, O.ORIENTATION, O.POINTS), reward=dx, goal=(60, 1.0))

CAVE_CRAWLER = TaskSpec(
    name="CaveCrawler-v0", world="CaveCrawler-v0.json", origin=(1, 2), paper_steps=1000,
    evogym_steps=1000,
    observation=(O.VCOM, O.POINTS, O.floor_sight(5, ("terrain",)),
                 O.ceiling_sight(5, ("terrain",))),
    reward=dx, goal=(69, 1.0))

CLIMBER_V1 = TaskSpec(
    name="Climber-v1", world="Climber-v1.json", origin=(1, 1), paper_steps=600, evogym_steps=600,
    observation=(O.VCOM, O.POINTS), reward=climb, termination=top_of_pipe)
