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
from tasks.specs import task_spec
from tsim.body import Body
from tsim.sim import BatchSim
from tsim.world import task_world

UNSTABLE_PENALTY = -3.0
GOALS = {"Walker-v0": (99, 1.0), "ObstacleTraverser-v1": (59, 2.0)}  # (voxel x of the goal, bonus)
FLOOR_SIGHT = {"ObstacleTraverser-v1": 5}
CEIL_SIGHT = {"Climber-v2": 3}


def obs_dim(task: str, n_points: int) -> int:
    """evogym's observation length for a robot of n points."""
    extra = {"Walker-v0": 2, "ObstacleTraverser-v1": 14, "Climber-v2": 10, "Thrower-v0": 6}
    task_spec(task)
    return extra[task] + 2 * n_points


class BatchEnv:
    """Batched evogym task. `episode_steps` defaults to the SGR paper's length for the task;
    pass "evogym" for evogym's registered limit."""

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
        self.obs_dims = np.array([obs_dim(task, n) for n in self.n_points])
        self.max_obs_dim = int(self.obs_dims.max())
        N = self.sim.max_robot_points
        self._mask = np.arange(N)[None, :] < self.n_points[:, None]
        world = self.sim.world
        self._terrain = (np.concatenate([o.pos0 for o in world.fixed_objects], axis=1)
                         if world.fixed_objects else np.zeros((2, 0)))
        self._has_package = any(o.name == "package" for o in world.free_objects)
        self._rel_cols = self._relative_columns()
        self.reset()

    # ------------------------------------------------------------------ layout helpers
    def _head(self) -> int:
        return {"Walker-v0": 2, "ObstacleTraverser-v1": 3, "Climber-v2": 3, "Thrower-v0": 6}[self.task]

    def _relative_columns(self) -> np.ndarray:
        """Column of each robot point's relative x and y in the observation row (dump column for
        padding)."""
        B, N = self._mask.shape
        p = np.arange(N)[None, :]
        head = self._head()
        cx = np.where(self._mask, head + p, self.max_obs_dim)
        cy = np.where(self._mask, head + self.n_points[:, None] + p, self.max_obs_dim)
        return np.stack([cx, cy], axis=2)

    def _robot(self) -> tuple[np.ndarray, np.ndarray]:
        N = self.sim.max_robot_points
        return self.sim.state[:, :N, 0:2], self.sim.state[:, :N, 2:4]

    def _package(self) -> tuple[np.ndarray, np.ndarray]:
        pos = np.stack([self.sim.object_pos(w, "package").T for w in range(self.n_worlds)])
        vel = np.stack([self.sim.object_vel(w, "package").T for w in range(self.n_worlds)])
        return pos, vel

    def _package_com(self) -> np.ndarray:
        pos = self._package()[0]
        return O.com(pos, np.ones(pos.shape[:2], dtype=bool))

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
        if np.any(self.elapsed >= self.episode_steps):
            raise RuntimeError("episode is over (truncated); call reset()")
        self.sim.set_actions(actions)
        com_before = self._robot_coms()[0]
        pkg_before = self._package_com() if self._has_package else None
        active = ~self.terminated
        self.sim.step()
        self.elapsed += 1
        unstable = self.sim.unstable & active
        com_after, vcom_after = self._robot_coms()
        reward = self._reward(com_before, com_after, pkg_before)
        reward = np.where(unstable, reward + UNSTABLE_PENALTY, reward)
        done = unstable.copy()
        if self.task in GOALS:
            gx, bonus = GOALS[self.task]
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

    # ------------------------------------------------------------------ task definitions
    def _reward(self, com_before, com_after, pkg_before) -> np.ndarray:
        d = com_after - com_before
        if self.task == "Climber-v2":
            return d[:, 1] + d[:, 0] * 0.2
        if self.task == "Thrower-v0":
            pkg_after = self._package_com()
            penalty = (com_before[:, 0] - com_after[:, 0]) * 0.25
            penalty = np.where(com_after[:, 0] < 0, -penalty, penalty)
            return pkg_after[:, 0] - pkg_before[:, 0] + penalty
        return d[:, 0]

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
        """Observations of the current state; `com`, `vcom` from `_robot_coms` if already known."""
        if com is None or vcom is None:
            com, vcom = self._robot_coms()
        pos, vel = self._robot()
        m = self._mask
        B = self.n_worlds
        obs = np.zeros((B, self.max_obs_dim + 1))
        if self.task == "Thrower-v0":
            ppos, pvel = self._package()
            pm = np.ones(ppos.shape[:2], dtype=bool)
            obs[:, 0:2] = vcom
            obs[:, 2:4] = O.com(ppos, pm) - com
            obs[:, 4:6] = O.com(pvel, pm)
        else:
            obs[:, 0:2] = vcom
            if self.task != "Walker-v0":
                obs[:, 2] = O.orientation(pos, self._pos0, m)
        rel = (pos - com[:, None, :]) * m[:, :, None]  # = O.relative(pos, m)
        rows = np.arange(B)[:, None, None]
        obs[rows, self._rel_cols] = rel
        sight = None
        if self.task in FLOOR_SIGHT:
            sight = O.terrain_sight(O.com_voxel_units(pos, self.n_points), self._terrain,
                                    FLOOR_SIGHT[self.task], below=True)
        elif self.task in CEIL_SIGHT:
            sight = O.terrain_sight(O.com_voxel_units(pos, self.n_points), self._terrain,
                                    CEIL_SIGHT[self.task], below=False)
        if sight is not None:
            start = self._head() + 2 * self.n_points
            cols = start[:, None] + np.arange(sight.shape[1])[None, :]
            obs[np.arange(B)[:, None], cols] = sight
        return obs[:, :self.max_obs_dim]

    def observe(self) -> np.ndarray:
        """Observations of the current state, recomputed (e.g. after editing `sim.state`)."""
        self._obs = self._observe()
        return self._obs.copy()

    def robot_obs(self, w: int) -> np.ndarray:
        """Robot w's observation without padding."""
        return self._obs[w, :self.obs_dims[w]].copy()
