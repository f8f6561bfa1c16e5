"""Thrower-v0: throw the package (a free 3 x 2 soft block) to the right without walking away."""

import numpy as np

from tasks import observations as O
from tasks.spec import Measure, TaskSpec


def reward(before: Measure, after: Measure):
    """Rightward progress of the package, minus a quarter of the robot's rightward progress while
    the robot is right of x = 0 (plus it when left of it, as evogym's code does)."""
    penalty = (before.com[:, 0] - after.com[:, 0]) * 0.25
    penalty = np.where(after.com[:, 0] < 0, -penalty, penalty)
    return after.objects["package"][:, 0] - before.objects["package"][:, 0] + penalty


SPEC = TaskSpec(name="Thrower-v0", world="Thrower-v0.json", origin=(1, 1), paper_steps=300,
                evogym_steps=300,
                observation=(O.VCOM, O.object_offset("package"), O.object_vcom("package"), O.POINTS),
                reward=reward, tracked=("package",), reads_points=False)
