"""The step kernel's variants are interchangeable: the parallel and serial kernels, every
local-array capacity tier and every way of finding contact pairs (plain loop, sweep and prune,
pair lists) give bit-identical states, so large robots (which need a bigger tier) and long worlds
(swept) follow the same physics as the validated 5x5 ones."""

import numpy as np
import pytest

from tasks.specs import task_spec, task_world
from tests.tsim.conftest import drive
from tsim import kernels as K
from tsim.sampling import sample_robot
from tsim.sim import BatchSim

pytestmark = pytest.mark.slow


def _run(task: str, bodies, steps: int, serial: bool, extra_tiers: int = 0,
         sweep: int | None = None, pair_list: int | None = None, drop: float = 0.0) -> BatchSim:
    sim = BatchSim(task_world(task), bodies, task_spec(task).origin)
    for w in range(len(bodies)):  # objects thrown down at `drop` units/s
        sim.state[w, sim.n_robot_points[w]:sim.counts[w, K.N_PTS], 3] = -drop
    sim.choose_kernel(serial=serial, extra_capacity_tiers=extra_tiers)
    if sweep is not None:
        sim.sweep_mode = sweep
    if pair_list is not None:
        sim.pair_list = pair_list
    return drive(sim, steps)


def _same(a: BatchSim, b: BatchSim) -> bool:
    return np.array_equal(a.state[..., 0:4], b.state[..., 0:4]) and np.array_equal(a.counts, b.counts)


@pytest.mark.parametrize("task", ["Walker-v0", "ObstacleTraverser-v1", "Thrower-v0"])
def test_parallel_serial_and_bigger_capacity_kernels_agree_bit_for_bit(task):
    rng = np.random.default_rng(11)
    bodies = [sample_robot((5, 5), rng) for _ in range(4)]
    ref = _run(task, bodies, 60, serial=False)
    assert ref.capacity_tier == 0  # 5x5 robots (and Thrower's box) fit the smallest tier
    assert _same(_run(task, bodies, 60, serial=True), ref)
    assert _same(_run(task, bodies, 60, serial=False, extra_tiers=1), ref)
    moved = ref.state[:, :, 0:2] - ref.initial_positions
    assert np.abs(moved).max() > 0.05  # the robots did move (and touched ground or the box)


def test_large_robots_take_a_bigger_tier_with_the_same_results():
    rng = np.random.default_rng(5)
    bodies = [sample_robot((8, 8), rng) for _ in range(3)]
    sim = _run("Walker-v0", bodies, 40, serial=False)
    assert sim.capacity_tier == 1 and sim.state.shape[1] > 64
    assert _same(_run("Walker-v0", bodies, 40, serial=False, extra_tiers=1), sim)
    assert np.all(np.isfinite(sim.state)) and not sim.unstable.any()


@pytest.mark.parametrize("task", ["BridgeWalker-v0", "Climber-v1"])
def test_sweep_and_prune_finds_the_plain_loops_pairs_in_its_order(task):
    """BridgeWalker's bridge (swept along x) and Climber-v1's wall (along y) are simulated objects
    of ~200 surface voxels, so their own pairs and the robot's contacts with them go through the
    pair loop: the same bits with the sweep forced on, off, and as chosen per world (on here; off
    for compact bodies)."""
    rng = np.random.default_rng(3)
    bodies = [sample_robot((5, 5), rng) for _ in range(3)]
    off = _run(task, bodies, 50, serial=True, sweep=K.SWEEP_OFF, pair_list=K.LIST_OFF)
    assert _same(_run(task, bodies, 50, serial=True, sweep=K.SWEEP_ALWAYS), off)
    auto = _run(task, bodies, 50, serial=True)
    assert auto.sweep_mode == K.SWEEP_AUTO
    assert _same(auto, off)
    assert _run("Walker-v0", bodies, 1, serial=True).sweep_mode == K.SWEEP_OFF
    moved = off.state[:, :, 0:2] - off.initial_positions
    assert np.abs(moved).max() > 0.05


@pytest.mark.parametrize("task, size, n, steps, drop", [
    ("Walker-v0", 12, 3, 40, 0.0),  # large compact bodies: the list is chosen
    # the package thrown onto the robot at 40 units/s closes a gap of SKIN within an env step:
    # fails if the list is never rebuilt within the env step, if it misses pairs within SKIN or
    # if it lists them out of order (checked by editing the kernel). Not caught: a rebuild after
    # SKIN instead of SKIN / 2 (only one side moves here) and a list overflow (none happens)
    ("Thrower-v0", 5, 4, 30, 40.0),
    ("BridgeWalker-v0", 5, 3, 50, 0.0),  # listed while swept: the robot walks on the bridge
])
def test_pair_lists_test_the_pairs_that_act_in_the_plain_loops_order(task, size, n, steps, drop):
    """A substep that tests only the pairs listed at an earlier one (within SKIN of each other
    then; rebuilt once a box has moved SKIN / 2) gives the bits of testing every pair."""
    rng = np.random.default_rng(7)
    bodies = [sample_robot((size, size), rng) for _ in range(n)]
    off = _run(task, bodies, steps, serial=True, sweep=K.SWEEP_OFF, pair_list=K.LIST_OFF,
               drop=drop)
    auto = _run(task, bodies, steps, serial=True, drop=drop)
    assert _same(auto, off)
    if size == 5 and task != "BridgeWalker-v0":  # 5x5 bodies run the kernel without lists...
        assert auto.pair_list == K.LIST_OFF
        listed = _run(task, bodies, steps, serial=True, pair_list=K.LIST_ALWAYS, drop=drop)
        assert _same(listed, off)
    else:  # ...large bodies and long worlds the one with them
        assert auto.pair_list == K.LIST_AUTO
    moved = off.state[:, :, 0:2] - off.initial_positions
    assert np.abs(moved).max() > 0.05
