"""`SgrVecEnv`: stable-baselines3's `VecEnv` over one batched simulation (`BatchEnv`), and
`make_vec_env`, shaped like SB3's own, which builds it from a gymnasium id.

Why: SB3 learns from a `VecEnv`, not from gymnasium's `VectorEnv`, and its own `DummyVecEnv` steps
one env at a time in Python. Here the N robots of a `VecEnv` are the N worlds of one `BatchEnv`,
stepped by one call, so a learner with many envs pays for the simulation once per step, not N
times (docs/RL.md).

The SB3 contract, as `DummyVecEnv` keeps it:
- `reset()` -> observations (N, obs_dim); `step(actions)` -> observations, rewards (N,) float32,
  dones (N,) bool, infos (one dict per env);
- a world whose episode ends is reset in the same call: its row of the returned observations is
  the new episode's first, and its info holds the last one as `terminal_observation`, with
  `TimeLimit.truncated` True when the episode was cut by its length rather than ended by the task;
- `seed(s)` makes the next `reset()` restart world i's task stream from s + i (evogym's draw
  after `env.reset(seed=s + i)`; the physics itself is deterministic);
- `get_attr`, `set_attr`, `env_method` and `env_is_wrapped` act on per-env views (`RobotView`:
  `body`, `obs_dim`, `n_actuators`, `robot_points()`, `render()`), SB3's own wrappers
  (`VecMonitor`, `VecNormalize`) wrap it as any VecEnv.

Mixed bodies (one per env) share one padded layout: observations (N, max obs_dim) with zeros after
robot i's own entries, actions (N, max actuators) of which robot i reads its first ones (what
`BatchEnv` does). stable-baselines3 is the optional extra `rl` (`pip install 'sgr[rl]'`); without it,
building one says so in one line.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from tasks.env import BatchEnv
from tasks.specs import TASKS
from tsim.body import build_body
from tsim.errors import SgrError

INSTALL = "pip install 'sgr[rl]'"


def _vec_env_base() -> type:
    """SB3's `VecEnv` class; SgrError saying what to install when SB3 is missing."""
    try:
        from stable_baselines3.common.vec_env import VecEnv
    except ImportError:
        raise SgrError(f"sgr.rl needs stable-baselines3 and torch: {INSTALL}") from None
    return VecEnv


def task_of(env_id: str) -> tuple[str, int]:
    """The task of a gymnasium id and the episode length that id is registered with:
    "sgr/Walker-v0" (the paper's length) or evogym's bare "Walker-v0" (evogym's length, registered
    by `import sgr.evogym`; without it, still evogym's). SgrError for another id."""
    import gymnasium as gym

    task = env_id[len("sgr/"):] if env_id.startswith("sgr/") else env_id
    if task not in TASKS:
        raise SgrError(f"unknown env id {env_id!r}: sgr's are sgr/<task> and evogym's bare ids, for "
                       f"tasks such as {', '.join(list(TASKS)[:3])}, ...")
    spec = gym.registry.get(env_id)
    if spec is not None and spec.max_episode_steps:
        return task, int(spec.max_episode_steps)
    return task, int(TASKS[task].paper_steps if env_id.startswith("sgr/") else TASKS[task].evogym_steps)


class RobotView:
    """One env of an `SgrVecEnv`, for `get_attr`/`env_method`: its body and layout, its points now,
    a picture of it."""

    def __init__(self, vec: SgrVecEnv, i: int):
        self._vec, self.index = vec, i

    @property
    def body(self) -> np.ndarray:
        """Its voxel matrix."""
        return self._vec.batch_env.sim.bodies[self.index].matrix.copy()

    @property
    def obs_dim(self) -> int:
        """How many of its observation row's entries are its own (the rest is padding)."""
        return int(self._vec.batch_env.obs_dims[self.index])

    @property
    def n_actuators(self) -> int:
        """How many of its action row's entries it reads."""
        return int(self._vec.batch_env.n_actuators[self.index])

    def robot_points(self) -> np.ndarray:
        """(2, N) its point positions now, evogym's point order, world units."""
        return self._vec.batch_env.sim.robot_pos(self.index)

    def render(self) -> np.ndarray:
        """(H, W, 3) uint8 picture of it and its world's objects now (tsim's renderer)."""
        from tsim.render import Renderer

        sim = self._vec.batch_env.sim
        renderer = self._vec._renderers.get(self.index)
        if renderer is None:
            renderer = self._vec._renderers[self.index] = Renderer(sim.world, sim.bodies[self.index])
        return renderer.frame(sim.robot_pos(self.index), sim.objects_pos(self.index))


