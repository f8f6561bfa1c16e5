"""Which body sizes a task's world admits: a body placed at the task's origin may fill no cell an
object of the world fills at the start (facts read off evogym's world files and task code)."""

import pytest

from tasks.specs import body_fit_problem, body_fits, largest_square_body


@pytest.mark.parametrize("task, fits, does_not", [
    # Thrower-v0: robot at cell (1, 1), the package added at (3, 7): rows 1-6 are free, row 7 is not
    ("Thrower-v0", (6, 6), (7, 7)),
    # Climber-v2: robot at (1, 1) between walls at x = 0 and x = 6: five columns wide
    ("Climber-v2", (20, 5), (5, 6)),
    # Carrier-v0: the package sits at (3, 6) on top of the 5x5 robot's place
    ("Carrier-v0", (5, 5), (6, 6)),
    # Walker-v0: flat ground, nothing above it
    ("Walker-v0", (16, 16), None),
    ("ObstacleTraverser-v1", (16, 16), None),
])
def test_a_body_fits_until_it_reaches_an_object_of_the_world(task, fits, does_not):
    assert body_fits(task, fits) and body_fit_problem(task, fits) is None
    if does_not is not None:
        assert not body_fits(task, does_not)


def test_the_refusal_is_one_line_naming_the_largest_square_that_fits():
    line = body_fit_problem("Thrower-v0", (10, 10))
    assert "\n" not in line and "Thrower-v0" in line and "[6, 6]" in line, line
    assert largest_square_body("Climber-v2") == 5 and largest_square_body("Thrower-v0") == 6


def test_a_reregistered_world_is_measured_again():
    """The room a world leaves is looked up again after `register(..., replace=True)`."""
    import gymnasium as gym
    import numpy as np

    from tasks import TaskSpec, register
    from tasks import observations as O
    from tasks.specs import TASKS, forget_worlds
    from tsim import world_from_matrix

    def world(wall_x: int | None) -> np.ndarray:
        m = np.zeros((12, 30), dtype=int)
        m[-1, :] = 5
        if wall_x is not None:
            m[:, wall_x] = 5
        return m

    def spec(wall_x):
        return TaskSpec(name="Room-v0", world=world_from_matrix(world(wall_x)), origin=(1, 1), paper_steps=5,
                        evogym_steps=5, observation=(O.VCOM, O.POINTS), reward=lambda b, a: a.com[:, 0])

    ids = set(gym.registry)
    try:
        register(spec(None))
        assert body_fits("Room-v0", (8, 8))
        register(spec(5), replace=True)  # a wall at x = 5: four columns are left at x = 1..4
        assert body_fits("Room-v0", (8, 4)) and not body_fits("Room-v0", (8, 5))
    finally:
        TASKS.pop("Room-v0", None)
        forget_worlds()
        for env_id in set(gym.registry) - ids:
            del gym.registry[env_id]
