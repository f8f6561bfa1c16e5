"""The state kept on the device between steps (tsim/backend/mirror.py), checked on the CPU: a `DeviceMirror`
works over the CPU's Taichi ndarrays as over a GPU's, so forcing it here tests its copying rules
(that every read sees the last step, every write reaches the next, and nothing else crosses) with
the CPU's bits as the oracle. Vulkan runs it for real in tests/tsim/backend/test_vulkan.py."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import tsim.sim as sim_mod
from tasks.env import BatchEnv
from tsim.backend import mirror as mirror_mod
from tsim.sampling import sample_robot

ROOT = Path(__file__).resolve().parents[3]


class Counted(mirror_mod.DeviceMirror):
    """A DeviceMirror that counts its copies in (host -> device) and out."""

    def __init__(self, host):
        super().__init__(host)
        self.copies = {"in": 0, "out": 0}
        dev = self._device
        to_numpy, from_numpy = dev.to_numpy, dev.from_numpy

        def out():
            self.copies["out"] += 1
            return to_numpy()

        def into(a):
            self.copies["in"] += 1
            return from_numpy(a)

        dev.to_numpy, dev.from_numpy = out, into


@pytest.fixture
def on_device(monkeypatch):
    """BatchSims made in the test keep their state in a `Counted` mirror."""
    monkeypatch.setattr(sim_mod, "mirror", lambda host, on_host: Counted(host))


def _envs(task: str, n: int, device: bool, monkeypatch) -> BatchEnv:
    rng = np.random.default_rng(3)
    bodies = [sample_robot((5, 5), rng) for _ in range(n)]
    if device:
        with monkeypatch.context() as m:
            m.setattr(sim_mod, "mirror", lambda host, on_host: Counted(host))
            return BatchEnv(task, bodies, episode_steps=40, fused=True)
    return BatchEnv(task, bodies, episode_steps=40, fused=True)


def _actions(env: BatchEnv, t: int) -> np.ndarray:
    a = 1.0 + 0.5 * np.sin(0.4 * t + np.arange(env.sim.max_actuators))[None, :]
    return np.repeat(a, env.n_worlds, axis=0)


@pytest.mark.parametrize("task", ["Walker-v0", "Carrier-v0", "Climber-v2"])
def test_a_device_state_gives_the_hosts_bits_through_reads_writes_and_resets(task, monkeypatch):
    """The same run with the state on the 'device' and on the host: observations, rewards and
    states equal to the bit, through outside reads, an outside write (a nudge), a partial reset
    (on the device by its kernel) and a state assigned whole (on the host, the same values written
    in place)."""
    parity(task, monkeypatch)


@pytest.mark.slow
@pytest.mark.subprocess
def test_a_device_state_gives_the_hosts_bits_in_f32():
    """The same in an f32 process, where a reset also writes the placement's low parts."""
    code = ("import pytest; from tests.tsim.backend.test_mirror import parity; "
            "[parity(t, pytest.MonkeyPatch()) for t in ('Walker-v0', 'Catcher-v0')]; "
            "from tsim.backend import runtime; print('ok', runtime.precision())")
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300,
                       env={**os.environ, "SGR_PRECISION": "f32", "PYTHONPATH": str(ROOT)})
    assert r.returncode == 0, r.stderr[-2000:]
    assert "ok f32" in r.stdout


def parity(task: str, monkeypatch) -> None:
    """`test_a_device_state_gives_the_hosts_bits_through_reads_writes_and_resets` of one task."""
    host, dev = _envs(task, 5, False, monkeypatch), _envs(task, 5, True, monkeypatch)
    assert isinstance(dev.sim._state_m, Counted) and not isinstance(host.sim._state_m, Counted)
    for t in range(24):
        outs = [e.step(_actions(e, t)) for e in (host, dev)]
        for a, b in zip(outs[0][:4], outs[1][:4], strict=True):
            assert a.tobytes() == b.tobytes(), t
        if t == 5:
            assert host.sim.read_state().tobytes() == dev.sim.read_state().tobytes()
        if t == 9:  # an outside write through `state`: the next step starts from it
            for e in (host, dev):
                e.sim.state[:, :, 2] += 0.01
        if t == 13:
            mask = np.array([True, False, True, False, False])
            obs = [e.sim.reset(mask) or e.observe() for e in (host, dev)]
            assert obs[0].tobytes() == obs[1].tobytes()
        if t == 17:  # a whole state assigned: copied in, the next step starts from it as from
            # the same values written in place
            nudged = host.sim.read_state().copy()
            nudged[:, :, 3] += 0.02
            host.sim.state[...] = nudged
            dev.sim.state = nudged
            assert host.observe().tobytes() == dev.observe().tobytes()
        if t == 19:  # a view of the state kept across a step, then assigned: on the host it saw
            # the step, so the assignment changes nothing; so on the device
            kept = [e.sim.read_state() for e in (host, dev)]
        if t == 20:
            host.sim.state, dev.sim.state = kept
            assert host.observe().tobytes() == dev.observe().tobytes()
    assert host.sim.read_state().tobytes() == dev.sim.read_state().tobytes()
    assert np.array_equal(host.sim.counts, dev.sim.counts)


