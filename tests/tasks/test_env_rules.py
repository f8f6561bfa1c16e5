"""Task rules of spec section 5 and 7: goal bonus and termination, the -3 instability penalty,
frozen terminated robots, and that batching never changes a robot's numbers."""

import numpy as np
import pytest

from tasks.bench import sinusoid
from tasks.env import BatchEnv
from tsim.sampling import sample_robot

BODY = np.array([[3, 3, 3, 3, 3], [3, 3, 3, 3, 3], [3, 3, 0, 3, 3], [3, 3, 0, 3, 3], [3, 3, 0, 3, 3]])


def _teleport(env: BatchEnv, w: int, com_x: float, bottom_y: float, vx: float) -> None:
    """Move robot w rigidly so its COM x and lowest point are as given, moving right at vx."""
    n = env.n_points[w]
    s = env.sim.state[w, :n]
    dx = com_x - s[:, 0].mean()
    dy = bottom_y - s[:, 1].min()
    for col in (0, 4):
        s[:, col] += dx
        s[:, col + 1] += dy
    s[:, 2] = vx
    s[:, 6] = vx


@pytest.mark.parametrize("task, goal_x, bonus, bottom_y",
                         [("Walker-v0", 9.9, 1.0, 0.1005), ("ObstacleTraverser-v1", 5.9, 2.0, 1.005)])
def test_crossing_the_finish_pays_the_bonus_once_and_terminates(task, goal_x, bonus, bottom_y):
    env = BatchEnv(task, [BODY, BODY])
    env.reset()
    _teleport(env, 0, goal_x - 0.004, bottom_y, vx=2.0)
    _teleport(env, 1, goal_x - 1.0, bottom_y, vx=0.0)
    env.observe()
    a = np.ones((2, env.sim.max_actuators))
    for _ in range(20):
        before = env.sim.robot_com()[0, 0]
        _, r, term, trunc, _ = env.step(a)
        after = env.sim.robot_com()[0, 0]
        if term[0]:
            break
        assert r[0] == pytest.approx(after - before, abs=1e-12)
    assert term[0] and not term[1] and not trunc.any()
    assert after > goal_x >= before
    assert r[0] == pytest.approx(after - before + bonus, abs=1e-12)
    frozen = env.sim.robot_pos(0)
    obs_end = env.robot_obs(0)
    _, r, term, _, _ = env.step(a)
    assert r[0] == 0.0 and term[0]
    assert np.array_equal(env.sim.robot_pos(0), frozen)  # a terminated robot stops moving
    assert np.array_equal(env.robot_obs(0), obs_end)


def test_self_collision_instability_gives_exactly_minus_3_terminates_and_repeats_the_observation():
    env = BatchEnv("Walker-v0", [np.full((5, 5), 2), np.full((5, 5), 2)], passive_ok=True)
    env.reset()
    s = env.sim.state[0, :env.n_points[0]]
    top = s[:, 1] > s[:, 1].min() + 0.25  # the top two rows of voxels (and the line below them)
    s[top, 1] -= 0.25  # fold them into the bottom rows: many non-neighbour voxel boxes overlap
    s[top, 5] -= 0.25
    obs_before = env.observe()
    _, r, term, _, info = env.step(np.ones((2, env.sim.max_actuators)))
    assert info["unstable"].tolist() == [True, False]
    assert r[0] == -3.0  # exactly: time did not advance, so the displacement part is 0
    assert term.tolist() == [True, False]
    assert np.array_equal(env.robot_obs(0), obs_before[0, :env.obs_dims[0]])
    _, r, _, _, _ = env.step(np.ones((2, env.sim.max_actuators)))
    assert r[0] == 0.0


