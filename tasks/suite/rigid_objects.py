"""Tasks with a rigid free object: Lifter-v0 (lift a rigid 1x2 package out of a slot), Carrier-v1
(carry a rigid 3x2 package over a drop onto a table), Pusher-v1 (push a rigid 3x2 package behind
the robot to the right), BeamToppler-v0 (topple a rigid 10x2 beam off two pegs) and BeamSlider-v0
(slide a rigid 10x2 beam along five pegs)."""

import numpy as np

from tasks import observations as O
from tasks.spec import Measure, TaskSpec
from tasks.suite.carry_push import OBS as PACKAGE_OBS
from tasks.suite.carry_push import push


def lift(before: Measure, after: Measure):
    """Ten times the package's upward progress plus ten times how much its x distance to 0.55
    shrank; while the robot's COM is below y = 0.3, twenty times the robot's upward progress."""
    p0, p1 = before.objects["package"], after.objects["package"]
    r = (p1[:, 1] - p0[:, 1]) * 10 + (np.abs(0.55 - p0[:, 0]) - np.abs(0.55 - p1[:, 0])) * 10
    return np.where(after.com[:, 1] < 0.3, r + (after.com[:, 1] - before.com[:, 1]) * 20, r)


def carry_to_table(before: Measure, after: Measure):
    """How much the robot COM's x distance to 4.0 shrank; while the package is below y = t (t = 0.4
    right of x = 2.0, else 0.6), ten times its vertical progress."""
    p0, p1 = before.objects["package"], after.objects["package"]
    r = np.abs(4.0 - before.com[:, 0]) - np.abs(4.0 - after.com[:, 0])
    t = np.where(p1[:, 0] > 2.0, 0.4, 0.6)
    return np.where(p1[:, 1] < t, r + (p1[:, 1] - p0[:, 1]) * 10, r)


def topple(before: Measure, after: Measure):
    """How much the robot's x distance to the beam shrank, plus |dx| + 3 |dy| - 10 dy of the beam."""
    b0, b1 = before.objects["beam"], after.objects["beam"]
    r = np.abs(b0[:, 0] - before.com[:, 0]) - np.abs(b1[:, 0] - after.com[:, 0])
    d = b1 - b0
    return r + np.abs(d[:, 0]) + np.abs(d[:, 1]) * 3 - d[:, 1] * 10


def slide(before: Measure, after: Measure):
    """How much the robot's x distance to the beam shrank, plus the beam's rightward progress."""
    b0, b1 = before.objects["beam"], after.objects["beam"]
    r = np.abs(b0[:, 0] - before.com[:, 0]) - np.abs(b1[:, 0] - after.com[:, 0])
    return r + (b1[:, 0] - b0[:, 0])


def beam_left(before: Measure, after: Measure):
    """+1 and the episode ends once the beam's COM is left of x = 0.2."""
    return np.ones(len(after.com)), after.objects["beam"][:, 0] < 0.2


BEAM_OBS = (O.object_offset("beam"), O.VCOM, O.object_vcom("beam"), O.object_orientation("beam"),
            O.POINTS)

LIFTER = TaskSpec(name="Lifter-v0", world="Lifter-v0.json", origin=(2, 3), paper_steps=300,
                  evogym_steps=300,
                  observation=(O.VCOM, O.object_offset("package"), O.object_vcom("package"),
                               O.object_orientation("package"), O.POINTS),
                  reward=lift, tracked=("package",), reads_points=False)
CARRIER_V1 = TaskSpec(name="Carrier-v1", world="Carrier-v1.json", origin=(1, 4), paper_steps=1000,
                      evogym_steps=1000, observation=PACKAGE_OBS, reward=carry_to_table,
                      tracked=("package",), reads_points=False)
PUSHER_V1 = TaskSpec(name="Pusher-v1", world="Pusher-v1.json", origin=(13, 1), paper_steps=600,
                     evogym_steps=600, observation=PACKAGE_OBS, reward=push, tracked=("package",),
                     goal=(69, 1.0), reads_points=False)
BEAM_TOPPLER = TaskSpec(name="BeamToppler-v0", world="BeamToppler-v0.json", origin=(1, 1),
                        paper_steps=1000, evogym_steps=1000, observation=BEAM_OBS, reward=topple,
                        tracked=("beam",), termination=beam_left, reads_points=False)
BEAM_SLIDER = TaskSpec(name="BeamSlider-v0", world="BeamSlider-v0.json", origin=(1, 1),
                       paper_steps=1000, evogym_steps=1000, observation=BEAM_OBS, reward=slide,
                       tracked=("beam",), termination=beam_left, reads_points=False)
