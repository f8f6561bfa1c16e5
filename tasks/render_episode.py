"""Rendering a task episode: `tsim.render` draws worlds, this drives one robot through a task."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from tasks.env import BatchEnv
from tsim.body import Body
from tsim.render import Renderer
from tsim.render import caption as write_caption

FRAME_BYTES = 2 << 30  # the most an episode's frames may hold (the GIF writer copies them once more)


def frame_stride(steps: int, width: int, height: int, indexed: bool) -> int:
    """The least k such that the reset frame and every k-th step's (and the last) fit FRAME_BYTES."""
    most = max(2, FRAME_BYTES // (width * height * (1 if indexed else 3)))  # frames
    return max(1, math.ceil(steps / (most - 1)))  # 1 + ceil(steps / k) frames are kept


def render_episode(task: str, body: Body | object, policy: Callable[[int, np.ndarray], np.ndarray],
                   steps: int | None = None, width: int = 640, height: int = 320, *, every: int = 1,
                   indexed: bool = False, start_shift: float = 0.0, precision: str | None = None,
                   caption: Callable[[int, float], str] | None = None, **renderer_kw) -> list[np.ndarray]:
    """Simulate one robot on `task` for `steps` env steps (task default if None) with actions
    `policy(t, obs)` and return frames: the reset state, then every `every`-th step (and the last).
    An episode whose frames would hold more than FRAME_BYTES keeps every k-th step's instead, k the
    least that fits (a 1,000,000-step episode at 640x320: every 96th), so that any episode a run may
    have can be drawn.

    Frames are RGB (H, W, 3), or `PALETTE` indices (H, W) with `indexed` (faster, same GIF). Stops
    early when the episode terminates (goal reached or unstable). `start_shift` starts the robot
    that much right of its placement (`BatchEnv`'s robot_shift). `precision`: the real type to
    simulate in (None: the process's). `caption(t, running_return)`: a line written on each frame
    (the steps done and the return so far; `tsim.render.caption`). `renderer_kw` go to `Renderer`.
    """
    if every < 1:
        raise ValueError(f"every must be >= 1, got {every}")
    env = BatchEnv(task, [body], episode_steps=steps, robot_shift=[start_shift] if start_shift else None,
                   precision=precision)
    every = max(every, frame_stride(env.episode_steps, width, height, indexed))
    renderer = Renderer(env.sim.world, env.sim.bodies[0], width, height, **renderer_kw)
    names = [o.name for o in env.sim.free_objects]
    draw = renderer.frame_indexed if indexed else renderer.frame

    total = 0.0

    def snap(t: int) -> np.ndarray:
        frame = draw(env.sim.robot_pos(0), {n: env.sim.object_pos(0, n) for n in names})
        return frame if caption is None else write_caption(frame, caption(t, total))

    frames = [snap(0)]
    obs = env.robot_obs(0)
    for t in range(env.episode_steps):
        action = np.asarray(policy(t, obs), dtype=np.float64).reshape(-1)
        _, reward, term, _, _ = env.step([action])
        total += float(reward[0])
        obs = env.robot_obs(0)
        if (t + 1) % every == 0 or term[0] or t + 1 == env.episode_steps:
            frames.append(snap(t + 1))
        if term[0]:
            break
    return frames
