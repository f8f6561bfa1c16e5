"""The shape-change tasks in a walled 20 x 10 box (ShapeChange.json, robot at cell (7, 1)); the
robot observes only its points relative to its COM.

AreaMaximizer-v0 / AreaMinimizer-v0: grow / shrink the area of the convex hull of the robot's
points (reward +-10 x its change); WingspanMazimizer-v0 (evogym's spelling): grow the x extent of
the points; HeightMaximizer-v0: grow their y extent.
"""

import numpy as np

from tasks import observations as O
from tasks.spec import Measure, TaskSpec

HULL_EPS = 1e-12  # |cross| (world units^2) below which three points count as collinear


def hull_area(points: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """(B,) area of the convex hull of each world's points (B, N, 2) where mask (B, N), batched.

    Edge i -> j is on the hull (counter-clockwise) when no point lies right of it and none lies
    strictly between i and j on it (so collinear boundary points split it into pieces); the area
    is the shoelace sum over those edges. Exact for any point set without duplicate points; cost
    O(B N^3) booleans (24 robots of 36 points: ~1 M).
    """
    p = np.where(mask[:, :, None], points, 0.0)
    e = p[:, None, :, :] - p[:, :, None, :]  # (B, i, j, 2): p_j - p_i
    r = p[:, None, None, :, :] - p[:, :, None, None, :]  # (B, i, 1, k, 2): p_k - p_i
    cross = e[:, :, :, None, 0] * r[..., 1] - e[:, :, :, None, 1] * r[..., 0]  # (B, i, j, k)
    dot = e[:, :, :, None, 0] * r[..., 0] + e[:, :, :, None, 1] * r[..., 1]
    len2 = (e ** 2).sum(axis=3)[..., None]
    k_real = mask[:, None, None, :]
    right = (cross < -HULL_EPS) & k_real
    between = (np.abs(cross) <= HULL_EPS) & (dot > 0) & (dot < len2) & k_real
    edge = ~(right | between).any(axis=3)
    edge &= mask[:, :, None] & mask[:, None, :] & (len2[..., 0] > 0)
    xi, yi = p[:, :, None, 0], p[:, :, None, 1]
    xj, yj = p[:, None, :, 0], p[:, None, :, 1]
    return 0.5 * np.where(edge, xi * yj - xj * yi, 0.0).sum(axis=(1, 2))


def _extent(m: Measure, axis: int) -> np.ndarray:
    v = m.points[:, :, axis]
    return np.where(m.mask, v, -np.inf).max(axis=1) - np.where(m.mask, v, np.inf).min(axis=1)


def area_max(before: Measure, after: Measure):
    return (hull_area(after.points, after.mask) - hull_area(before.points, before.mask)) * 10


def area_min(before: Measure, after: Measure):
    return -(hull_area(after.points, after.mask) - hull_area(before.points, before.mask)) * 10


def wingspan(before: Measure, after: Measure):
    return _extent(after, 0) - _extent(before, 0)


def height(before: Measure, after: Measure):
    return _extent(after, 1) - _extent(before, 1)


def _spec(name: str, reward, steps: int) -> TaskSpec:
    return TaskSpec(name=name, world="ShapeChange.json", origin=(7, 1), paper_steps=steps,
                    evogym_steps=steps, observation=(O.POINTS,), reward=reward)


AREA_MAX = _spec("AreaMaximizer-v0", area_max, 600)
AREA_MIN = _spec("AreaMinimizer-v0", area_min, 600)
WINGSPAN = _spec("WingspanMazimizer-v0", wingspan, 600)
HEIGHT = _spec("HeightMaximizer-v0", height, 500)
