"""evogym's tasks on top of tsim: one spec per task, a batched env and gymnasium adapters.

The specs are `TaskSpec`s (`tasks.spec`, `tasks/suite/`); `BatchEnv` is the batched, task-agnostic
env. Importing the package registers the `sgr/<task>` ids.

    from tasks import BatchEnv, TASKS
    env = BatchEnv("Walker-v0", [body_a, body_b])
    tasks.register(TaskSpec(name="MyTask-v0", ...))   # yours, everywhere sgr's are (docs/TASKS.md)
"""

from tasks.env import BatchEnv, obs_dim
from tasks.gym_env import SgrEnv, SgrVectorEnv, register_envs
from tasks.registry import register
from tasks.spec import Measure, TaskSpec
from tasks.specs import TASKS, task_spec, task_world

register_envs()

__all__ = ["TASKS", "BatchEnv", "Measure", "SgrEnv", "SgrVectorEnv", "TaskSpec", "obs_dim", "register",
           "task_spec", "task_world"]
