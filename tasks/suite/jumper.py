"""Jumper-v0: jump as high as possible in place, between two walls; the robot sees the floor 2
voxels either side."""

import numpy as np

from tasks import observations as O
from tasks.spec import Measure, TaskSpec


def reward(before: Measure, after: Measure):
    """Ten times the upward progress of the COM minus five times its sideways movement."""
    d = after.com - before.com
    return d[:, 1] * 10 - np.abs(d[:, 0]) * 5


SPEC = TaskSpec(name="Jumper-v0", world="Jumper-v0.json", origin=(32, 1), paper_steps=500,
                evogym_steps=500, observation=(O.VCOM, O.POINTS, O.floor_sight(2)), reward=reward,
                reads_points=False)