def SgrVecEnv(*args: Any, **kwargs: Any):  # noqa: N802 (a class to its users: built on first use)
    """`SgrVecEnv(task, bodies, episode_steps=None, precision=None)`: an SB3 `VecEnv` of one robot
    per body (module docstring). The class is made on first use so that importing this module
    needs no stable-baselines3; `isinstance(env, stable_baselines3.common.vec_env.VecEnv)` holds."""
    return _vec_env_class()(*args, **kwargs)


_CLASS: type | None = None


def _vec_env_class() -> type:
    global _CLASS
    if _CLASS is None:
        _CLASS = _make_class(_vec_env_base())
    return _CLASS


def _make_class(base: type) -> type:
    from tasks.gym_env import _action_space, _obs_space

    class _SgrVecEnv(base):
        __doc__ = SgrVecEnv.__doc__
        metadata = {"render_modes": ["rgb_array"]}

        def __init__(self, task: str, bodies: Sequence[Any], episode_steps: int | None = None,
                     precision: str | None = None, render_mode: str | None = None):
            if len(bodies) == 0:
                raise SgrError("an SgrVecEnv needs at least one body")
            if render_mode not in (None, "rgb_array"):
                raise SgrError(f"render_mode {render_mode!r} is not supported here (None, 'rgb_array')")
            self._env = BatchEnv(task, list(bodies), episode_steps=episode_steps, precision=precision)
            self.task = task
            self.render_mode = render_mode  # (what SB3's __init__ asks every env for)
            self._actions: np.ndarray | None = None
            self._renderers: dict[int, Any] = {}
            self._views = [RobotView(self, i) for i in range(self._env.n_worlds)]
            super().__init__(self._env.n_worlds, _obs_space(self._env.max_obs_dim),
                             _action_space(self._env.sim.max_actuators))

        def __repr__(self) -> str:
            return (f"SgrVecEnv({self.task!r}, {self.num_envs} robots, "
                    f"episode_steps={self._env.episode_steps})")

        @property
        def batch_env(self) -> BatchEnv:
            """The underlying `BatchEnv` (its `sim`, `spec`)."""
            return self._env

        def reset(self) -> np.ndarray:
            """Every world anew; after `seed(s)`, world i's task stream restarts from s + i."""
            seeds = self._seeds
            if any(s is not None for s in seeds):
                self._env.seed([int(s) if s is not None else i for i, s in enumerate(seeds)])
            self._reset_seeds()
            self._reset_options()
            self.reset_infos = [{} for _ in range(self.num_envs)]
            return self._env.reset().copy()

        def step_async(self, actions: np.ndarray) -> None:
            self._actions = np.asarray(actions, dtype=np.float64).reshape(self.num_envs, -1)

        def step_wait(self):
            obs, reward, term, trunc, info = self._env.step(self._actions)
            done = term | trunc
            infos: list[dict] = [{} for _ in range(self.num_envs)]
            if done.any():
                final = obs.copy()
                obs = self._env.reset(mask=done)
                for i in np.flatnonzero(done):
                    infos[i]["terminal_observation"] = final[i]
                    infos[i]["TimeLimit.truncated"] = bool(trunc[i] and not term[i])
            for i in np.flatnonzero(info["unstable"]):
                infos[i]["unstable"] = True
            return obs.copy(), reward.astype(np.float32), done, infos

        def close(self) -> None:
            self._renderers.clear()

        def get_images(self) -> Sequence[np.ndarray | None]:
            return [v.render() for v in self._views]

        def _views_of(self, indices) -> list[RobotView]:
            return [self._views[i] for i in self._get_indices(indices)]

        def get_attr(self, attr_name: str, indices=None) -> list[Any]:
            """Each env's `attr_name`: a `RobotView` attribute (body, obs_dim, n_actuators), else the
            VecEnv's own (render_mode, task, ...)."""
            out = []
            for v in self._views_of(indices):
                out.append(getattr(v, attr_name) if hasattr(v, attr_name) else getattr(self, attr_name))
            return out

        def set_attr(self, attr_name: str, value: Any, indices=None) -> None:
            """Set an attribute of the VecEnv (all envs share it: they are one simulation)."""
            if hasattr(RobotView, attr_name):
                raise AttributeError(f"{attr_name} is a robot's own and cannot be set")
            setattr(self, attr_name, value)

        def env_method(self, method_name: str, *method_args, indices=None, **method_kwargs) -> list[Any]:
            """`method_name` of each env's `RobotView` (robot_points, render)."""
            return [getattr(v, method_name)(*method_args, **method_kwargs) for v in self._views_of(indices)]

        def env_is_wrapped(self, wrapper_class: type, indices=None) -> list[bool]:
            """No env is wrapped one by one (SB3's wrappers wrap the VecEnv)."""
            return [False] * len(self._views_of(indices))

    _SgrVecEnv.__name__ = _SgrVecEnv.__qualname__ = "SgrVecEnv"
    return _SgrVecEnv


