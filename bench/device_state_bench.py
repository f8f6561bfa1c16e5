"""The state kept on the device between env steps (tsim/backend/mirror.py, issue 48 item 2) against the
state passed as a numpy array to every launch (what a device backend did before: Taichi copies it
in before each launch and out after), side by side, alternating, in this process's backend.

    SGR_ARCH=vulkan python bench/device_state_bench.py [--task Walker-v0] [--robots 256]
                                                      [--steps 20] [--rounds 3] [--record PATH]

Prints env robot-steps/s of each (the best of --rounds, each a run of --steps `BatchEnv.step`s
after one warm-up step) and the state's bytes per world, which the numpy way moved twice per launch.
On the CPU the two are the same code (the kernels take the numpy array itself), so run it on a
device: a GPU, or Vulkan (Mesa's lavapipe keeps its "device" memory in host RAM, so there it
measures Taichi's copies and launch work, not a bus).
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def run(task: str, bodies: list, steps: int, keep_on_device: bool) -> tuple[float, int]:
    """(env robot-steps/s, state bytes per world) of `steps` env steps, state on the device or not."""
    import tsim.sim as sim_mod
    from tasks.env import BatchEnv
    from tsim.backend.mirror import HostArray, mirror

    make = mirror if keep_on_device else (lambda host, on_host: HostArray(host))
    saved, sim_mod.mirror = sim_mod.mirror, make
    try:
        env = BatchEnv(task, bodies, episode_steps=steps + 2)
    finally:
        sim_mod.mirror = saved
    acts = np.full((env.n_worlds, env.sim.max_actuators), 1.2)
    env.step(acts)  # compiles, and copies the reset's state in
    t = time.perf_counter()
    for k in range(steps):
        acts[:] = 1.2 if k % 2 else 0.8
        env.step(acts)
    dt = time.perf_counter() - t
    B, P, cols = env.sim.state_shape
    return env.n_worlds * steps / dt, P * cols * np.dtype(env.sim.dtype).itemsize


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", default="Walker-v0")
    ap.add_argument("--robots", type=int, default=256)
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--record", metavar="PATH", help="also write a record (tasks/records.py)")
    a = ap.parse_args()

    from tasks.records import cpu_model
    from tsim import backend
    from tsim.sampling import sample_robots

    bodies = list(sample_robots(a.robots, (5, 5), np.random.default_rng(0)))
    be = backend.get()
    best = {"device": 0.0, "numpy": 0.0}
    per_world = 0
    for r in range(a.rounds):
        order = (("device", True), ("numpy", False))
        for name, keep in order if r % 2 == 0 else order[::-1]:
            rate, per_world = run(a.task, bodies, a.steps, keep)
            best[name] = max(best[name], rate)
            print(f"round {r}: state {name:>6}: {rate:,.0f} env robot-steps/s", flush=True)
    print(f"{be.line()}; {cpu_model()}; {a.task}, B = {a.robots}, "
          f"5x5: state on the device {best['device']:,.0f}, numpy through every launch "
          f"{best['numpy']:,.0f} env robot-steps/s ({best['device'] / best['numpy']:.2f}x); "
          f"the state is {per_world:,} bytes per world"
          + (" (on the CPU both are the same code)" if be.on_host else ""))
    if a.record:
        from tasks.records import figure, write_record

        write_record(a.record, None, {
            "state_on_device": figure(round(best["device"]), "env robot-steps/s"),
            "state_through_numpy": figure(round(best["numpy"]), "env robot-steps/s"),
            "state_bytes_per_world": figure(per_world, "bytes")}, task=a.task, robots=a.robots)


if __name__ == "__main__":
    main()
