"""Walking tasks over terrain that end with -3 when the robot falls over: UpStepper-v0 (stairs up),
DownStepper-v0 (stairs down), ObstacleTraverser-v0 (bumpy ground), Hurdler-v0 (posts). The robot
sees the floor 5 voxels either side."""

import math

from tasks import observations as O
from tasks.spec import TaskSpec
from tasks.suite._common import dx, upside_down

OBS = (O.VCOM, O.ORIENTATION, O.POINTS, O.floor_sight(5))

UP = TaskSpec(name="UpStepper-v0", world="UpStepper-v0.json", origin=(1, 1), paper_steps=600,
              evogym_steps=600, observation=OBS, reward=dx, goal=(69, 2.0),
              termination=upside_down(math.pi / 2 - math.pi / 12, 3 * math.pi / 2 + math.pi / 12))
DOWN = TaskSpec(name="DownStepper-v0", world="DownStepper-v0.json", origin=(1, 11), paper_steps=500,
                evogym_steps=500, observation=OBS, reward=dx, goal=(74, 2.0),
                termination=upside_down())
OBSTACLE_V0 = TaskSpec(name="ObstacleTraverser-v0", world="ObstacleTraverser-v0.json",
                       origin=(2, 1), paper_steps=1000, evogym_steps=1000, observation=OBS,
                       reward=dx, goal=(79, 2.0), termination=upside_down())
HURDLER = TaskSpec(name="Hurdler-v0", world="Hurdler-v0.json", origin=(2, 4), paper_steps=1000,
                   evogym_steps=1000, observation=OBS, reward=dx, termination=upside_down())
