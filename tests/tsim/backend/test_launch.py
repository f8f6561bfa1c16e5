"""`BatchSim.step` re-launches its kernel from a cached launch context (tsim/backend/launch.py): it must
compute exactly what Taichi's own call computes, and notice when its arguments change."""

import numpy as np
import pytest

from tasks.specs import task_world
from tsim import kernels as K
from tsim.sampling import sample_robot
from tsim.sim import BatchSim


def _pair(n: int = 4):
    rng = np.random.default_rng(11)
    bodies = [sample_robot((5, 5), rng) for _ in range(n)]
    return (BatchSim(task_world("Walker-v0"), bodies, (1, 1)),
            BatchSim(task_world("Walker-v0"), bodies, (1, 1)))


def _step_both(cached: BatchSim, plain: BatchSim, t: int) -> None:
    """One step of each; `plain` forgets its cached launch, so Taichi's call runs every time."""
    a = 1.0 + 0.5 * np.sin(0.3 * t + np.arange(cached.max_actuators))[None, :]
    for sim in (cached, plain):
        sim.set_actions(np.repeat(a, sim.n_worlds, axis=0))
    cached.step()
    plain._launch = None
    plain.step()


def test_cached_launches_compute_what_taichis_call_computes():
    cached, plain = _pair()
    for t in range(20):
        _step_both(cached, plain, t)
    assert cached._launch is not None  # the cached path did run (CPU)
    assert cached.state.tobytes() == plain.state.tobytes()
    assert np.array_equal(cached.counts, plain.counts)


@pytest.mark.slow
def test_cached_launch_follows_replaced_arrays_and_changed_arguments():
    cached, plain = _pair()
    for t in range(5):
        _step_both(cached, plain, t)
    # a state assigned whole to one (copied into the simulator's own array, which the cached
    # launch keeps writing), the same values written in place into the other; and actions in
    # column-major order (not cached: Taichi's call copies them to row-major order each time)
    nudged = cached.read_state().copy()
    nudged[:, :, 2] += 0.05
    cached.state = nudged
    plain.state[...] = nudged
    for sim in (cached, plain):
        sim.actions = np.asfortranarray(sim.actions)
    for t in range(5, 10):
        _step_both(cached, plain, t)
    assert cached.state.tobytes() == plain.state.tobytes()
    # a full reset replaces `counts`; a world deactivated afterwards must stay frozen
    for sim in (cached, plain):
        sim.actions = np.ascontiguousarray(sim.actions)
        sim.reset()
        sim.deactivate(np.array([False, True, False, False]))
    frozen = cached.state[1].copy()
    for t in range(10, 15):
        _step_both(cached, plain, t)
    assert cached.state.tobytes() == plain.state.tobytes()
    assert np.array_equal(cached.state[1], frozen)
    # a different compiled kernel (sweep and prune forced on) is launched, not the cached one
    before = cached._launch
    for sim in (cached, plain):
        sim.sweep_mode = K.SWEEP_ALWAYS
    for t in range(15, 20):
        _step_both(cached, plain, t)
    assert cached.state.tobytes() == plain.state.tobytes()  # the same bits either way, so:
    assert cached._launch is not before and cached._launch is not None


def test_cached_launch_is_for_its_kernel_only():
    """Two kernels with the same signature and arguments: the context of one must not be reused
    for the other (it would run the first kernel's code)."""
    from tsim.backend import runtime
    from tsim.backend.launch import CachedLaunch

    ti = runtime.ti
    arr = ti.types.ndarray(dtype=ti.f64, ndim=1)

    @ti.kernel
    def add_one(x: arr):
        for i in range(x.shape[0]):
            x[i] += 1.0

    @ti.kernel
    def double(x: arr):
        for i in range(x.shape[0]):
            x[i] *= 2.0

    x = np.ones(4)
    add_one(x)
    cached = CachedLaunch.build(add_one, (x,))
    assert cached is not None and cached.matches(add_one, (x,))
    assert not cached.matches(double, (x,))
    cached.launch()
    assert np.array_equal(x, np.full(4, 3.0))  # the cached launch ran add_one again
