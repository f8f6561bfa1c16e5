"""Carrier-v0 (carry the soft 3x2 package that starts on top of the robot) and Pusher-v0 (push
the soft 3x2 package lying ahead) to the right; +1 once the robot's COM passes voxel x = 99."""

import numpy as np

from tasks import observations as O
from tasks.spec import Measure, TaskSpec

OBS = (O.VCOM, O.object_offset("package"), O.object_vcom("package"), O.POINTS)


def carry(before: Measure, after: Measure):
    """Half the package's and half the robot's rightward progress; while the package is below
    y = 0.3 (dropped), ten times its vertical progress."""
    p0, p1 = before.objects["package"], after.objects["package"]
    r = (p1[:, 0] - p0[:, 0]) * 0.5 + (after.com[:, 0] - before.com[:, 0]) * 0.5
    return np.where(p1[:, 1] < 0.3, r + (p1[:, 1] - p0[:, 1]) * 10, r)


def push(before: Measure, after: Measure):
    """0.75 x the package's and 0.5 x the robot's rightward progress, plus how much their x
    distance shrank; while the package is below y = 0, ten times its vertical progress."""
    p0, p1 = before.objects["package"], after.objects["package"]
    c0, c1 = before.com, after.com
    r = (p1[:, 0] - p0[:, 0]) * 0.75 + (c1[:, 0] - c0[:, 0]) * 0.5
    r = r + (np.abs(c0[:, 0] - p0[:, 0]) - np.abs(c1[:, 0] - p1[:, 0]))
    return np.where(p1[:, 1] < 0.0, r + (p1[:, 1] - p0[:, 1]) * 10, r)


CARRIER = TaskSpec(name="Carrier-v0", world="Carrier-v0.json", origin=(1, 1), paper_steps=500,
                   evogym_steps=500, observation=OBS, reward=carry, tracked=("package",),
                   goal=(99, 1.0), reads_points=False)
PUSHER = TaskSpec(name="Pusher-v0", world="Pusher-v0.json", origin=(1, 1), paper_steps=500,
                  evogym_steps=500, observation=OBS, reward=push, tracked=("package",),
                  goal=(99, 1.0), reads_points=False)
