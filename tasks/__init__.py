"""evogym's tasks on top of tsim: one spec per task (`tasks.spec`, `tasks/suite/`), a batched,
task-agnostic env (`BatchEnv`) and gymnasium adapters. Importing registers the `sgr/<task>` ids.

    from tasks import BatchEnv, TASKS
    env = BatchEnv("Walker-v0", [body_a, body_b])
"""

from tasks.env import BatchEnv, obs_dim
from tasks.gym_env import SgrEnv, SgrVectorEnv, register_envs
from tasks.spec import TaskSpec
from tasks.specs import TASKS, task_spec, task_world

register_envs()

__all__ = ["TASKS", "BatchEnv", "SgrEnv", "SgrVectorEnv", "TaskSpec", "obs_dim", "task_spec", "task_world"]
