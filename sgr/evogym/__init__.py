"""evogym 2.0's API on sgr's simulator: `evogym` code ports by importing `sgr.evogym` instead.

Change `evogym` to `sgr.evogym` in its imports (`sed 's/\\bevogym\\b/sgr.evogym/g'`). Same layout
as evogym: `sgr.evogym` (this package: EvoWorld, WorldObject, EvoSim, EvoViewer and the utils),
`.envs` (EvoGymBase, BenchmarkBase and the 32 tasks under evogym's bare gym ids), `.utils`, `.world`,
`.sim`, `.viewer`. docs/EVOGYM_COMPAT.md lists every public name of evogym and its status here.

Where this API differs from sgr's native one (tsim, tasks, evolve; `import sgr`), on purpose, since
it is evogym's:

- `sgr.evogym.sample_robot(shape, pd)` returns (body, connections), the body a float matrix, drawn
  from Python's global `random` (so `random.seed(s)` gives evogym's robot); the native
  `sgr.sample_robot(shape, rng, pd)` returns the int matrix alone, drawn from the
  `np.random.Generator` it is given (connections follow from the matrix: `sgr.build_body`).
- Bodies here are evogym's (matrix, connections) pairs; natively a body is an int matrix or a
  `tsim.Body`.
- Point arrays are evogym's (2, n), one world at a time (`EvoSim.pos_at_time`,
  `object_pos_at_time`, ...); natively batched arrays are (B, n, 2) and COMs (B, 2) (tsim's
  docstring: "Shapes and units").
- Environments are one robot each under evogym's bare gym ids ("Walker-v0"); natively
  `tasks.BatchEnv` steps many robots at once, and the gymnasium ids are "sgr/Walker-v0".
- Bad input raises ValueError with evogym's meaning; the native layers raise `sgr.SgrError`, a
  ValueError too, for the same kind of mistake.
"""

from sgr.evogym.sim import EvoSim
from sgr.evogym.utils import (
    BASELINE_ENV_NAMES,
    VOXEL_TYPES,
    Pair,
    Timer,
    draw,
    get_full_connectivity,
    get_uniform,
    has_actuator,
    hashable,
    is_connected,
    sample_robot,
)
from sgr.evogym.viewer import EvoViewer
from sgr.evogym.world import EvoWorld, WorldObject

__all__ = ["BASELINE_ENV_NAMES", "VOXEL_TYPES", "EvoSim", "EvoViewer", "EvoWorld", "Pair", "Timer",
           "WorldObject", "draw",
           "get_full_connectivity", "get_uniform", "has_actuator", "hashable", "is_connected",
           "sample_robot"]
