"""ObstacleTraverser-v1: cross rough terrain to the right; +2 once the COM passes voxel x = 59.
The robot sees the floor 5 voxels either side."""

from tasks import observations as O
from tasks.spec import Measure, TaskSpec


def reward(before: Measure, after: Measure):
    """Rightward progress of the robot's COM."""
    return (after.com - before.com)[:, 0]


SPEC = TaskSpec(name="ObstacleTraverser-v1", world="ObstacleTraverser-v1.json", origin=(2, 4),
                paper_steps=600, evogym_steps=1000,
                observation=(O.VCOM, O.ORIENTATION, O.POINTS, O.floor_sight(5)),
                reward=reward, goal=(59, 2.0), reads_points=False)
