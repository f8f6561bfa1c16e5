"""Rendering a task episode: `tsim.render` draws worlds, this drives one robot through a task."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from tasks.env import BatchEnv
from tsim.body import Body
from tsim.errors import SgrError
from tsim.render import Renderer

FRAME_BYTES = 4 << 30  # the most an episode's frames may hold: more would fill memory before the GIF


def render_episode(task: str, body: Body | object, policy: Callable[[int, np.ndarray], np.ndarray],
                   steps: int | None = None, width: int = 640, height: int = 320, *, every: int = 1,
                   indexed: bool = False, start_shift: float = 0.0, precision: str | None = None,
                   **renderer_kw) -> list[np.ndarray]:
    """Simulate one robot on `task` for `steps` env steps (task default if None) with actions
    `policy(t, obs)` and return frames: the reset state, then every `every`-th step (and the last).

    Frames are RGB (H, W, 3), or `PALETTE` indices (H, W) with `indexed` (faster, same GIF). Stops
    early when the episode terminates (goal reached or unstable). `start_shift` starts the robot
    that much right of its placement (`BatchEnv`'s robot_shift). `precision`: the real type to
    simulate in (None: the process's). `renderer_kw` go to `Renderer`.
    """
    if every < 1:
        raise ValueError(f"every must be >= 1, got {every}")
    env = BatchEnv(task, [body], episode_steps=steps, robot_shift=[start_shift] if start_shift else None,
                   precision=precision)
    frames_at_most = env.episode_steps // every + 2
    need = frames_at_most * width * height * (1 if indexed else 3)
    if need > FRAME_BYTES:
        raise SgrError(f"{frames_at_most:,} frames of {width}x{height} would hold {need / 2**30:.0f} GiB "
                       f"(at most {FRAME_BYTES >> 30} GiB): render fewer steps or smaller frames")
    renderer = Renderer(env.sim.world, env.sim.bodies[0], width, height, **renderer_kw)
    names = [o.name for o in env.sim.free_objects]
    draw = renderer.frame_indexed if indexed else renderer.frame

    def snap() -> np.ndarray:
        return draw(env.sim.robot_pos(0), {n: env.sim.object_pos(0, n) for n in names})

    frames = [snap()]
    obs = env.robot_obs(0)
    for t in range(env.episode_steps):
        action = np.asarray(policy(t, obs), dtype=np.float64).reshape(-1)
        _, _, term, _, _ = env.step([action])
        obs = env.robot_obs(0)
        if (t + 1) % every == 0 or term[0] or t + 1 == env.episode_steps:
            frames.append(snap())
        if term[0]:
            break
    return frames
