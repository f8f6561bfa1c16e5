"""The four evogym benchmark tasks on top of tsim; importing registers the `sgr/<task>` gymnasium ids."""

from tasks.gym_env import register_envs

register_envs()
