"""evogym 2.0's API on sgr's simulator: `evogym` code ports by changing `evogym` to `sgr.evogym` in
its imports (`sed 's/\\bevogym\\b/sgr.evogym/g'`). Same layout as evogym: `sgr.evogym` (this
package: EvoWorld, WorldObject, EvoSim, EvoViewer and the utils), `.envs` (EvoGymBase,
BenchmarkBase and the 32 tasks under evogym's bare gym ids), `.utils`, `.world`, `.sim`, `.viewer`.
docs/EVOGYM_COMPAT.md lists every public name of evogym and its status here.
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
