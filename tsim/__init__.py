"""tsim: evogym 2.0's mass-spring voxel physics in Taichi, many worlds (each its own body) at once.

    from tsim import BatchSim, build_body, load_world, sample_robot
    sim = BatchSim(load_world(path_to_world_json), [build_body(m) for m in bodies], origin=(1, 1))

The simulator knows no task: tasks (placement, observations, rewards) live in the `tasks` package.

Physics first, then where it runs:
- `constants`, `body`, `bodybatch`, `sampling`, `world`: evogym's materials, bodies and worlds;
- `layout`: a batch's padded arrays; `sim`: `BatchSim`, the batch stepped; `kernels/`: the step,
  one physics stage per module; `rounding`: f32's initial placement;
- `backend/`: where and how the kernels run: the `Backend` seam (`tsim.backend.get`), its tables of
  archs and precisions, Taichi's start-up, devices, launchers (cached, SPIR-V, lanes) and arrays
  kept on a device; only `sim` and `kernels/` import it (tests/test_architecture.py);
- `render`, `files`: frames and GIFs; whole-or-nothing file writes.

Shapes and units, the one convention for point arrays in tsim, tasks and evolve:
- Units: world units (a voxel is 0.1 wide); velocities per unit of simulated time (dt = 1e-4 per
  substep, 30 substeps per env step); materials are evogym's codes 0-5.
- Batched arrays put the world first and the coordinate last: `BatchSim.state` is (B, P, 8), one
  row per point; points of every world are (B, n, 2) (with a (B, n) mask where robots differ);
  one point per world, such as a COM, is (B, 2); one number per world is (B,).
- evogym's own layout, (2, n) with row 0 x and row 1 y, is kept for one body or one world where
  an API mirrors evogym: `BatchSim.robot_pos/robot_vel/object_pos/object_vel(w)`, `Body.place`,
  `WorldObject.pos0`, the points `Renderer` draws, and all of `sgr.evogym` (`EvoSim.pos_at_time`,
  `object_pos_at_time`, ...), whose shapes are evogym's and do not change.
- One named exception inside tasks: the points a sight block looks over (tasks/observations.py,
  `Scene.terrain` (2, M) and `Scene.object_now` (B, 2, M)) keep evogym's (2, .) layout, the one
  evogym's get_floor_obs/get_ceil_obs take; only their max and min are read.
"""

from tsim.body import Body, build_body, check_robot, has_actuator, is_connected
from tsim.errors import SgrError
from tsim.render import Renderer, write_gif
from tsim.sampling import sample_robot, sample_robots
from tsim.sim import BatchSim
from tsim.world import World, load_world, world_from_dict, world_from_matrix

__all__ = ["BatchSim", "Body", "Renderer", "SgrError", "World", "build_body", "check_robot", "has_actuator",
           "is_connected", "load_world", "sample_robot", "sample_robots", "world_from_dict",
           "world_from_matrix", "write_gif"]
