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
