"""A task registered in the user's own code (`tasks.register`) reaches the rollout workers, which
know only sgr's tasks: its spec travels with each job, functions and world included, and the
returns are those of one in-process batch."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from evolve.nn.dense import DenseController
from evolve.rollout.episodes import dense_policy
from evolve.rollout.pool import RolloutPool
from tasks import Measure, TaskSpec, register
from tasks import observations as O
from tasks.env import obs_dim
from tasks.specs import TASKS, task_world
from tsim import world_from_matrix
from tsim.body import build_body
from tsim.sampling import sample_robot

pytestmark = [pytest.mark.slow, pytest.mark.subprocess]

NAME = "UserStepLeft-v0"


def leftward_and_low(before: Measure, after: Measure):
    """Leftward progress minus a tenth of the rise: a reward no sgr module defines."""
    return (before.com[:, 0] - after.com[:, 0]) - 0.1 * (after.com[:, 1] - before.com[:, 1])


@pytest.fixture
def user_task():
    ground = np.zeros((9, 40), dtype=int)
    ground[-2:, :] = 5
    ground[-3, 20:] = 5
    before, ids = dict(TASKS), set(gym.registry)
    register(TaskSpec(name=NAME, world=world_from_matrix(ground), origin=(30, 3), paper_steps=40,
                      evogym_steps=40, observation=(O.VCOM, O.POINTS), reward=leftward_and_low,
                      goal=(3, 1.0, "left")))
    yield NAME
    TASKS.clear()
    TASKS.update(before)
    task_world.cache_clear()
    for env_id in set(gym.registry) - ids:
        del gym.registry[env_id]


def _robots(n: int, seed: int = 3) -> tuple[list[np.ndarray], list[DenseController]]:
    rng = np.random.default_rng(seed)
    bodies = [sample_robot((5, 5), rng) for _ in range(n)]
    ctrls = []
    for body in bodies:
        b = build_body(body)
        n_in = obs_dim(NAME, b.n_points)
        ctrls.append(DenseController([rng.normal(0, 1, (n_in, 25))], [rng.normal(0, 0.5, 25)], ["tanh"], n_in,
                                     np.asarray(b.actuator_flat, dtype=np.int64)))
    return bodies, ctrls


def test_a_user_task_gives_the_same_returns_in_two_worker_processes(user_task):
    bodies, ctrls = _robots(6)
    with RolloutPool(1) as here, RolloutPool(2) as workers:
        a = here.run(user_task, bodies, ctrls, dense_policy)
        b = workers.run(user_task, bodies, ctrls, dense_policy)
        assert len(workers._procs) == 2  # really in two other processes
    assert np.array_equal(a, b) and np.ptp(a) > 0


@pytest.mark.ray
def test_a_user_task_on_ray_actors(user_task):
    """Ray actors too (Ray pickles the job; the spec inside it registers the task there)."""
    ray = pytest.importorskip("ray")
    from evolve.rollout.ray_cluster import RayRolloutPool

    bodies, ctrls = _robots(4)
    ray.init(address="local", num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        with RayRolloutPool(actors=2) as pool:
            on_ray = pool.run(user_task, bodies, ctrls, dense_policy)
    finally:
        ray.shutdown()
    assert np.array_equal(on_ray, RolloutPool(1).run(user_task, bodies, ctrls, dense_policy))
