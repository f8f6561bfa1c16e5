"""evogym 2.0's `EvoGymBase` and `BenchmarkBase` on sgr: the base classes evogym users write their
own environments on (a world, a simulation, a viewer, and observation helpers).

The helpers compute what evogym's compute, with the same numpy expressions, from `EvoSim`'s
read-outs: `EvoGymBase`'s in voxels, `BenchmarkBase`'s in world units (x 0.1), as evogym's.
"""

from __future__ import annotations

from importlib import resources
from typing import Any

import gymnasium as gym
import numpy as np

from sgr.evogym.sim import EvoSim
from sgr.evogym.viewer import EvoViewer
from sgr.evogym.world import EvoWorld

__all__ = ["BenchmarkBase", "EvoGymBase"]

RENDER_MODES = ("screen", "human", "img", "rgb_array")


def check_render_mode(render_mode: str | None) -> None:
    """ValueError naming the accepted modes unless `render_mode` is None or one of them."""
    if render_mode is not None and render_mode not in RENDER_MODES:
        raise ValueError(f"render_mode {render_mode!r} is not one of None, {', '.join(RENDER_MODES)}")


def render_with(viewer: EvoViewer, mode: str | None, options: dict[str, Any] | None) -> np.ndarray | None:
    """evogym's `render()` of an env: None without a mode, else the viewer's render with the
    `render_options` (verbose, hide_background, hide_grid, hide_edges, hide_voxels)."""
    if mode is None:
        return None
    o = options or {}
    return viewer.render(mode, o.get("verbose", False), o.get("hide_background", False),
                         o.get("hide_grid", False), o.get("hide_edges", False), o.get("hide_voxels", False))


class EvoGymBase(gym.Env):
    """Base of evogym environments over an `EvoWorld` (evogym's EvoGymBase): `step` takes a dict
    of actions by robot name, clips them to [0.6, 1.6] and returns the unstable flag."""

    metadata = {"render_modes": list(RENDER_MODES), "render_fps": 50}

    def __init__(self, world: EvoWorld, render_mode: str | None = None,
                 render_options: dict[str, Any] | None = None) -> None:
        check_render_mode(render_mode)
        self._sim = EvoSim(world)
        self._default_viewer = EvoViewer(self._sim)
        self._render_mode = render_mode
        self._render_options = render_options

    @property
    def render_mode(self) -> str | None:
        """The render mode given at construction (gymnasium reads it)."""
        return self._render_mode

    def step(self, action: dict[str, np.ndarray]) -> bool:
        """Set each named robot's actions (clipped to [0.6, 1.6]) and step; True when unstable."""
        if not isinstance(action, dict):
            raise TypeError(f"EvoGymBase.step takes a dict of actions by robot name, got "
                            f"{type(action).__name__}")
        for name, a in action.items():
            a = np.minimum(np.maximum(np.asarray(a, dtype=np.float64), 0.6), 1.6)  # np.clip's values
            self._sim.set_action(name, a)
        done = self._sim.step()
        if self._render_mode in ("human", "screen"):
            self.render()
        return done

    def reset(self, seed: int | None = None, options: dict[str, Any] | None = None) -> None:
        """Back to the initial state (time 0)."""
        self._sim.reset()

    @property
    def sim(self) -> EvoSim:
        """The environment's simulation."""
        return self._sim

    @property
    def default_viewer(self) -> EvoViewer:
        """The viewer `render()` uses."""
        return self._default_viewer

    def render(self) -> np.ndarray | None:
        """None without a render mode; an (H, W, 3) uint8 image for 'img' / 'rgb_array'; a window
        for 'screen' / 'human'."""
        return render_with(self._default_viewer, self._render_mode, self._render_options)

    def close(self) -> None:
        """Close the viewer."""
        self._default_viewer.close()

    def get_actuator_indices(self, robot_name: str) -> np.ndarray:
        """See `EvoSim.get_actuator_indices`."""
        return self._sim.get_actuator_indices(robot_name)

    def get_dim_action_space(self, robot_name: str) -> int:
        """See `EvoSim.get_dim_action_space`."""
        return self._sim.get_dim_action_space(robot_name)

    def get_time(self) -> int:
        """Steps since the last reset."""
        return self._sim.get_time()

    def pos_at_time(self, time: int) -> np.ndarray:
        """See `EvoSim.pos_at_time`."""
        return self._sim.pos_at_time(time)

    def vel_at_time(self, time: int) -> np.ndarray:
        """See `EvoSim.vel_at_time`."""
        return self._sim.vel_at_time(time)

    def object_pos_at_time(self, time: int, object_name: str) -> np.ndarray:
        """See `EvoSim.object_pos_at_time`."""
        return self._sim.object_pos_at_time(time, object_name)

    def object_vel_at_time(self, time: int, object_name: str) -> np.ndarray:
        """See `EvoSim.object_vel_at_time`."""
        return self._sim.object_vel_at_time(time, object_name)

    def object_orientation_at_time(self, time: int, object_name: str) -> float:
        """See `EvoSim.object_orientation_at_time`."""
        return self._sim.object_orientation_at_time(time, object_name)

    # ------------------------------------------------------------------ observation helpers
    def get_pos_com_obs(self, object_name: str) -> np.ndarray:
        """(2,) mean position of the object's points now."""
        p = np.mean(self._sim.object_pos_at_time(self.get_time(), object_name), axis=1)
        return np.array([p[0], p[1]])

    def get_vel_com_obs(self, object_name: str) -> np.ndarray:
        """(2,) mean velocity of the object's points now."""
        v = np.mean(self._sim.object_vel_at_time(self.get_time(), object_name), axis=1)
        return np.array([v[0], v[1]])

    def get_relative_pos_obs(self, object_name: str) -> np.ndarray:
        """(2n,) the object's point positions minus their mean: all x, then all y."""
        p = self._sim.object_pos_at_time(self.get_time(), object_name)
        com = np.mean(p, axis=1)
        return (p - np.array([com]).T).flatten()

    def get_ort_obs(self, object_name: str) -> np.ndarray:
        """(1,) the object's orientation now."""
        return np.array([self.object_orientation_at_time(self.get_time(), object_name)])

    def _sight(self, object_name: str, terrain_list: list[str], sight_dist: int, sight_range: float,
               below: bool) -> np.ndarray | None:
        p = self._sim.object_pos_at_time(self.get_time(), object_name)
        com = np.mean(p, axis=1)
        if len(terrain_list) == 0:
            return None
        t = np.concatenate([self._sim.object_pos_at_time(self.get_time(), n) for n in terrain_list],
                           axis=1)
        t = t[:, t[0, :] > com[0] - (sight_dist + 0.5)]
        t = t[:, t[0, :] < com[0] + (sight_dist + 0.5)]
        t = t[:, (t[1, :] < com[1]) if below else (t[1, :] > com[1])]
        sign = -1 if below else 1
        out = np.zeros(sight_dist * 2 + 1) + sign * sight_range + com[1]
        for i in range(-sight_dist, sight_dist + 1):
            win = (t[0, :] > com[0] + (i - 0.5)) & (t[0, :] < com[0] + (i + 0.5))
            if np.any(win):
                out[i + sight_dist] = np.max(t[1, win]) if below else np.min(t[1, win])
        out = (com[1] - out) if below else (out - com[1])
        return np.clip(out, 0, sight_range)

    def get_floor_obs(self, object_name: str, terrain_list: list[str], sight_dist: int,
                      sight_range: float = 5) -> np.ndarray | None:
        """(2 sight_dist + 1,) distance down to the highest point of `terrain_list` objects in each
        voxel column around the object's COM, capped at `sight_range` (None for no terrain)."""
        return self._sight(object_name, terrain_list, sight_dist, sight_range, below=True)

    def get_ceil_obs(self, object_name: str, terrain_list: list[str], sight_dist: int,
                     sight_range: float = 5) -> np.ndarray | None:
        """As `get_floor_obs`, up to the lowest terrain point above the COM."""
        return self._sight(object_name, terrain_list, sight_dist, sight_range, below=False)


