"""Batched versions of evogym's observation helpers (spec section 6), numpy over padded arrays,
and the observation blocks task specs are made of.

Arrays are (B, N, 2) point positions/velocities in world units with a (B, N) validity mask; every
helper returns one row per world.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from tasks.orientation import PI_EVOGYM, orientation  # noqa: F401 (re-exported)
from tasks.spec import Block
from tsim import constants as C


@dataclass
class Scene:
    """What observation blocks see: the robots' points (B, N, 2) with their mask, COMs (B, 2),
    positions at reset, the static terrain's points (2, M), and free objects by name.

    The points are read when a block first asks for `pos` or `vel` (`robot`): on a device the
    state then comes to the host only for tasks whose blocks read it."""

    robot: Callable[[], tuple[np.ndarray, np.ndarray]]  # () -> the robots' (B, N, 2) pos, vel
    mask: np.ndarray
    n_points: np.ndarray
    com: np.ndarray
    vcom: np.ndarray
    pos0: np.ndarray
    terrain: np.ndarray
    object_points: Callable[[str], tuple[np.ndarray, np.ndarray]]  # name -> (B, n, 2) pos, vel
    object_pos0: Callable[[str], np.ndarray] | None = None  # name -> (B, n, 2) positions at reset
    # name -> (B, 2) position and velocity COMs of a free object, if the env computes them
    # otherwise than `com` of `object_points` (the same bits; `BatchEnv`'s kernel path)
    object_coms: Callable[[str], tuple[np.ndarray, np.ndarray]] | None = None
    # name -> (B,) a free object's orientation, likewise (`orientation` of its points otherwise),
    # and () -> (B,) the robot's
    object_orientation: Callable[[str], np.ndarray] | None = None
    robot_orientation: Callable[[], np.ndarray] | None = None
    state: dict[str, np.ndarray] | None = None  # the task's per-world state (TaskSpec.state)
    # name -> (B, 2, n) current points of any world object, fixed or simulated (sight over objects)
    object_now: Callable[[str], np.ndarray] | None = None
    # the `Measure` of this same state when the env has one (after a step): its orientation, if the
    # reward or termination asked for it, is not computed twice
    measure: object | None = None
    # (dist, below) -> the sight over the static terrain, if the env computes it otherwise than
    # `terrain_sight` of `com_voxel_units` (the same bits; `BatchEnv`'s kernel path)
    static_sight: Callable[[int, bool], np.ndarray] | None = None
    # (dist, below, objects) -> the sight over those objects likewise, or None where the env has no
    # other way for them
    object_sight: Callable[[int, bool, tuple[str, ...]], np.ndarray | None] | None = None

    @functools.cached_property
    def _points(self) -> tuple[np.ndarray, np.ndarray]:
        return self.robot()

    @property
    def pos(self) -> np.ndarray:
        """(B, N, 2) the robots' point positions."""
        return self._points[0]

    @property
    def vel(self) -> np.ndarray:
        """(B, N, 2) the robots' point velocities."""
        return self._points[1]


