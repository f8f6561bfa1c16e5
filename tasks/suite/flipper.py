"""Flipper-v0: flip over (turn) as often as possible on flat ground; the episode ends once the COM
is left of x = 0.1 (no penalty). Observation: orientation and points, no velocity.

Task state: a flip counter per world, reset with the world. The reward is the change of the
orientation unwrapped by it: a step from below pi/3 to above 5 pi/3 is one flip back, from above
5 pi/3 to below pi/3 one flip forward.
"""

import math

import numpy as np

from tasks import observations as O
from tasks.spec import Measure, TaskSpec


def reward(before: Measure, after: Measure):
    """Change of the orientation unwrapped by a flip counter: crossing 0 / 2 pi counts a whole turn,
    so the return measures how far the robot rolled, not its final angle."""
    o0, o1 = before.orientation, after.orientation
    flips = after.state["flips"]
    f0 = flips.copy()
    flips -= (o0 < math.pi / 3) & (o1 > 5 * math.pi / 3)
    flips += (o0 > 5 * math.pi / 3) & (o1 < math.pi / 3)
    return (o1 + flips * 2 * math.pi) - (o0 + f0 * 2 * math.pi)


def no_flips(rng) -> dict:
    """Task state at reset: no flips counted yet."""
    return {"flips": np.int64(0)}


def termination(before: Measure, after: Measure):
    """The episode ends (no penalty) when the COM leaves the ground's left end (x < 0.1)."""
    return np.zeros(len(after.com)), after.com[:, 0] < 0.1


SPEC = TaskSpec(name="Flipper-v0", world="Flipper-v0.json", origin=(60, 1), paper_steps=600,
                evogym_steps=600, observation=(O.ORIENTATION, O.POINTS), reward=reward,
                termination=termination, state=no_flips)
