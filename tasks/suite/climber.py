"""Climber-v2: climb up a narrow shaft; the robot sees the ceiling 3 voxels either side."""

from tasks import observations as O
from tasks.spec import Measure, TaskSpec


def reward(before: Measure, after: Measure):
    """Upward progress of the COM plus a fifth of the rightward progress."""
    d = after.com - before.com
    return d[:, 1] + d[:, 0] * 0.2


SPEC = TaskSpec(name="Climber-v2", world="Climber-v2.json", origin=(1, 1), paper_steps=400,
                evogym_steps=1000, observation=(O.VCOM, O.ORIENTATION, O.POINTS, O.ceiling_sight(3)),
                reward=reward, reads_points=False)