def com(pos: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """(B, 2) mean of each row's valid points (`mask` (B, N) bool): every point weighs the same, as
    in evogym's centre of mass."""
    n = mask.sum(axis=1, keepdims=True)
    return (pos * mask[:, :, None]).sum(axis=1) / n


def relative(pos: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Positions minus COM, zero on padding: (B, N, 2)."""
    return (pos - com(pos, mask)[:, None, :]) * mask[:, :, None]


def com_voxel_units(pos: np.ndarray, n_points: np.ndarray) -> np.ndarray:
    """(B, 2) COM as evogym's observation helpers compute it: np.mean of positions / 0.1, to the
    bit (the sight windows' edges depend on it). One np.mean per distinct point count, over all
    robots that have it: the same reduction, row by row, as one np.mean per robot
    (`com_voxel_units_per_robot`, the test oracle), ~3x faster at B = 128."""
    out = np.empty((len(n_points), 2))
    for n in np.unique(n_points):
        rows = np.nonzero(n_points == n)[0]
        out[rows] = np.mean(pos[rows, :n].transpose(0, 2, 1) / C.CELL, axis=2)
    return out


def com_voxel_units_per_robot(pos: np.ndarray, n_points: np.ndarray) -> np.ndarray:
    """`com_voxel_units` robot by robot: evogym's own expression, kept as the test oracle."""
    return np.stack([np.mean(pos[b, :n].T / C.CELL, axis=1) for b, n in enumerate(n_points)])


def terrain_sight(com_vox: np.ndarray, terrain: np.ndarray, sight_dist: int, *, below: bool,
                  sight_range: float = 5.0) -> np.ndarray:
    """Floor (below=True) or ceiling distances of `get_floor_obs` / `get_ceil_obs`, world units.

    `terrain` is (2, M), shared by every world, or (B, 2, M), per world (objects that move).
    Computed in voxel units, as evogym does, so the open windows on lattice lines behave the same
    (the half-integer COM quirk of spec section 6).
    """
    c = com_vox  # (B, 2)
    t = terrain / C.CELL  # (2, M) or (B, 2, M)
    tx, ty = (t[0][None, :], t[1][None, :]) if t.ndim == 2 else (t[:, 0], t[:, 1])
    cx, cy = c[:, 0:1], c[:, 1:2]
    keep = (tx > cx - (sight_dist + 0.5)) & (tx < cx + (sight_dist + 0.5))
    keep &= (ty < cy) if below else (ty > cy)
    out = np.empty((len(c), 2 * sight_dist + 1))
    for k, i in enumerate(range(-sight_dist, sight_dist + 1)):
        win = keep & (tx > cx + (i - 0.5)) & (tx < cx + (i + 0.5))
        if below:
            e = np.where(win, ty, -np.inf).max(axis=1)
            e = np.where(win.any(axis=1), e, cy[:, 0] - sight_range)
            out[:, k] = np.clip(cy[:, 0] - e, 0, sight_range)
        else:
            e = np.where(win, ty, np.inf).min(axis=1)
            e = np.where(win.any(axis=1), e, cy[:, 0] + sight_range)
            out[:, k] = np.clip(e - cy[:, 0], 0, sight_range)
    return out * C.CELL


# ---------------------------------------------------------------------- observation blocks
def _orientation(s: Scene) -> np.ndarray:
    m = s.measure
    if m is not None and m.points is not None:
        return m.orientation[:, None]  # the same points, pos0 and mask: the same bits
    if s.robot_orientation is not None:
        return s.robot_orientation()[:, None]
    return orientation(s.pos, s.pos0, s.mask)[:, None]


VCOM = Block("robot velocity COM", 2, lambda s: s.vcom)
ORIENTATION = Block("robot orientation", 1, _orientation)
POINTS = Block("robot points relative to its COM (x of every point, then y)", -1, lambda s: None)


def _object_com(s: Scene, name: str, which: int) -> np.ndarray:
    if s.object_coms is not None:
        return s.object_coms(name)[which]
    pts = s.object_points(name)[which]
    return com(pts, np.ones(pts.shape[:2], dtype=bool))


def object_offset(name: str) -> Block:
    """Block of 2: free object `name`'s COM minus the robot's COM, world units."""
    return Block(f"{name} COM relative to the robot COM", 2, lambda s: _object_com(s, name, 0) - s.com)


def object_vcom(name: str) -> Block:
    """Block of 2: free object `name`'s mean point velocity, absolute, not relative to the robot."""
    return Block(f"{name} velocity COM", 2, lambda s: _object_com(s, name, 1))


def object_orientation(name: str) -> Block:
    """evogym's orientation of free object `name` against its points at reset."""
    def fn(s: Scene) -> np.ndarray:
        if s.object_orientation is not None:
            return s.object_orientation(name)[:, None]
        pos = s.object_points(name)[0]
        return orientation(pos, s.object_pos0(name), np.ones(pos.shape[:2], dtype=bool))[:, None]
    return Block(f"{name} orientation", 1, fn)


def _sight_points(s: Scene, objects: tuple[str, ...] | None) -> np.ndarray:
    """The points a sight block looks at: the static terrain (2, M), or the named objects' current
    points (B, 2, M), fixed or simulated (their order does not matter: only max/min are taken)."""
    if objects is None:
        return s.terrain
    return np.concatenate([s.object_now(n) for n in objects], axis=2)


def _sight(s: Scene, dist: int, objects: tuple[str, ...] | None, below: bool) -> np.ndarray:
    if objects is None and s.static_sight is not None:
        return s.static_sight(dist, below)
    if objects is not None and s.object_sight is not None:
        out = s.object_sight(dist, below, objects)
        if out is not None:
            return out
    return terrain_sight(com_voxel_units(s.pos, s.n_points), _sight_points(s, objects), dist, below=below)


def floor_sight(dist: int, objects: tuple[str, ...] | None = None) -> Block:
    """evogym's get_floor_obs: terrain height below the COM in 2 * dist + 1 columns, over the
    static terrain or over the named objects (evogym's `terrain_list`, which may move)."""
    return Block(f"floor sight +-{dist}", 2 * dist + 1, lambda s: _sight(s, dist, objects, True))


def ceiling_sight(dist: int, objects: tuple[str, ...] | None = None) -> Block:
    """evogym's get_ceil_obs: terrain above the COM in 2 * dist + 1 columns (objects as in
    `floor_sight`)."""
    return Block(f"ceiling sight +-{dist}", 2 * dist + 1, lambda s: _sight(s, dist, objects, False))
