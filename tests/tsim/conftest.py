"""What the kernel tests share: one way to drive a batch through a few steps."""

from collections.abc import Callable

import numpy as np

from tsim.sim import BatchSim


def drive(sim: BatchSim, steps: int, before_step: Callable[[BatchSim, int], None] | None = None) -> BatchSim:
    """Step `sim` `steps` times under sinusoidal actions, a phase per actuator and per world (so
    every world and spring moves differently); `before_step(sim, t)` may change the state first."""
    n_worlds = sim.state.shape[0]
    phase = np.arange(sim.max_actuators)[None, :] * 0.7 + np.arange(n_worlds)[:, None]
    for t in range(steps):
        sim.set_actions(1.1 + 0.45 * np.sin(t / 6.0 + phase))
        if before_step is not None:
            before_step(sim, t)
        sim.step()
    return sim
