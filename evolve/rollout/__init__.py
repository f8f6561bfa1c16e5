"""Episodes of many robots: the batched episode loop, local worker processes, Ray actors."""

from evolve.rollout.episodes import BatchPolicy, dense_policy, rollout_policy
from evolve.rollout.pool import RolloutPool, WorkerDied

__all__ = ["BatchPolicy", "RolloutPool", "WorkerDied", "dense_policy", "rollout_policy"]
