"""gymnasium adapters: `SgrEnv` (one robot) and `SgrVectorEnv` (many robots, one Taichi batch).

Both wrap `BatchEnv`, so a single env and a batch compute exactly the same numbers. Spaces are
evogym's: actions Box(0.6, 1.6, (n_actuators,)), observations Box(-100, 100, (obs_dim,)), float64.
Truncation of `gymnasium.make("sgr/<task>", body=m)` comes from gymnasium's TimeLimit with the
paper's episode length; pass `max_episode_steps=` for another (evogym's: `EVOGYM_STEPS[task]`).
`gymnasium.make_vec("sgr/<task>", num_envs=n, body=m)` or `(..., bodies=[...])` gives the
batched `SgrVectorEnv`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv

from tasks.env import BatchEnv
from tasks.specs import TASKS
from tsim import constants as C
from tsim.body import build_body
from tsim.render import Renderer

OBS_BOUND = 100.0
_NO_LIMIT = 2**62  # BatchEnv's own limit is disabled; TimeLimit / episode_steps decides
EVOGYM_STEPS = {name: spec.evogym_steps for name, spec in TASKS.items()}


def _obs_space(n: int) -> gym.spaces.Box:
    return gym.spaces.Box(-OBS_BOUND, OBS_BOUND, (n,), dtype=np.float64)


def _action_space(n: int) -> gym.spaces.Box:
    return gym.spaces.Box(C.ACTION_MIN, C.ACTION_MAX, (n,), dtype=np.float64)


class SgrEnv(gym.Env):
    """One evogym task with one robot. `body` is the 5x5 (or any) voxel matrix."""

    def __repr__(self) -> str:
        from tsim.body import describe_body

        return f"SgrEnv({self.task!r}, {describe_body(self._env.sim.bodies[0].matrix)})"

    metadata = {"render_modes": ["rgb_array", "img"], "render_fps": 50}

    def __init__(self, task: str, body: Any, episode_steps: int | None = None,
                 render_mode: str | None = None, connections: Any = None,
                 render_options: dict | None = None, precision: str | None = None):
        """evogym's keyword arguments: `connections` (2, k) glue the body's voxels (default: every
        adjacent pair); `render_mode` 'rgb_array' / 'img' make `render()` return an image
        (`render_options` {'hide_grid': True} drops the grid); windows: sgr.evogym's bare ids.
        `precision`: the simulator's real type (None: the process's; `tsim.backend.get`)."""
        if render_mode not in (None, "rgb_array", "img"):
            raise ValueError(f"render_mode {render_mode!r} is not supported here (None, 'rgb_array', "
                             "'img'); for a window use the bare ids of sgr.evogym.envs")
        if connections is not None:
            body = build_body(np.asarray(body), np.asarray(connections))
        self._env = BatchEnv(task, [body], episode_steps=_NO_LIMIT if episode_steps is None
                             else episode_steps, precision=precision)
        self.render_mode = render_mode
        self._render_options = render_options or {}
        self._renderer: Renderer | None = None
        self.task = task
        self.observation_space = _obs_space(int(self._env.obs_dims[0]))
        self.action_space = _action_space(int(self._env.n_actuators[0]))

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start a new episode; return its first observation and an empty info dict.

        The physics is deterministic; a task with per-episode randomness (Catcher-v0's placement,
        BidirectionalWalker-v0's goals) draws from the env's stream at every reset, restarted from
        `seed` when one is given (evogym's draw after `random.seed(seed); env.reset()`).

        Args:
            seed: Restart the task's random stream from this seed.
            options: Unused (gymnasium's API).
        """
        super().reset(seed=seed)
        if seed is not None:  # per-episode task randomness (BidirectionalWalker's goals)
            self._env.seed([seed])
        return self._env.reset()[0, :self.observation_space.shape[0]].copy(), {}

    def step(self, action):
        """Advance the robot by one env step: gymnasium's (obs, reward, terminated, truncated, info).

        Truncates only with `episode_steps`, otherwise gymnasium's TimeLimit does. `info` holds
        `unstable`.

        Args:
            action (ArrayLike): (n_actuators,) actuator targets, clipped to [0.6, 1.6].

        Raises:
            ValueError: When `action` is not of shape (n_actuators,).
        """
        a = np.asarray(action, dtype=np.float64)
        if a.shape != self.action_space.shape:
            raise ValueError(f"wrong action shape: expected {self.action_space.shape}, got {a.shape}")
        obs, r, term, trunc, info = self._env.step(a[None, :])
        return (obs[0, :self.observation_space.shape[0]].copy(), float(r[0]), bool(term[0]),
                bool(trunc[0]), {"unstable": bool(info["unstable"][0])})

    def render(self) -> np.ndarray | None:
        """An image of the robot and the world's objects now, or None without a render mode.

        Drawn by tsim's renderer, the camera following the robot.

        Returns:
            An (H, W, 3) uint8 image, or None when the env has no render mode.
        """
        if self.render_mode is None:
            return None
        sim = self._env.sim
        if self._renderer is None:
            self._renderer = Renderer(sim.world, sim.bodies[0],
                                      grid=not self._render_options.get("hide_grid", False))
        return self._renderer.frame(sim.robot_pos(0), sim.objects_pos(0))

    def robot_points(self) -> np.ndarray:
        """(2, N) robot point positions in evogym's point order, world units."""
        return self._env.sim.robot_pos(0)

    def object_points(self, name: str = "package") -> np.ndarray:
        """(2, M) points of a free object, e.g. Thrower-v0's box ("package")."""
        return self._env.sim.object_pos(0, name)

    @property
    def batch_env(self) -> BatchEnv:
        """The underlying one-world `BatchEnv`, for what gymnasium's API does not expose.

        Its `sim` and `spec`, for instance.
        """
        return self._env


