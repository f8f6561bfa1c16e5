"""evogym 2.0's `evogym.envs` on sgr: the base classes for custom environments (`EvoGymBase`,
`BenchmarkBase`); importing it registers evogym's 32 tasks under their bare gym ids ("Walker-v0"),
computed by sgr's validated tasks (`TaskEnv`, and `TaskVectorEnv` for `gym.make_vec`), and evogym's
env classes by name (`WalkingFlat`, `Climb2`, ...: each a `TaskEnv` bound to its task)."""

from sgr.evogym.envs.base import BenchmarkBase, EvoGymBase
from sgr.evogym.envs.benchmark import TaskEnv, TaskVectorEnv, register_bare_ids, task_classes

register_bare_ids()
globals().update(task_classes())

__all__ = ["BenchmarkBase", "EvoGymBase", "TaskEnv", "TaskVectorEnv", *sorted(task_classes())]
