"""Batched versions of evogym's observation helpers (spec section 6), numpy over padded arrays,
and the observation blocks task specs are made of.

Arrays are (B, N, 2) point positions/velocities in world units with a (B, N) validity mask; every
helper returns one row per world.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from tasks.spec import Block
from tsim import constants as C


@dataclass
class Scene:
    """What observation blocks see: the robots' points (B, N, 2) with their mask, COMs (B, 2),
    positions at reset, the static terrain's points (2, M), and free objects by name."""

    pos: np.ndarray
    vel: np.ndarray
    mask: np.ndarray
    n_points: np.ndarray
    com: np.ndarray
    vcom: np.ndarray
    pos0: np.ndarray
    terrain: np.ndarray
    object_points: Callable[[str], tuple[np.ndarray, np.ndarray]]  # name -> (B, n, 2) pos, vel
    object_pos0: Callable[[str], np.ndarray] | None = None  # name -> (B, n, 2) positions at reset
    state: dict[str, np.ndarray] | None = None  # the task's per-world state (TaskSpec.state)

PI_EVOGYM = 3.1415926


def com(pos: np.ndarray, mask: np.ndarray) -> np.ndarray:
    n = mask.sum(axis=1, keepdims=True)
    return (pos * mask[:, :, None]).sum(axis=1) / n