class SgrVectorEnv(VectorEnv):
    """All robots of `bodies` in one batched simulation (gymnasium VectorEnv, same-step autoreset).

    Mixed bodies: observation and action lengths differ per robot, so rows are padded to the
    largest: observations (num_envs, max_obs_dim) with zeros after robot i's `obs_dims[i]`
    entries, actions (num_envs, max_actuators) of which robot i reads its first `n_actuators[i]`.
    When a robot's episode ends its world is reset in the same call; the final observation is
    in `info["final_obs"]` (rows of finished robots) with `info["_final_obs"]` the mask.
    """

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP}

    def __init__(self, task: str, bodies: Sequence[Any] | None = None, *, body: Any = None,
                 num_envs: int | None = None, max_episode_steps: int | None = None,
                 connections: Any = None):
        """`bodies` (one per robot), or `body` (with evogym's `connections`, optional) repeated
        `num_envs` times."""
        if (bodies is None) == (body is None):
            raise ValueError("give either bodies=[...] (one per robot) or body= with num_envs")
        if connections is not None:
            if body is None:
                raise ValueError("connections= goes with body=; give bodies=[...] as built bodies")
            body = build_body(np.asarray(body), np.asarray(connections))
        if bodies is None:
            bodies = [body] * (1 if num_envs is None else int(num_envs))
        elif num_envs not in (None, 1, len(bodies)):  # make_vec passes num_envs=1 by default
            raise ValueError(f"num_envs={num_envs} but {len(bodies)} bodies given")
        self._env = BatchEnv(task, list(bodies), episode_steps=max_episode_steps)
        self.num_envs = self._env.n_worlds
        self.obs_dims = self._env.obs_dims.copy()
        self.n_actuators = self._env.n_actuators.copy()
        self.single_observation_space = _obs_space(self._env.max_obs_dim)
        self.single_action_space = _action_space(self._env.sim.max_actuators)
        self.observation_space = gym.vector.utils.batch_space(self.single_observation_space,
                                                              self.num_envs)
        self.action_space = gym.vector.utils.batch_space(self.single_action_space, self.num_envs)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Reset every robot; return the observations and an empty info dict.

        Args:
            seed: Restart robot i's task stream from seed + i (see `SgrEnv.reset`).
            options: Unused (gymnasium's API).
        """
        super().reset(seed=seed)
        if seed is not None:  # world i's task stream from seed + i
            self._env.seed(seed)
        return self._env.reset(), {}

    def step(self, actions):
        """Advance every robot by one env step; robots whose episode ended are reset in this call.

        This is gymnasium's same-step autoreset; the class tells where the final observations are.

        Args:
            actions (ArrayLike): (num_envs, max_actuators), padded as the class tells.
        """
        obs, reward, term, trunc, info = self._env.step(np.asarray(actions, dtype=np.float64))
        done = term | trunc
        out = {"unstable": info["unstable"], "_unstable": np.ones(self.num_envs, dtype=bool)}
        if done.any():
            out["final_obs"] = np.where(done[:, None], obs, 0.0)
            out["_final_obs"] = done
            obs = self._env.reset(mask=done)
        return obs, reward, term, trunc, out

    def robot_points(self, i: int) -> np.ndarray:
        """(2, N_i) point positions of robot i, evogym's point order, world units."""
        return self._env.sim.robot_pos(i)

    @property
    def batch_env(self) -> BatchEnv:
        """The underlying `BatchEnv` of all robots, for what gymnasium's API does not expose.

        Its `sim` and `spec`, for instance.
        """
        return self._env


def register_id(env_id: str, **kwargs: Any) -> None:
    """`gym.register(env_id, **kwargs)`, the id a task of its own rather than a version of another.

    evogym's ids end in -v0, -v1, ... but Carrier-v0 and Carrier-v1 are different tasks, not
    versions of one: gymnasium would warn on `gym.make("sgr/Carrier-v0")` that it "is out of date"
    and suggest v1. Each id's spec is named with its version (`Carrier-v0`), so gymnasium finds no
    other version of it.
    """
    gym.register(env_id, **kwargs)
    spec = gym.registry[env_id]
    if spec.version is not None:
        spec.name = f"{spec.name}-v{spec.version}"


def register_envs() -> None:
    """Register `sgr/<task>` ids (idempotent); `import tasks` does this."""
    for name, spec in TASKS.items():
        env_id = f"sgr/{name}"
        if env_id in gym.registry:
            continue
        register_id(env_id, entry_point="tasks.gym_env:SgrEnv",
                    vector_entry_point="tasks.gym_env:SgrVectorEnv", kwargs={"task": name},
                    max_episode_steps=spec.paper_steps)
