"""Tasks whose terrain is one object mixing fixed (material 5) and soft voxels: the simulator runs
it as a free object whose fixed corners never move (tsim's fixed points), so its soft parts sag
and give under the robot.

BridgeWalker-v0: walk right over a soft bridge between fixed posts; +1 and the end past x = 60
voxels. CaveCrawler-v0: crawl right through a low cave with soft stalactites and a soft bump,
seeing the cave's floor and ceiling; +1 and the end past x = 69 voxels. Climber-v1: climb a
vertical pipe with soft wall patches; +1 and the end above y = 65 voxels.
"""

from __future__ import annotations

from tasks import observations as O
from tasks.spec import TaskSpec
from tasks.suite._common import dx, dy, reached_height

climb = dy  # upward progress of the robot's COM
top_of_pipe = reached_height(65 * 0.1)  # +1 and the end above y = 65 voxels, as evogym writes it


BRIDGE_WALKER = TaskSpec(
    name="BridgeWalker-v0", world="BridgeWalker-v0.json", origin=(2, 5), paper_steps=500,
    evogym_steps=500, observation=(O.VCOM, O.ORIENTATION, O.POINTS), reward=dx, goal=(60, 1.0),
    reads_points=False)

CAVE_CRAWLER = TaskSpec(
    name="CaveCrawler-v0", world="CaveCrawler-v0.json", origin=(1, 2), paper_steps=1000,
    evogym_steps=1000,
    observation=(O.VCOM, O.POINTS, O.floor_sight(5, ("terrain",)),
                 O.ceiling_sight(5, ("terrain",))),
    reward=dx, goal=(69, 1.0), reads_points=False)

CLIMBER_V1 = TaskSpec(
    name="Climber-v1", world="Climber-v1.json", origin=(1, 1), paper_steps=600, evogym_steps=600,
    observation=(O.VCOM, O.POINTS), reward=climb, termination=top_of_pipe, reads_points=False)
