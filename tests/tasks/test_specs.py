"""Task specs: the registry names unknown tasks, and a task is one spec plus one registry line."""

import numpy as np
import pytest

from tasks import observations as O
from tasks.env import BatchEnv
from tasks.spec import Measure, TaskSpec
from tasks.specs import TASKS, task_spec, task_world


def test_unknown_task_names_the_task_and_the_closest_ones():
    with pytest.raises(ValueError, match="unknown task 'Jumper-v9'"):
        task_world("Jumper-v9")
    with pytest.raises(ValueError, match="unknown task 'Jumper-v9'; did you mean Jumper-v0 or "
                                         "GapJumper-v0[?] Known tasks: Walker-v0"):
        task_spec("Jumper-v9")
    with pytest.raises(ValueError, match="unknown task 'Hopper'; known tasks: Walker-v0"):  # none close
        task_spec("Hopper")


def test_observation_layouts_give_evogym_lengths():
    """evogym's observation lengths for a robot of n points (2 n relative coordinates plus each
    task's extra entries: velocity COM, orientation, package, floor or ceiling sight)."""
    extra = {"Walker-v0": 2, "ObstacleTraverser-v1": 3 + 11, "Climber-v2": 3 + 7, "Thrower-v0": 6}
    for name, e in extra.items():
        assert TASKS[name].obs_dim(36) == e + 72


def climb_reward(before: Measure, after: Measure):
    return (after.com - before.com)[:, 1]


def test_a_new_task_is_one_spec_and_one_registry_line(monkeypatch):
    toy = TaskSpec(name="Hopper-v0", world="Walker-v0.json", origin=(1, 1), paper_steps=20, evogym_steps=20,
                   observation=(O.VCOM, O.POINTS, O.floor_sight(2)), reward=climb_reward)
    monkeypatch.setitem(TASKS, toy.name, toy)  # the registry line
    body = np.array([[3, 3, 3], [3, 0, 3]])
    env = BatchEnv("Hopper-v0", [body])
    obs = env.reset()
    assert obs.shape == (1, 2 + 2 * env.n_points[0] + 5)
    com0 = env.sim.robot_com()[0].copy()
    total = 0.0
    for t in range(20):
        obs, r, term, trunc, _ = env.step(np.full((1, 5), 1.0 + 0.5 * (t % 2)))
        total += r[0]
    assert trunc[0] and not term[0]
    assert total == pytest.approx(env.sim.robot_com()[0][1] - com0[1], abs=1e-12)
    assert np.array_equal(obs[0, -5:], O.floor_sight(2).fn(_scene_of(env))[0])


def _scene_of(env: BatchEnv) -> O.Scene:
    com, vcom = env._robot_coms()
    return O.Scene(robot=env._robot, mask=env._mask, n_points=env.n_points, com=com, vcom=vcom,
                   pos0=env._pos0, terrain=env._terrain, object_points=env._object_points)


def test_placement_and_per_world_objects_must_agree(monkeypatch):
    """A spec whose placement and per_world objects disagree fails with one ValueError line naming
    the task and the object: at registration (spec construction) where the spec alone shows it, at
    env construction (the first placement) where only the placement's result does."""
    import dataclasses

    from tasks.spec import AddedObject
    from tasks.suite import catcher

    base = catcher.SPEC
    shared = AddedObject("peg3", "peg.json", (30, 30))
    with pytest.raises(ValueError, match=r"^task Catcher-v0: per_world object 'package' has no "
                                         r"placement \(TaskSpec.placement is None\)$"):
        dataclasses.replace(base, placement=None)
    with pytest.raises(ValueError, match=r"^task Catcher-v0: placement given but no object is "
                                         r"per_world$"):
        dataclasses.replace(base, objects=(shared,))

    def build(placement):
        spec = dataclasses.replace(base, objects=base.objects + (shared,), placement=placement)
        monkeypatch.setitem(TASKS, spec.name, spec)
        task_world.cache_clear()
        try:
            return BatchEnv(spec.name, [np.array([[3, 3, 3], [3, 0, 3]])])
        finally:
            task_world.cache_clear()

    body_err = r"^task Catcher-v0: placement names 'peg3', which is not a per_world object " \
               r"\(per_world objects: package, peg1, peg2\)$"
    with pytest.raises(ValueError, match=body_err):
        build(lambda state: {**catcher.placement(state), "peg3": (31, 30)})
    with pytest.raises(ValueError, match=r"^task Catcher-v0: placement names 'ground'"):
        build(lambda state: {**catcher.placement(state), "ground": (0, 0)})
    with pytest.raises(ValueError, match=r"^task Catcher-v0: per_world object 'peg2' has no "
                                         r"placement \(missing from what TaskSpec.placement "
                                         r"returned\)$"):
        build(lambda state: {k: v for k, v in catcher.placement(state).items() if k != "peg2"})
    assert build(catcher.placement).n_worlds == 1  # the real placement passes