@pytest.mark.slow
@pytest.mark.parametrize("task", ["Walker-v0", "Thrower-v0"])
def test_mixed_batch_equals_one_env_per_body(task):
    rng = np.random.default_rng(11)
    bodies = [sample_robot((5, 5), rng) for _ in range(3)] + [BODY]
    batch = BatchEnv(task, bodies, episode_steps=60)
    singles = [BatchEnv(task, [b], episode_steps=60) for b in bodies]
    obs = batch.reset()
    for i, e in enumerate(singles):
        assert np.array_equal(obs[i, :batch.obs_dims[i]], e.reset()[0])
        assert np.all(obs[i, batch.obs_dims[i]:] == 0.0)  # padding
    ret_b = np.zeros(len(bodies))
    ret_s = np.zeros(len(bodies))
    for t in range(60):
        acts = [sinusoid(t + 7 * i, n) for i, n in enumerate(batch.n_actuators)]
        ob, rb, tb, _, _ = batch.step(acts)
        ret_b += rb
        for i, e in enumerate(singles):
            os_, rs, ts, _, _ = e.step([acts[i]])
            ret_s[i] += rs[0]
            assert np.max(np.abs(ob[i, :batch.obs_dims[i]] - os_[0])) <= 1e-12
            assert abs(rb[i] - rs[0]) <= 1e-12 and tb[i] == ts[0]
    assert np.max(np.abs(ret_b - ret_s)) <= 1e-12


def test_partial_reset_restarts_only_the_chosen_robots():
    env = BatchEnv("Walker-v0", [BODY, BODY], episode_steps=10)
    obs0 = env.reset()
    for t in range(10):
        env.step([sinusoid(t, n) for n in env.n_actuators])
    with pytest.raises(RuntimeError, match="truncated"):
        env.step([sinusoid(0, n) for n in env.n_actuators])
    obs = env.reset(np.array([True, False]))
    assert np.array_equal(obs[0], obs0[0]) and not np.array_equal(obs[1], obs0[1])
    assert env.elapsed.tolist() == [0, 10]


@pytest.mark.parametrize("mask", [np.array([1, 0]), [1, 0], np.array([0.0, 1.0])])
def test_a_reset_mask_that_is_not_booleans_is_refused_before_anything_resets(mask):
    """numpy reads [1, 0] as indices (both worlds), the simulator read it as a mask (world 0): the
    env's step counts and the physics went out of step. Now neither layer guesses."""
    env = BatchEnv("Walker-v0", [BODY, BODY], episode_steps=10)
    env.reset()
    for t in range(3):
        env.step([sinusoid(t, n) for n in env.n_actuators])
    state = env.sim.state.copy()
    with pytest.raises(ValueError, match="reset mask must be 2 booleans"):
        env.reset(mask)
    assert env.elapsed.tolist() == [3, 3] and env.sim.time.tolist() == [3, 3]
    assert np.array_equal(env.sim.state, state)
    with pytest.raises(ValueError, match="reset mask must be 2 booleans"):
        env.sim.reset(mask)


@pytest.mark.parametrize("steps, ok", [(np.int64(4), True), (np.int32(4), True), (True, False),
                                       (np.bool_(True), False), (4.0, False), (0, False)])
def test_episode_steps_takes_numpys_integers_and_refuses_bools_and_floats(steps, ok):
    """A length read from an array or a config is often a numpy integer: it is an int; True is not
    an episode of 1 step."""
    if ok:
        env = BatchEnv("Walker-v0", [BODY], episode_steps=steps)
        assert env.episode_steps == 4 and type(env.episode_steps) is int
    else:
        with pytest.raises(ValueError, match="episode_steps must be a positive int"):
            BatchEnv("Walker-v0", [BODY], episode_steps=steps)


def test_seeds_as_a_0_d_array_are_the_int_they_hold():
    """`np.array(3)` was `TypeError: len() of unsized object`; it seeds as 3 does (world w: 3 + w)."""
    bodies = [sample_robot((3, 3), np.random.default_rng(s)) for s in range(3)]
    a = BatchEnv("Catcher-v0", bodies, seeds=np.array(3))
    b = BatchEnv("Catcher-v0", bodies, seeds=3)
    assert np.array_equal(a.reset(), b.reset())
    assert np.array_equal(a.sim.read_state(), b.sim.read_state())


@pytest.mark.parametrize("fused", [True, False])
@pytest.mark.parametrize("dtype", [bool, complex])
def test_bool_and_complex_actions_are_refused_on_both_env_paths(fused, dtype):
    """The kernel path took them as 1.0 (complex with a warning) where the numpy path refused."""
    env = BatchEnv("Walker-v0", [BODY], fused=fused)
    env.reset()
    with pytest.raises(ValueError, match="actions must be real numbers"):
        env.step(np.ones((1, env.sim.max_actuators), dtype))

