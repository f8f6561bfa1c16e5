"""Tasks of one's own: `tasks.register` makes a spec a task everywhere sgr's are (BatchEnv,
gymnasium), worlds are built from a terrain matrix or a dict, goals can lie to the left, and
`Renderer` takes a task name."""

import gymnasium as gym
import numpy as np
import pytest

from tasks import BatchEnv, Measure, TaskSpec, register
from tasks import observations as O
from tasks.specs import TASKS, task_world
from tsim import Renderer, world_from_dict, world_from_matrix
from tsim.world import load_world

BODY = np.array([[3, 3, 3], [3, 0, 3]])


def leftward(before: Measure, after: Measure):
    return before.com[:, 0] - after.com[:, 0]


def flat(width: int = 30, height: int = 6) -> np.ndarray:
    m = np.zeros((height, width), dtype=int)
    m[-1, :] = 5
    return m


@pytest.fixture
def registry():
    """TASKS and gymnasium's registry as they were, after the test."""
    before = dict(TASKS)
    ids = set(gym.registry)
    yield
    TASKS.clear()
    TASKS.update(before)
    task_world.cache_clear()
    for env_id in set(gym.registry) - ids:
        del gym.registry[env_id]


def test_a_registered_task_runs_in_batchenv_and_gymnasium(registry):
    spec = register(TaskSpec(name="Left-v0", world=world_from_matrix(flat()), origin=(20, 1), paper_steps=15,
                             evogym_steps=15, observation=(O.VCOM, O.POINTS), reward=leftward))
    env = BatchEnv("Left-v0", [BODY])
    com0 = env.sim.robot_com()[0].copy()
    total = sum(env.step(np.full((1, 5), 1.0 + 0.5 * (t % 2)))[1][0] for t in range(15))
    assert total == pytest.approx(com0[0] - env.sim.robot_com()[0][0], abs=1e-12)  # leftward progress
    g = gym.make("sgr/Left-v0", body=BODY)
    assert g.spec.max_episode_steps == 15 and g.unwrapped.batch_env.spec is spec
    with pytest.raises(ValueError, match="registered already"):
        register(TaskSpec(name="Left-v0", world="Walker-v0.json", origin=(1, 1), paper_steps=5,
                          evogym_steps=5, observation=(O.VCOM, O.POINTS), reward=leftward))
    with pytest.raises(ValueError, match="one of sgr's own tasks"):
        register(TaskSpec(name="Walker-v0", world="Walker-v0.json", origin=(1, 1), paper_steps=5,
                          evogym_steps=5, observation=(O.VCOM, O.POINTS), reward=leftward))


def test_a_world_from_a_matrix_is_the_world_of_the_same_json(tmp_path):
    """The matrix below written as evogym's JSON by hand (cell index x + y * width, y from the
    bottom, each cell glued to its filled 4-neighbours) loads to the same objects and terrain."""
    m = np.zeros((4, 5), dtype=int)
    m[3, :] = 5        # ground, y = 0
    m[2, 3:] = 5       # a step, y = 1, x = 3..4
    m[0, 0] = 2        # a soft voxel floating at the top left (its own object)
    ground = [0, 1, 2, 3, 4, 8, 9]
    nbrs = {0: [1], 1: [0, 2], 2: [1, 3], 3: [2, 4, 8], 4: [3, 9], 8: [3, 9], 9: [4, 8]}
    data = {"grid_width": 5, "grid_height": 4, "objects": {
        "terrain": {"indices": [15], "types": [2], "neighbors": {"15": []}},
        "terrain_1": {"indices": ground, "types": [5] * 7,
                      "neighbors": {str(k): v for k, v in nbrs.items()}}}}
    a = world_from_matrix(m)
    b = world_from_dict(data)
    (tmp_path / "w.json").write_text(__import__("json").dumps(data))
    c = load_world(tmp_path / "w.json")
    for w in (a, b):
        assert [o.name for o in w.objects] == [o.name for o in c.objects]
        assert all(np.array_equal(x.pos0, y.pos0) and np.array_equal(x.body.matrix, y.body.matrix)
                   for x, y in zip(w.objects, c.objects, strict=True))
        assert np.array_equal(w.terrain.grid, c.terrain.grid)
        assert np.array_equal(w.terrain.corners, c.terrain.corners)
    assert [o.name for o in a.free_objects] == ["terrain"] and a.terrain.grid[4, 1] >= 0
    with pytest.raises(ValueError, match="materials must be 0..5"):
        world_from_matrix([[7]])
    with pytest.raises(ValueError, match="bad world 'custom'"):
        world_from_dict({"grid_width": 5, "objects": {}})


@pytest.mark.parametrize("grid, indices, match", [
    ((0, 2), [0, 1], "grid must be at least 1x1, got 0x2"),   # was a ZeroDivisionError
    ((4, 0), [0, 1], "grid must be at least 1x1, got 4x0"),   # was an IndexError
    ((4, 2), [0, 12], "cell index 12 is outside the 4x2 grid"),
    ((4, 2), [-1, 0], "cell index -1 is outside the 4x2 grid"),  # wrapped into another row
])
def test_a_world_whose_cells_leave_its_grid_is_refused_in_one_line(grid, indices, match):
    data = {"grid_width": grid[0], "grid_height": grid[1], "objects": {"ground": {
        "indices": indices, "types": [5] * len(indices), "neighbors": {str(i): [] for i in indices}}}}
    with pytest.raises(ValueError, match=f"bad world 'custom': .*{match}"):
        world_from_dict(data)


def test_a_free_object_above_the_grid_loads_as_evogym_loads_it():
    """Only the terrain's cells must lie in the grid (they make its cell grid); a free box above it
    is simulated, as evogym simulates it."""
    data = {"grid_width": 10, "grid_height": 3, "objects": {
        "ground": {"indices": list(range(10)), "types": [5] * 10,
                   "neighbors": {str(i): [j for j in (i - 1, i + 1) if 0 <= j < 10] for i in range(10)}},
        "box": {"indices": [38], "types": [1], "neighbors": {"38": []}}}}
    world = world_from_dict(data)
    assert [o.cell for o in world.objects if o.name == "box"] == [(8, 3)]


@pytest.mark.parametrize("direction, start, ends", [("left", 20, True), ("right", 20, False)])
def test_a_goal_to_the_left_ends_the_episode_with_its_bonus(registry, direction, start, ends):
    """A robot that is placed left of the goal's x has passed a "left" goal at its first step
    (bonus and over), and not a "right" one."""
    register(TaskSpec(name="Goal-v0", world=world_from_matrix(flat()), origin=(start, 1), paper_steps=5,
                      evogym_steps=5, observation=(O.VCOM, O.POINTS), reward=leftward,
                      goal=(25, 7.0, direction)))
    _, r, term, _, _ = BatchEnv("Goal-v0", [BODY]).step(np.ones((1, 5)))
    assert bool(term[0]) is ends and bool(r[0] > 6.0) is ends
    with pytest.raises(ValueError, match="goal must be"):
        TaskSpec(name="Bad", world="Walker-v0.json", origin=(1, 1), paper_steps=5, evogym_steps=5,
                 observation=(O.POINTS,), reward=leftward, goal=(25, 1.0, "up"))


def test_renderer_takes_a_task_name(tmp_path):
    r = Renderer("Walker-v0", BODY, 64, 32)
    assert r.world is task_world("Walker-v0")
    with pytest.raises(ValueError, match="no world 'Walkr-v0': not a world file, nor a task name"):
        Renderer("Walkr-v0", BODY)