def relative(pos: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Positions minus COM, zero on padding: (B, N, 2)."""
    return (pos - com(pos, mask)[:, None, :]) * mask[:, :, None]


def _eigen_com(pos: np.ndarray, n: np.ndarray) -> np.ndarray:
    """(B, 2) COM as Eigen 3.4's vectorised `rowwise().sum() / cols()` adds the points: the first,
    then groups of four ((p1 + p2) + (p3 + p4)) while a whole group fits below the last multiple
    of four of n - 1, then the rest one by one. `pos` is zero-padded beyond n (B, N, 2)."""
    B, N = pos.shape[:2]
    p = np.concatenate([pos, np.zeros((B, 4, 2))], axis=1)
    groups = ((n - 1) & ~3) // 4
    s = p[:, 0].copy()
    for k in range((N + 3) // 4):
        i = 1 + 4 * k
        g = (p[:, i] + p[:, i + 1]) + (p[:, i + 2] + p[:, i + 3])
        s = np.where((k < groups)[:, None], s + g, s)
    rows = np.arange(B)
    for j in range(3):
        i = 1 + 4 * groups + j
        s = np.where((i < n)[:, None], s + p[rows, np.minimum(i, N + 3)], s)
    return s / n[:, None]


def _eigen_sum(a: np.ndarray, n: np.ndarray) -> np.ndarray:
    """(B,) sums of a (B, N), zero-padded beyond n >= 4, in the order of Eigen's SSE2 reduction
    (`Array::sum()`): two accumulators of two lanes over blocks of four, joined, one more pair if
    left, lanes added, then a last odd element."""
    B, N = a.shape
    a = np.concatenate([a, np.zeros((B, 4))], axis=1)
    end4 = (n // 4) * 4
    p0, p1 = a[:, 0:2].copy(), a[:, 2:4].copy()
    for i in range(4, N, 4):
        use = (i < end4)[:, None]
        p0 = np.where(use, p0 + a[:, i:i + 2], p0)
        p1 = np.where(use, p1 + a[:, i + 2:i + 4], p1)
    p0 = p0 + p1
    rows = np.arange(B)[:, None]
    pair = a[rows, end4[:, None] + np.arange(2)[None, :]]
    p0 = np.where((n - end4 >= 2)[:, None], p0 + pair, p0)
    res = p0[:, 0] + p0[:, 1]
    return np.where(n % 2 == 1, res + a[rows[:, 0], n - 1], res)


def orientation(pos: np.ndarray, pos0: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """evogym's orientation (`object_orientation_at_time`): mass-weighted mean unsigned angle of
    the centred points against time 0, with its clamps, pi = 3.1415926 and the sign taken from the
    summed cross products. Sums in Eigen's order (`_eigen_com`, `_eigen_sum`), so that the points
    of an undeformed body whose dot products round above 1 (clamped to arccos(0.99999)) are the
    same as evogym's: the result then equals evogym's to rounding, at reset too."""
    n = mask.sum(axis=1)
    m = mask[:, :, None]
    new = (pos - _eigen_com(pos * m, n)[:, None, :]) * m
    old = (pos0 - _eigen_com(pos0 * m, n)[:, None, :]) * m
    mag_new = np.sqrt(new[:, :, 0] * new[:, :, 0] + new[:, :, 1] * new[:, :, 1])
    mag_old = np.sqrt(old[:, :, 0] * old[:, :, 0] + old[:, :, 1] * old[:, :, 1])
    un = np.where(mag_new[:, :, None] > 0, new / np.where(mag_new > 0, mag_new, 1)[:, :, None], new)
    uo = np.where(mag_old[:, :, None] > 0, old / np.where(mag_old > 0, mag_old, 1)[:, :, None], old)
    cos = un[:, :, 0] * uo[:, :, 0] + un[:, :, 1] * uo[:, :, 1]
    cos = np.where(mag_new * mag_old < 1e-7, 0.99999, cos)
    cos = np.where(cos > 1.0, 0.99999, cos)
    cos = np.where(cos < -1.0, -0.99999, cos)
    ang = np.arccos(cos) * mag_old * mask
    avg = _eigen_sum(ang, n) / _eigen_sum(mag_old * mask, n)
    cross = _eigen_sum((un[:, :, 0] * uo[:, :, 1] - un[:, :, 1] * uo[:, :, 0]) * mask, n)
    return np.where(cross > 0, 2 * PI_EVOGYM - avg, avg)


def com_voxel_units(pos: np.ndarray, n_points: np.ndarray) -> np.ndarray:
    """(B, 2) COM as evogym's observation helpers compute it: np.mean of positions / 0.1."""
    return np.stack([np.mean(pos[b, :n].T / C.CELL, axis=1) for b, n in enumerate(n_points)])


def terrain_sight(com_vox: np.ndarray, terrain: np.ndarray, sight_dist: int, *, below: bool,
                  sight_range: float = 5.0) -> np.ndarray:
    """Floor (below=True) or ceiling distances of `get_floor_obs` / `get_ceil_obs`, world units.

    Computed in voxel units, as evogym does, so the open windows on lattice lines behave the same
    (the half-integer COM quirk of spec section 6).
    """
    c = com_vox  # (B, 2)
    t = terrain / C.CELL  # (2, M)
    tx, ty = t[0][None, :], t[1][None, :]
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
VCOM = Block("robot velocity COM", 2, lambda s: s.vcom)
ORIENTATION = Block("robot orientation", 1, lambda s: orientation(s.pos, s.pos0, s.mask)[:, None])
POINTS = Block("robot points relative to its COM (x of every point, then y)", -1, lambda s: None)


def _object_com(s: Scene, name: str, which: int) -> np.ndarray:
    pts = s.object_points(name)[which]
    return com(pts, np.ones(pts.shape[:2], dtype=bool))


def object_offset(name: str) -> Block:
    return Block(f"{name} COM relative to the robot COM", 2, lambda s: _object_com(s, name, 0) - s.com)


def object_vcom(name: str) -> Block:
    return Block(f"{name} velocity COM", 2, lambda s: _object_com(s, name, 1))


def object_orientation(name: str) -> Block:
    """evogym's orientation of free object `name` against its points at reset."""
    def fn(s: Scene) -> np.ndarray:
        pos = s.object_points(name)[0]
        return orientation(pos, s.object_pos0(name), np.ones(pos.shape[:2], dtype=bool))[:, None]
    return Block(f"{name} orientation", 1, fn)


def floor_sight(dist: int) -> Block:
    """evogym's get_floor_obs: terrain height below the COM in 2 * dist + 1 columns."""
    return Block(f"floor sight +-{dist}", 2 * dist + 1, lambda s: terrain_sight(
        com_voxel_units(s.pos, s.n_points), s.terrain, dist, below=True))


def ceiling_sight(dist: int) -> Block:
    """evogym's get_ceil_obs: terrain above the COM in 2 * dist + 1 columns."""
    return Block(f"ceiling sight +-{dist}", 2 * dist + 1, lambda s: terrain_sight(
        com_voxel_units(s.pos, s.n_points), s.terrain, dist, below=False))
