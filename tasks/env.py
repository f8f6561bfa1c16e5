"""`BatchEnv`: one task, many robots (bodies may differ), stepped together.

Layout: observations are a (B, max_obs_dim) float64 array, row b holding robot b's evogym
observation in its first `obs_dims[b]` entries and zeros after; actions are (B, max_actuators) with
robot b using its first `n_actuators[b]` entries (or a list of per-robot arrays). Rewards,
`terminated` and `truncated` are (B,) arrays. A robot that terminated stops moving and earns 0 from
then on while the others go on.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from tasks import observations as O
from tasks.spec import Measure
from tasks.specs import task_spec, task_world
from tsim.body import Body
from tsim.sim import BatchSim

UNSTABLE_PENALTY = -3.0


def obs_dim(task: str, n_points: int) -> int:
    """evogym's observation length for a robot of n points on `task`."""
    return task_spec(task).obs_dim(n_points)


class BatchEnv:
    """Batched evogym task. `episode_steps` defaults to the SGR paper's length for the task;
    pass "evogym" for evogym's registered limit. Everything task-specific comes from the task's
    spec (`tasks/spec.py`)."""

    def __init__(self, task: str, bodies: Sequence[Body | object],
                 episode_steps: int | str | None = None, *, arch: str | None = None,
                 passive_ok: bool = False):
        self.spec = task_spec(task)
        self.task = task
        if episode_steps is None:
            episode_steps = self.spec.paper_steps
        elif episode_steps == "evogym":
            episode_steps = self.spec.evogym_steps
        if not isinstance(episode_steps, int) or episode_steps < 1:
            raise ValueError(f"episode_steps must be a positive int, 'evogym' or None, got {episode_steps!r}")
        self.episode_steps = episode_steps
        self.sim = BatchSim(task_world(task), bodies, self.spec.origin, arch=arch,
                            passive_ok=passive_ok)
        self.n_worlds = self.sim.n_worlds
        self.n_actuators = self.sim.n_actuators.copy()
        self.n_points = self.sim.n_robot_points.copy()
        self.obs_dims = np.array([self.spec.obs_dim(n) for n in self.n_points])
        self.max_obs_dim = int(self.obs_dims.max())
        N = self.sim.max_robot_points
        self._mask = np.arange(N)[None, :] < self.n_points[:, None]
        world = self.sim.world
        self._terrain = (np.concatenate([o.pos0 for o in world.fixed_objects], axis=1)
                         if world.fixed_objects else np.zeros((2, 0)))
        self._head = self.spec.head_width()
        self._rel_cols = self._relative_columns()
        self.reset()

    # ------------------------------------------------------------------ layout helpers
    def _relative_columns(self) -> np.ndarray:
        """Column of each robot point's relative x and y in the observation row (dump column for
        padding)."""
        B, N = self._mask.shape
        p = np.arange(N)[None, :]
        head = self._head
        cx = np.where(self._mask, head + p, self.max_obs_dim)
        cy = np.where(self._mask, head + self.n_points[:, None] + p, self.max_obs_dim)
        return np.stack([cx, cy], axis=2)

    def _robot(self) -> tuple[np.ndarray, np.ndarray]:
        N = self.sim.max_robot_points
        return self.sim.state[:, :N, 0:2], self.sim.state[:, :N, 2:4]

    def _object_points(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """(B, n, 2) positions and velocities of free object `name` in every world."""
        pos = np.stack([self.sim.object_pos(w, name).T for w in range(self.n_worlds)])
        vel = np.stack([self.sim.object_vel(w, name).T for w in range(self.n_worlds)])
        return pos, vel

    def _measure(self, com: np.ndarray) -> Measure:
        objects = {}
        for name in self.spec.tracked:
            pos = self._object_points(name)[0]
            objects[name] = O.com(pos, np.ones(pos.shape[:2], dtype=bool))
        return Measure(com, objects)

    # ------------------------------------------------------------------ API
    def reset(self, mask: np.ndarray | None = None) -> np.ndarray:
        """Start new episodes: all worlds, or only those where `mask` (B,) is True."""
        self.sim.reset(mask)
        if mask is None:
            self.elapsed = np.zeros(self.n_worlds, dtype=np.int64)
            self.terminated = np.zeros(self.n_worlds, dtype=bool)
            self._pos0 = self._robot()[0].copy()
        else:
            self.elapsed[mask] = 0
            self.terminated[mask] = False
        return self.observe()

    @property
    def t(self) -> int:
        """Steps taken by the longest-running world since its reset."""
        return int(self.elapsed.max())

    def step(self, actions) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict]:
        """One env step of every world: (obs (B, max_obs_dim), reward, terminated, truncated (B,),
        info with `unstable` and `t`). An unstable world gets -3 and terminates; a terminated one
        earns 0 from then on. RuntimeError once any world reached `episode_steps`, until `reset`."""
        if np.any(self.elapsed >= self.episode_steps):
            raise RuntimeError("episode is over (truncated); call reset()")
        self.sim.set_actions(actions)
        before = self._measure(self._robot_coms()[0])
        active = ~self.terminated
        self.sim.step()
        self.elapsed += 1
        unstable = self.sim.unstable & active
        com_after, vcom_after = self._robot_coms()
        reward = self.spec.reward(before, self._measure(com_after))
        reward = np.where(unstable, reward + UNSTABLE_PENALTY, reward)
        done = unstable.copy()
        if self.spec.goal is not None:
            gx, bonus = self.spec.goal
            goal = active & (com_after[:, 0] > gx * 0.1)
            reward = np.where(goal, reward + bonus, reward)
            done |= goal
        reward = np.where(active, reward, 0.0)
        self.terminated |= done
        self.sim.deactivate(self.terminated)
        self._obs = self._observe(com_after, vcom_after)
        truncated = (self.elapsed >= self.episode_steps) & ~self.terminated
        info = {"unstable": unstable, "t": self.elapsed.copy()}
        return self._obs.copy(), reward, self.terminated.copy(), truncated, info

    # ------------------------------------------------------------------ measurements
    def _robot_coms(self) -> tuple[np.ndarray, np.ndarray]:
        """(B, 2) position and velocity COMs of the robots in one pass over the state; equal to
        `O.com` bit for bit (the same sums in point order; padding rows hold zeros unless a free
        object's points follow the robot's)."""
        rows = self.sim.state[:, :self.sim.max_robot_points, 0:4]
        if self.sim.free_objects:
            rows = rows * self._mask[:, :, None]
        s = rows.sum(axis=1) / self.n_points[:, None]
        return s[:, 0:2], s[:, 2:4]

    def _observe(self, com: np.ndarray | None = None, vcom: np.ndarray | None = None) -> np.ndarray:
        """Observations of the current state, the spec's blocks in order; `com`, `vcom` from
        `_robot_coms` if already known."""
        if com is None or vcom is None:
            com, vcom = self._robot_coms()
        pos, vel = self._robot()
        m = self._mask
        B = self.n_worlds
        scene = O.Scene(pos=pos, vel=vel, mask=m, n_points=self.n_points, com=com, vcom=vcom,
                        pos0=self._pos0, terrain=self._terrain, object_points=self._object_points)
        obs = np.zeros((B, self.max_obs_dim + 1))
        col, after_points = 0, None  # blocks after the points start at head + 2 n per robot
        for block in self.spec.observation:
            if block.width < 0:
                rel = (pos - com[:, None, :]) * m[:, :, None]  # = O.relative(pos, m)
                obs[np.arange(B)[:, None, None], self._rel_cols] = rel
                after_points = self._head + 2 * self.n_points
                continue
            values = block.fn(scene)
            if after_points is None:
                obs[:, col:col + block.width] = values
                col += block.width
            else:
                cols = after_points[:, None] + np.arange(block.width)[None, :]
                obs[np.arange(B)[:, None], cols] = values
                after_points = after_points + block.width
        return obs[:, :self.max_obs_dim]

    def observe(self) -> np.ndarray:
        """Observations of the current state, recomputed (e.g. after editing `sim.state`)."""
        self._obs = self._observe()
        return self._obs.copy()

    def robot_obs(self, w: int) -> np.ndarray:
        """Robot w's observation without padding."""
        return self._obs[w, :self.obs_dims[w]].copy()
