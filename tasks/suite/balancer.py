"""Balancer-v0 and v1: balance on top of a 1-wide post (v0: start on it; v1: start beside it and
climb it). Observation: orientation and points, no velocity."""

import numpy as np

from tasks import observations as O
from tasks.spec import Measure, TaskSpec


def approach(x: float, y: float):
    """Reward: how much the COM's distances to x and to y (world units) shrank in the step."""
    def reward(before: Measure, after: Measure):
        c0, c1 = before.com, after.com
        return (np.abs(x - c0[:, 0]) - np.abs(x - c1[:, 0])) + (np.abs(y - c0[:, 1]) - np.abs(y - c1[:, 1]))
    return reward


SPEC_V0 = TaskSpec(name="Balancer-v0", world="Balancer-v0.json", origin=(15, 3), paper_steps=600,
                   evogym_steps=600, observation=(O.ORIENTATION, O.POINTS), reward=approach(1.7, 0.5),
                   reads_points=False)
SPEC_V1 = TaskSpec(name="Balancer-v1", world="Balancer-v1.json", origin=(10, 1), paper_steps=600,
                   evogym_steps=600, observation=(O.ORIENTATION, O.POINTS), reward=approach(1.75, 0.6),
                   reads_points=False)
