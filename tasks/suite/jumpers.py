"""GapJumper-v0 and PlatformJumper-v0: jump right from platform to platform (fixed objects, no
ground); -3 and the episode ends once the COM is below y = 0.4 (fallen off); PlatformJumper also
ends with -3 when the robot falls over (both can apply). The robot sees the platforms 5 voxels
either side."""

from tasks import observations as O
from tasks.spec import TaskSpec
from tasks.suite._common import both, dx, fell_below, upside_down

OBS = (O.VCOM, O.ORIENTATION, O.POINTS, O.floor_sight(5))

GAP = TaskSpec(name="GapJumper-v0", world="GapJumper-v0.json", origin=(1, 6), paper_steps=1000,
               evogym_steps=1000, observation=OBS, reward=dx, termination=fell_below(0.4), reads_points=False)
PLATFORM = TaskSpec(name="PlatformJumper-v0", world="PlatformJumper-v0.json", origin=(1, 6),
                    paper_steps=1000, evogym_steps=1000, observation=OBS, reward=dx,
                    termination=both(fell_below(0.4), upside_down()))
