"""EvoSim against evogym itself on a world of our own (tests/data/evogym_api/multi_world.*,
recorded by references/evogym_api_reference.py): terrain with a step, a rigid box, a lever held by a
fixed voxel, a falling ball, a robot added from an array with custom connections and a second
robot, both driven by set_action with targets up to 1.65 (evogym's EvoSim does not clip: clipping
would change the run).
Every step's positions and velocities of every point, in evogym's order and units, and each
object's orientation; and bad input: one clear error each."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

import sgr.evogym as evogym
from sgr.evogym import EvoSim, EvoWorld

ROOT = Path(__file__).resolve().parents[3]
DATA = ROOT / "tests" / "data" / "evogym_api"
PI2 = 2 * 3.1415926  # evogym's orientation lives on [0, 2 x its pi)


def _ref():
    spec = importlib.util.spec_from_file_location("evogym_api_reference",
                                                  ROOT / "references" / "evogym_api_reference.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def run():
    ref, d = _ref(), np.load(DATA / "multi_world.npz", allow_pickle=False)
    sim = EvoSim(ref.multi_world_layout(EvoWorld))
    names = [str(n) for n in d["names"]]
    got = {"pos": [], "vel": [], "ort": [], "unstable": [], "time": []}
    for t in range(len(d["time"])):
        ref.drive(sim, t)
        got["unstable"].append(sim.step())
        now = sim.get_time()
        got["time"].append(now)
        got["pos"].append(sim.pos_at_time(now))
        got["vel"].append(sim.vel_at_time(now))
        got["ort"].append([sim.object_orientation_at_time(now, n) for n in names])
    return sim, d, names, {k: np.array(v) for k, v in got.items()}


@pytest.mark.slow
def test_every_point_follows_evogym_for_300_steps(run):
    sim, d, _, got = run
    assert got["pos"].shape == d["pos"].shape  # every point of the world, terrain included
    np.testing.assert_array_equal(got["unstable"], d["unstable"])
    np.testing.assert_array_equal(got["time"], d["time"])
    assert isinstance(sim.get_time(), int)
    assert np.abs(got["pos"] - d["pos"]).max() < 1e-9
    assert np.abs(got["vel"] - d["vel"]).max() < 1e-9


def _circle(a, b):
    diff = np.abs(a - b) % PI2
    return np.minimum(diff, PI2 - diff)


def test_orientations_follow_evogym(run):
    """The robot's orientation equals evogym's at every step (angles on evogym's circle: near 0
    its sign test flips to ~2 pi on rounding noise). The objects' too, up to that sign: evogym
    takes the sign from the summed cross products of the points against step 0, which for a box
    that only squashes symmetrically (no turn) is rounding noise, so evogym itself reports the
    angle a or 2 pi - a at random; the box does this here."""
    _, d, names, got = run
    for robot in (names.index("walker"), names.index("hopper")):
        assert _circle(got["ort"][:, robot], d["orientation"][:, robot]).max() < 1e-9
        assert np.ptp(d["orientation"][:, robot]) > 0.01  # it turns: the comparison has content
    either = np.minimum(_circle(got["ort"], d["orientation"]), _circle(PI2 - got["ort"], d["orientation"]))
    assert either.max() < 1e-9


def test_past_steps_and_actuators_read_back_as_evogyms(run):
    sim, d, names, _ = run
    for n in names:
        np.testing.assert_allclose(sim.object_pos_at_time(150, n), d[f"objpos_{n}"], rtol=0, atol=1e-9)
    np.testing.assert_array_equal(sim.pos_at_time(0), d["pos0"])
    np.testing.assert_array_equal(sim.get_actuator_indices("walker"), d["act_walker"])
    np.testing.assert_array_equal(sim.get_actuator_indices("hopper"), d["act_hopper"])
    assert sim.get_dim_action_space("hopper") == 2


def test_reset_starts_again_at_time_0_and_revert_goes_back(run):
    ref, d = _ref(), np.load(DATA / "multi_world.npz", allow_pickle=False)
    sim = EvoSim(ref.multi_world_layout(EvoWorld))
    for t in range(20):
        ref.drive(sim, t)
        sim.step()
    sim.revert(10)
    assert sim.get_time() == 10
    for t in range(10, 20):
        ref.drive(sim, t)
        sim.step()
    assert np.abs(sim.pos_at_time(20) - d["pos"][19]).max() < 1e-9
    sim.reset()
    assert sim.get_time() == 0
    np.testing.assert_array_equal(sim.pos_at_time(0), d["pos0"])


def _world(*objects):
    w = EvoWorld.from_json(str(DATA / "simple_environment.json"))
    for name, body, x, y in objects:
        w.add_from_array(name, np.array(body), x, y)
    return w


def test_bad_input_gets_one_clear_error():
    sim = EvoSim(_world(("robot", [[3, 3], [1, 1]], 1, 1)))
    with pytest.raises(ValueError, match="nope is not a valid object name"):
        sim.object_pos_at_time(0, "nope")
    with pytest.raises(ValueError, match="box2 is not a valid robot name"):
        sim.set_action("box2", np.ones(2))
    with pytest.raises(ValueError, match=r"time 3 is outside valid range \[0, 0\]"):
        sim.pos_at_time(3)
    with pytest.raises(TypeError, match="not of type int"):
        sim.vel_at_time(1.0)
    with pytest.raises(ValueError, match="expected action with 2 values but got action with 3"):
        sim.set_action("robot", np.ones(3))
    with pytest.raises(ValueError, match="non-finite"):
        sim.set_action("robot", np.array([1.0, np.nan]))


def test_worlds_sgr_cannot_simulate_say_what_is_missing():
    with pytest.raises(ValueError, match="robot 'a': it has fixed voxels"):
        EvoSim(_world(("a", [[3, 5]], 1, 1)))
    only_ground = EvoWorld()
    only_ground.add_from_array("ground", np.array([[5, 5, 5]]), 0, 0)
    with pytest.raises(ValueError, match="all fixed"):
        EvoSim(only_ground)
    only_ground.add_from_array("lever", np.array([[1, 1], [5, 0]]), 0, 1)
    with pytest.raises(ValueError, match="fixed voxels in every object, and no robot"):
        EvoSim(only_ground)
    empty = EvoWorld()
    empty.add_from_array("ghost", np.zeros((2, 2)), 0, 0)
    with pytest.raises(ValueError, match="'ghost': it has no voxels"):
        EvoSim(empty)


def test_a_world_without_robot_simulates_its_objects():
    sim = EvoSim(_world())
    for _ in range(5):
        assert sim.step() is False
    box = sim.object_pos_at_time(5, "box")
    assert box[1].min() < sim.object_pos_at_time(0, "box")[1].min()  # the box falls (it starts at y = 7)
    assert evogym.EvoSim is EvoSim


def test_a_second_robot_goes_unstable_at_evogyms_step():
    """evogym's instability rule for a robot that is not the first (tests/data/evogym_api/
    second_robot.npz): the robot evogym flags at step 37 of Lifter-v0, as a second robot. The flag
    comes at the same step, time stops at 37 as evogym's, and the state is evogym's last
    snapshot; later steps stay flagged (with a warning: evogym would go on from its unstable
    state)."""
    ref, d = _ref(), np.load(DATA / "second_robot.npz", allow_pickle=False)
    world, acts = ref.second_robot_world(EvoWorld, ROOT / "tasks" / "worlds")
    sim = EvoSim(world)
    flags, times = [], []
    with pytest.warns(UserWarning, match="after an unstable step"):
        for t in range(len(d["unstable"])):
            sim.set_action("aaa", np.array([1.0]))
            sim.set_action("robot", np.clip(acts[t], 0.6, 1.6))
            flags.append(sim.step())
            times.append(sim.get_time())
    np.testing.assert_array_equal(flags, d["unstable"])
    np.testing.assert_array_equal(times, d["time"])
    assert np.abs(sim.pos_at_time(sim.get_time()) - d["pos"]).max() < 1e-9


def test_a_world_with_no_objects_is_refused_saying_so():
    """It said "its objects have all fixed (material 5)": all() of no objects is True."""
    with pytest.raises(ValueError, match="it has no objects"):
        EvoSim(EvoWorld())
