"""Climber-v0: climb a closed vertical pipe 5 voxels wide; +1 and the episode ends once the COM
is above y = 8.6 (world units)."""

import numpy as np

from tasks import observations as O
from tasks.spec import Measure, TaskSpec


def reward(before: Measure, after: Measure):
    """Upward progress of the robot's COM."""
    return (after.com - before.com)[:, 1]


def termination(before: Measure, after: Measure):
    """+1 and the end once the COM is above y = 8.6 (the top of the pipe)."""
    return np.ones(len(after.com)), after.com[:, 1] > 8.6


SPEC = TaskSpec(name="Climber-v0", world="Climber-v0.json", origin=(1, 1), paper_steps=400,
                evogym_steps=400, observation=(O.VCOM, O.POINTS), reward=reward,
                termination=termination)
