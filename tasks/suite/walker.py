"""Walker-v0: walk right on flat ground; +1 once the COM passes voxel x = 99."""

from tasks import observations as O
from tasks.spec import Measure, TaskSpec


def reward(before: Measure, after: Measure):
    """Rightward progress of the robot's COM."""
    return (after.com - before.com)[:, 0]


SPEC = TaskSpec(name="Walker-v0", world="Walker-v0.json", origin=(1, 1), paper_steps=500,
                evogym_steps=500, observation=(O.VCOM, O.POINTS), reward=reward, goal=(99, 1.0),
                reads_points=False)