def test_a_partial_reset_on_the_device_starts_from_the_placement_as_it_now_is(monkeypatch):
    """The placement a partial reset on the device starts from (`kernel_initial_positions`) is
    copied there once per placement: a write through `initial_positions` and a `shift_robots`
    each reach the next partial reset (the kernels' constant arrays copied here, as a device
    holds its own copy)."""
    monkeypatch.setattr(sim_mod, "constant", lambda a, on_host: np.array(a))
    host, dev = _envs("Walker-v0", 4, False, monkeypatch), _envs("Walker-v0", 4, True, monkeypatch)
    mask = np.array([True, False, True, True])

    def lift(sim):
        sim.initial_positions[:, :, 1] += 0.01

    for t, change in enumerate((lift, lambda sim: sim.shift_robots(np.full(4, 0.02)), lift)):
        for e in (host, dev):
            e.step(_actions(e, t))
            change(e.sim)
            e.sim.reset(mask)
        assert host.sim.read_state().tobytes() == dev.sim.read_state().tobytes(), t


def test_stepping_an_env_moves_no_state_between_device_and_host(monkeypatch):
    """Walker-v0's observations and rewards come from kernels over the device's state, so steps
    copy nothing; a read copies the state out once, a write then copies it in once, and a full
    reset needs nothing back."""
    env = _envs("Walker-v0", 4, True, monkeypatch)
    m = env.sim._state_m
    env.step(_actions(env, 0))  # the first step copies in the reset's state
    start = dict(m.copies)
    for t in range(1, 11):
        env.step(_actions(env, t))
    assert m.copies == start
    env.sim.read_state()
    env.sim.read_state()
    assert m.copies == {"in": start["in"], "out": start["out"] + 1}
    env.step(_actions(env, 11))
    assert m.copies == {"in": start["in"], "out": start["out"] + 1}  # a read is not a write
    env.sim.state[0, 0, 2] += 0.0
    env.step(_actions(env, 12))
    assert m.copies == {"in": start["in"] + 1, "out": start["out"] + 2}
    env.sim.reset()
    env.step(_actions(env, 0))
    assert m.copies == {"in": start["in"] + 2, "out": start["out"] + 2}
    # a partial reset is made on the device (`tsim.kernels.reset`): nothing crosses
    for t in range(1, 4):
        env.step(_actions(env, t))
    env.reset(np.array([True, False, True, False]))
    env.step(_actions(env, 4))
    assert m.copies == {"in": start["in"] + 2, "out": start["out"] + 2}


def test_read_state_is_read_only_and_a_wrong_shape_is_refused(on_device):
    env = _envs("Walker-v0", 2, False, None)
    with pytest.raises(ValueError, match="read-only"):
        env.sim.read_state()[0, 0, 0] = 1.0
    with pytest.raises(ValueError, match="a state must have shape"):
        env.sim.state = np.zeros((1, 2, 3))


def test_sgr_device_mirror_makes_the_cpu_use_a_device_mirror(monkeypatch):
    """SGR_DEVICE_MIRROR=1 (a testing aid) gives the CPU a DeviceMirror, so that a test run under
    it catches code relying on a kept state reference; without it the CPU passes numpy itself."""
    from tasks.specs import task_world
    from tsim.sim import BatchSim

    body = sample_robot((5, 5), np.random.default_rng(0))
    monkeypatch.setenv("SGR_DEVICE_MIRROR", "1")
    assert isinstance(BatchSim(task_world("Walker-v0"), [body], (1, 1))._state_m, mirror_mod.DeviceMirror)
    monkeypatch.delenv("SGR_DEVICE_MIRROR")
    assert isinstance(BatchSim(task_world("Walker-v0"), [body], (1, 1))._state_m, mirror_mod.HostArray)


def test_the_kernels_placement_is_copied_again_only_after_it_may_have_changed(monkeypatch):
    """`kernel_initial_positions` keeps its copy through reads that cannot change the placement
    (object and robot positions, steps, partial resets) and makes a new one after a write through
    `initial_positions`, a `shift_robots` or a `place_object`."""
    env = _envs("Carrier-v0", 3, True, monkeypatch)
    sim = env.sim
    kept = sim.kernel_initial_positions()
    env.step(_actions(env, 0))
    sim.object_pos(0, sim.free_objects[0].name)
    sim.object_vel(0, sim.free_objects[0].name)
    sim.robot_pos(0)
    sim.reset(np.array([True, False, True]))
    assert sim.kernel_initial_positions() is kept
    for change in (lambda: sim.initial_positions, lambda: sim.shift_robots(np.zeros(3)),
                   lambda: sim.place_object(0, sim.free_objects[0].name, (2, 2))):
        change()
        assert sim.kernel_initial_positions() is not kept
        kept = sim.kernel_initial_positions()
