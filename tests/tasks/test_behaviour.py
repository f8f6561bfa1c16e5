"""Behaviour features (tasks/behaviour.py) against episodes computed by hand: a body whose points are
moved by known amounts step by step, actions of a known frequency, a body turned by a known
angle; and in f64 on the CPU the features of a robot do not depend on the batch it runs in."""

from __future__ import annotations

import math

import numpy as np
import pytest

from evolve.rollout.episodes import rollout_policy
from tasks.behaviour import FEATURES, STEP_SECONDS, BehaviourRecorder, terrain_tops
from tasks.env import BatchEnv
from tsim import constants as C

BODY = np.array([[3, 3, 3], [3, 3, 3], [3, 3, 3]])  # nine vertical actuators
F = {name: i for i, name in enumerate(FEATURES)}


def moved_episode(shifts: np.ndarray, actions: np.ndarray | None = None, turn: float = 0.0) -> np.ndarray:
    """The features of one Walker-v0 body whose points are its start's moved by shifts[t] (world
    units) after step t (and turned by `turn` radians about its COM at the last step), driven by
    `actions[t]`; nothing is simulated."""
    env = BatchEnv("Walker-v0", [BODY], episode_steps=len(shifts))
    rec = BehaviourRecorder(env)
    n = env.n_points[0]
    start = env.sim.state[0, :n, 0:2].copy()
    for t, shift in enumerate(shifts):
        pos = start + shift
        if t == len(shifts) - 1 and turn:
            c = pos.mean(axis=0)
            rot = np.array([[math.cos(turn), -math.sin(turn)], [math.sin(turn), math.cos(turn)]])
            pos = (pos - c) @ rot.T + c
        state = env.sim.state
        state[0, :n, 0:2] = pos
        env.sim.state = state
        act = np.full((1, env.sim.max_actuators), 1.0) if actions is None else actions[t][None, :]
        rec.step(act, np.array([True]))
    return rec.features()[0]


def test_displacement_and_height_are_the_com_moves_in_voxels():
    """Points moved by (0.05 t, 0.02 sin) per step: dx, dy the last shift / 0.1, height_mean the
    mean of the y shifts / 0.1, height_max their max / 0.1."""
    T = 40
    t = np.arange(T)
    shifts = np.stack([0.05 * (t + 1), 0.3 * np.abs(np.sin(t / 5))], axis=1)
    f = moved_episode(shifts)
    assert f[F["dx"]] == pytest.approx(shifts[-1, 0] / C.CELL, abs=1e-9)
    assert f[F["dy"]] == pytest.approx(shifts[-1, 1] / C.CELL, abs=1e-9)
    assert f[F["height_mean"]] == pytest.approx(shifts[:, 1].mean() / C.CELL, abs=1e-9)
    assert f[F["height_max"]] == pytest.approx(shifts[:, 1].max() / C.CELL, abs=1e-9)


def test_contact_is_the_share_of_steps_on_the_ground():
    """The body starts on the ground (its bottom points at y = 0.1, the terrain's top): 10 steps
    lifted by a voxel of 30 count as off the ground, the others (and a lift below CONTACT_TOL) on it."""
    shifts = np.zeros((30, 2))
    shifts[5:15, 1] = C.CELL
    shifts[20, 1] = 0.05 * C.CELL  # within the tolerance: still touching
    f = moved_episode(shifts)
    assert f[F["contact"]] == pytest.approx(20 / 30)


def test_gait_frequency_is_the_actuation_s_dominant_frequency():
    """Actions oscillating at k cycles per episode give k / (T x 3 ms) Hz; constant actions 0."""
    T, k = 200, 12
    t = np.arange(T)
    wave = 1.1 + 0.4 * np.sin(2 * math.pi * k * t / T)
    actions = np.repeat(wave[:, None], 9, axis=1)
    actions[:, 4] = 1.1 + 0.1 * np.sin(2 * math.pi * 3 * t / T)  # a weaker, slower one
    f = moved_episode(np.zeros((T, 2)), actions)
    assert f[F["gait_frequency"]] == pytest.approx(k / (T * STEP_SECONDS))
    assert k / (T * STEP_SECONDS) == pytest.approx(20.0)
    still = moved_episode(np.zeros((T, 2)), np.full((T, 9), 1.3))
    assert still[F["gait_frequency"]] == 0.0


@pytest.mark.parametrize("turn", [0.3, -0.8, 2.5])
def test_orientation_is_the_body_s_final_turn(turn):
    """A body turned by `turn` radians at the end reads `turn` (within (-pi, pi])."""
    f = moved_episode(np.zeros((5, 2)), turn=turn)
    assert f[F["orientation"]] == pytest.approx(turn, abs=1e-9)


def test_terrain_tops_are_the_highest_top_at_or_below_each_row():
    """A column of terrain points at rows 0..2 has its top at row 2, seen from rows 2 and up;
    from below it there is none (-1)."""
    pts = np.array([[0.0, 0.0, 0.0, 0.1], [0.0, 0.1, 0.2, 0.0]])
    c0, tops = terrain_tops(pts)
    assert c0 == 0 and tops[0].tolist() == [-1, -1, 2, 2] and tops[1].tolist() == [0, 0, 0, 0]


class Sine:
    """Every actuator at 1.1 + 0.4 sin(2 pi f t): a policy the batch cannot tell apart per robot."""

    def __init__(self, env, hz: float = 7.0):
        self.env, self.t, self.hz = env, 0, hz

    def act(self, obs: np.ndarray) -> np.ndarray:
        self.t += 1
        v = 1.1 + 0.4 * math.sin(2 * math.pi * self.hz * self.t * STEP_SECONDS)
        return np.full((self.env.n_worlds, self.env.sim.max_actuators), v)


def test_features_do_not_depend_on_the_batch():
    """In f64 on the CPU, a robot's return and features are the same alone and in a batch with
    other bodies (padding included), bit for bit."""
    rng = np.random.default_rng(4)
    from tsim.sampling import sample_robots

    bodies = list(sample_robots(5, (5, 5), rng))
    together = rollout_policy("Walker-v0", bodies, Sine, episode_steps=120, record=True)
    for i in (0, 3):
        alone = rollout_policy("Walker-v0", [bodies[i]], Sine, episode_steps=120, record=True)
        assert alone.shape == (1, 1 + len(FEATURES))
        assert alone[0].tolist() == together[i].tolist()


def test_recording_leaves_the_returns_as_they_were():
    """The returns with recording on are the returns without it, bit for bit."""
    from tsim.sampling import sample_robots

    bodies = list(sample_robots(4, (5, 5), np.random.default_rng(9)))
    plain = rollout_policy("Climber-v2", bodies, Sine, episode_steps=80)
    recorded = rollout_policy("Climber-v2", bodies, Sine, episode_steps=80, record=True)
    assert plain.ndim == 1 and recorded[:, 0].tolist() == plain.tolist()