def make_vec_env(env_id: str, n_envs: int = 1, seed: int | None = None, start_index: int = 0,
                 monitor_dir: str | None = None, wrapper_class: Any = None, env_kwargs: dict | None = None,
                 vec_env_cls: Any = None, vec_env_kwargs: dict | None = None,
                 monitor_kwargs: dict | None = None, wrapper_kwargs: dict | None = None):
    """An SB3 `VecEnv` of `n_envs` robots in one batch, with SB3's `make_vec_env` signature, wrapped
    in `VecMonitor` (episode returns and lengths in infos, `monitor_dir` for its CSV) as SB3's
    wraps each env in `Monitor`.

    Args:
        env_id: "sgr/<task>" (the paper's episode length) or evogym's bare id ("Walker-v0",
            evogym's length).
        n_envs: robots in the batch.
        seed: world i's task stream restarts from seed + start_index + i at the first reset (SB3's
            numbering).
        env_kwargs: `body` (one voxel matrix for every env, with evogym's optional
            `connections`) or `bodies` (a list of n_envs), and optionally `max_episode_steps`
            and `precision` ("f64", "f32").
        vec_env_cls, vec_env_kwargs: accepted for SB3's signature; the batch is always one
            `SgrVecEnv` (SB3's `SubprocVecEnv` would put each robot in its own process).
        wrapper_class, wrapper_kwargs: refused (a gymnasium wrapper wraps one env; the robots here
            are one batch: wrap the returned VecEnv instead).
    Raises:
        SgrError: an unknown id, a missing body, a wrapper_class, or no stable-baselines3 installed.
    """
    if wrapper_class is not None:
        raise SgrError("wrapper_class: the robots are one batched VecEnv, not one env each; wrap the "
                       "returned VecEnv with a VecEnvWrapper instead")
    kw = dict(env_kwargs or {})
    task, steps = task_of(env_id)
    steps = kw.pop("max_episode_steps", steps)
    precision = kw.pop("precision", None)
    connections = kw.pop("connections", None)
    if "body" in kw and "bodies" in kw:
        raise SgrError("env_kwargs: give body (one for every env) or bodies (one per env), not both")
    if "bodies" in kw:
        if connections is not None:
            raise SgrError("env_kwargs: connections goes with body=; give bodies=[...] as built bodies")
        bodies = list(kw.pop("bodies"))
        if len(bodies) != n_envs:
            raise SgrError(f"env_kwargs: {len(bodies)} bodies for n_envs={n_envs}")
    elif "body" in kw:
        body = kw.pop("body")
        if connections is not None:
            body = build_body(np.asarray(body), np.asarray(connections))
        bodies = [body] * int(n_envs)
    else:
        raise SgrError("env_kwargs needs body= (a voxel matrix) or bodies= (one per env)")
    render_mode = kw.pop("render_mode", None)
    if kw:
        raise SgrError(f"env_kwargs: unknown key{'s' if len(kw) > 1 else ''} {', '.join(map(repr, kw))} "
                       "(body, bodies, connections, max_episode_steps, precision, render_mode)")
    env = SgrVecEnv(task, bodies, episode_steps=steps, precision=precision, render_mode=render_mode)
    if seed is not None:
        env.seed(seed + start_index)
    from stable_baselines3.common.vec_env import VecMonitor

    filename = None
    if monitor_dir is not None:
        import os

        os.makedirs(monitor_dir, exist_ok=True)
        filename = os.path.join(monitor_dir, "monitor.csv")
    return VecMonitor(env, filename, **(monitor_kwargs or {}))

