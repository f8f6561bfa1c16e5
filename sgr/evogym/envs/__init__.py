"""evogym 2.0's `evogym.envs` on sgr: the base classes for custom environments (`EvoGymBase`,
`BenchmarkBase`); importing it registers evogym's 32 tasks under their bare gym ids ("Walker-v0"),
computed by sgr's validated tasks (`TaskEnv`, and `TaskVectorEnv` for `gym.make_vec`)."""

from sgr.evogym.envs.base import BenchmarkBase, EvoGymBase
from sgr.evogym.envs.benchmark import TaskEnv, TaskVectorEnv, register_bare_ids

register_bare_ids()

__all__ = ["BenchmarkBase", "EvoGymBase", "TaskEnv", "TaskVectorEnv"]
