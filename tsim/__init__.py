"""tsim: evogym 2.0's mass-spring voxel physics in Taichi, many worlds (each its own body) at once.

    from tsim import BatchSim, build_body, load_world, sample_robot
    sim = BatchSim(load_world(path_to_world_json), [build_body(m) for m in bodies], origin=(1, 1))

The simulator knows no task: tasks (placement, observations, rewards) live in the `tasks` package.
"""

from tsim.body import Body, build_body, check_robot, has_actuator, is_connected
from tsim.errors import SgrError
from tsim.render import Renderer, write_gif
from tsim.sampling import sample_robot
from tsim.sim import BatchSim
from tsim.world import World, load_world, world_from_dict, world_from_matrix

__all__ = ["BatchSim", "Body", "Renderer", "SgrError", "World", "build_body", "check_robot", "has_actuator",
           "is_connected", "load_world", "sample_robot", "world_from_dict", "world_from_matrix", "write_gif"]
