"""The step kernels are interchangeable: the fast local-array kernel (worlds <= 64 points), its
serial twin and the generic kernel (any size) give bit-identical states, so large robots follow
the same physics as the validated small ones."""

import numpy as np
import pytest

from tasks.specs import task_spec
from tsim.sampling import sample_robot
from tsim.sim import BatchSim
from tsim.world import task_world


def _run(task: str, bodies, steps: int, kernel: str) -> BatchSim:
    sim = BatchSim(task_world(task), bodies, task_spec(task).origin)
    if kernel == "generic":
        sim._small = False
    else:
        sim._serial = kernel == "serial"
    for t in range(steps):
        phase = np.arange(sim.max_actuators)[None, :] * 0.7 + np.arange(len(bodies))[:, None]
        sim.set_actions(1.1 + 0.45 * np.sin(t / 6.0 + phase))
        sim.step()
    return sim


@pytest.mark.parametrize("task", ["Walker-v0", "ObstacleTraverser-v1", "Thrower-v0"])
def test_fast_serial_and_generic_kernels_agree_bit_for_bit(task):
    rng = np.random.default_rng(11)
    bodies = [sample_robot((5, 5), rng) for _ in range(4)]
    sims = {k: _run(task, bodies, 60, k) for k in ("parallel", "serial", "generic")}
    ref = sims["parallel"]
    assert ref._small  # these bodies take the fast kernel unless forced
    for k in ("serial", "generic"):
        assert np.array_equal(sims[k].state[..., 0:4], ref.state[..., 0:4]), k
        assert np.array_equal(sims[k].counts, ref.counts), k
    moved = ref.state[:, :, 0:2] - ref._pos0
    assert np.abs(moved).max() > 0.05  # the robots did move (and touched ground or the box)
