"""Climber-v0: climb a closed vertical pipe 5 voxels wide; +1 and the episode ends once the COM
is above y = 8.6 (world units)."""

from tasks import observations as O
from tasks.spec import TaskSpec
from tasks.suite._common import dy, reached_height

reward = dy  # upward progress of the robot's COM
termination = reached_height(8.6)  # +1 and the end at the top of the pipe (evogym: 86 * 0.1 = 8.6)

SPEC = TaskSpec(name="Climber-v0", world="Climber-v0.json", origin=(1, 1), paper_steps=400,
                evogym_steps=400, observation=(O.VCOM, O.POINTS), reward=reward,
                termination=termination, reads_points=False)
