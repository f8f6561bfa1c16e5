"""Batch behaviour: action validation, isolation of a blown-up world, deactivation."""

import numpy as np
import pytest

from tasks.specs import task_world
from tsim.sampling import sample_robot
from tsim.sim import BatchSim


@pytest.fixture()
def sim():
    rng = np.random.default_rng(3)
    return BatchSim(task_world("Walker-v0"), [sample_robot((5, 5), rng) for _ in range(3)], (1, 1))


@pytest.mark.parametrize("actions, words", [
    (1.0, "got float"), (None, "got NoneType"), ("1.0", "got str"),
    (np.ones((3, 8), complex), "real numbers, got dtype complex128"),  # the imaginary part was dropped
    (np.ones((3, 8), bool), "real numbers, got dtype bool"),
    ("a None row", "robot 1 must be real numbers"),
])
def test_actions_that_are_not_rows_of_real_numbers_are_refused_naming_what_they_are(sim, actions, words):
    """A scalar was `TypeError: object of type 'float' has no len()`; complex actions were cast
    with a warning."""
    if isinstance(actions, np.ndarray):
        actions = np.ones((3, sim.max_actuators), actions.dtype)
    if isinstance(actions, str) and actions == "a None row":
        actions = [[1.0] * n if w != 1 else [None] * n for w, n in enumerate(sim.n_actuators)]
    with pytest.raises(ValueError, match=words):
        sim.set_actions(actions)


def test_wrong_action_shape_and_non_finite_actions_raise(sim):
    with pytest.raises(ValueError, match="wrong action shape"):
        sim.set_actions(np.ones((2, sim.max_actuators)))
    with pytest.raises(ValueError, match="wrong action shape"):
        sim.set_actions([np.ones(n + 1) for n in sim.n_actuators])
    bad = np.ones((3, sim.max_actuators))
    bad[1, 0] = np.nan
    with pytest.raises(ValueError, match="non-finite"):
        sim.set_actions(bad)


def test_actions_are_clipped_to_evogym_range(sim):
    sim.set_actions(np.full((3, sim.max_actuators), 5.0))
    assert sim.actions[:, :sim.max_actuators].max() <= 1.6


def test_blown_up_world_is_flagged_and_frozen_while_others_go_on(sim):
    sim.step()
    sim.state[1, 0, 0] = np.nan  # a robot point gone bad
    before = [sim.robot_com()[w].copy() for w in (0, 2)]
    sim.set_actions(np.full((3, sim.max_actuators), 1.6))
    sim.step(5)
    assert sim.unstable.tolist() == [False, True, False]
    assert np.all(np.isfinite(sim.robot_pos(0))) and np.all(np.isfinite(sim.robot_pos(2)))
    assert not np.allclose(sim.robot_com()[0], before[0])
    assert sim.time.tolist() == [6, 1, 6]


def test_states64_in_f64_is_a_copy_of_the_state_positions_and_velocities(sim):
    sim.set_actions(np.full((3, sim.max_actuators), 1.6))
    sim.step(3)
    s = sim.states64()
    assert s.dtype == np.float64 and np.array_equal(s, sim.state[:, :, 0:4])
    s[:] = 0.0
    assert np.abs(sim.state[:, :, 0:2]).max() > 0  # the caller's array, not the state


def test_deactivated_world_stops_moving(sim):
    """A deactivated world keeps every point exactly where it was while the other worlds still move.

    Each robot is compared with its own snapshot taken just before the steps.
    """
    sim.set_actions(np.full((3, sim.max_actuators), 1.6))
    sim.step()
    sim.deactivate(np.array([True, False, False]))
    before = [sim.robot_pos(w) for w in range(3)]
    sim.step(3)
    assert np.array_equal(sim.robot_pos(0), before[0])
    for w in (1, 2):
        assert np.abs(sim.robot_pos(w) - before[w]).max() > 1e-6
    assert sim.time.tolist() == [1, 4, 4]


def _cantilever_world(tmp_path):
    """A fixed post (x = 10, y = 0..3) carrying a soft arm 4 voxels long at its top, one object."""
    import json

    from tsim.world import load_world

    w = 20
    cells = {(10, y): 5 for y in range(4)} | {(x, 3): 2 for x in range(11, 15)}
    idx = {x + y * w: t for (x, y), t in cells.items()}
    nbs = {str(i): [j for j in idx if j in (i - 1, i + 1, i - w, i + w)
                    and abs(j % w - i % w) <= 1] for i in idx}
    obj = {"indices": list(idx), "types": list(idx.values()), "neighbors": nbs}
    p = tmp_path / "cantilever.json"
    p.write_text(json.dumps({"grid_width": w, "grid_height": 5, "objects": {"arm": obj}}))
    return load_world(p)


def test_fixed_corners_of_a_simulated_object_never_move(tmp_path):
    """An object mixing fixed and soft voxels is simulated as one object: its fixed corners keep
    their initial bits and stay at rest (evogym discards their updates) while the soft arm sags."""
    from tsim.body import build_body

    world = _cantilever_world(tmp_path)
    (arm,) = world.free_objects
    fixed = np.unique(arm.body.voxel_points[arm.body.voxel_type == 5])
    soft = np.setdiff1d(np.arange(arm.body.n_points), fixed)
    sim = BatchSim(world, [build_body(np.array([[3, 3]]))] * 2, (1, 1))
    sim.step(20)
    for w in range(2):
        pos, vel = sim.object_pos(w, "arm"), sim.object_vel(w, "arm")
        assert np.array_equal(pos[:, fixed], arm.pos0[:, fixed])
        assert not vel[:, fixed].any()
        assert pos[1, soft].min() < arm.pos0[1, soft].min() - 0.01  # the tip sags


def test_an_all_fixed_object_placed_per_world_is_simulated_where_it_is_put(tmp_path):
    """An all-fixed object marked per_world is not shared terrain: each world puts it elsewhere
    (from its next reset on) and it stays there, every point fixed."""
    from tsim.body import build_body
    from tsim.world import WorldObject

    base = _cantilever_world(tmp_path)
    bar = build_body(np.full((1, 3), 5), allow_fixed=True)
    peg = WorldObject("bar", bar, (0, 0), bar.place(0, 0)).placed("peg", (2, 6), per_world=True)
    assert peg.is_fixed and not peg.is_terrain
    world = base.with_objects((peg,))
    assert [o.name for o in world.free_objects] == ["arm", "peg"]
    sim = BatchSim(world, [build_body(np.array([[3, 3]]))] * 2, (1, 1))
    sim.place_object(1, "peg", (5, 8))
    sim.reset(np.array([False, True]))
    sim.step(10)
    assert np.array_equal(sim.object_pos(0, "peg"), peg.body.place(2, 6))
    assert np.array_equal(sim.object_pos(1, "peg"), peg.body.place(5, 8))