class BenchmarkBase(EvoGymBase):
    """Base of evogym's benchmark tasks: the viewer tracks 'robot' and every read-out is in world
    units (evogym's BenchmarkBase). `DATA_PATH` holds the tasks' world files."""

    DATA_PATH = str(resources.files("tasks") / "worlds")
    VOXEL_SIZE = 0.1

    def __init__(self, world: EvoWorld, render_mode: str | None = None,
                 render_options: dict[str, Any] | None = None):
        EvoGymBase.__init__(self, world=world, render_mode=render_mode, render_options=render_options)
        self.default_viewer.track_objects("robot")

    def pos_at_time(self, time: int) -> np.ndarray:
        """World units."""
        return super().pos_at_time(time) * self.VOXEL_SIZE

    def vel_at_time(self, time: int) -> np.ndarray:
        """World units."""
        return super().vel_at_time(time) * self.VOXEL_SIZE

    def object_pos_at_time(self, time: int, object_name: str) -> np.ndarray:
        """World units."""
        return super().object_pos_at_time(time, object_name) * self.VOXEL_SIZE

    def object_vel_at_time(self, time: int, object_name: str) -> np.ndarray:
        """World units."""
        return super().object_vel_at_time(time, object_name) * self.VOXEL_SIZE

    def get_pos_com_obs(self, object_name: str) -> np.ndarray:
        """World units."""
        return super().get_pos_com_obs(object_name) * self.VOXEL_SIZE

    def get_vel_com_obs(self, object_name: str) -> np.ndarray:
        """World units."""
        return super().get_vel_com_obs(object_name) * self.VOXEL_SIZE

    def get_relative_pos_obs(self, object_name: str) -> np.ndarray:
        """World units."""
        return super().get_relative_pos_obs(object_name) * self.VOXEL_SIZE

    def get_floor_obs(self, object_name: str, terrain_list: list[str], sight_dist: int,
                      sight_range: float = 5) -> np.ndarray:
        """World units."""
        return super().get_floor_obs(object_name, terrain_list, sight_dist, sight_range) * self.VOXEL_SIZE

    def get_ceil_obs(self, object_name: str, terrain_list: list[str], sight_dist: int,
                     sight_range: float = 5) -> np.ndarray:
        """World units."""
        return super().get_ceil_obs(object_name, terrain_list, sight_dist, sight_range) * self.VOXEL_SIZE
