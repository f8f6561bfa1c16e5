"""The shape-change tasks in a walled 20 x 10 box (ShapeChange.json, robot at cell (7, 1)); the
robot observes only its points relative to its COM.

AreaMaximizer-v0 / AreaMinimizer-v0: grow / shrink the area of the convex hull of the robot's
points (reward +-10 x its change); WingspanMazimizer-v0 (evogym's spelling): grow the x extent of
the points; HeightMaximizer-v0: grow their y extent.
"""

import numpy as np

from tasks import kernels as EK
from tasks import observations as O
from tasks.spec import Measure, TaskSpec
from tsim.backend import runtime
from tsim.backend.tables import ARCHS


def _chain(P: np.ndarray, n: np.ndarray, reverse: bool) -> np.ndarray:
    """One half of Andrew's monotone chain over the x-sorted points P (B, N, 2), all worlds at once
    (the loop runs over point positions, not over worlds; the sum over chain lengths): returns the
    sum of the cross products of consecutive chain vertices (twice the signed area under that
    half)."""
    B, N = P.shape[:2]
    rows = np.arange(B)
    H = np.zeros((B, N + 1, 2))
    L = np.zeros(B, dtype=np.int64)
    for k in range(N):
        active = k < n
        idx = np.where(active, n - 1 - k if reverse else k, 0)
        q = P[rows, idx]
        while True:
            a = H[rows, np.maximum(L - 2, 0)]
            b = H[rows, np.maximum(L - 1, 0)]
            turn = (b[:, 0] - a[:, 0]) * (q[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (q[:, 0] - a[:, 0])
            pop = active & (L >= 2) & (turn <= 0)
            if not pop.any():
                break
            L -= pop
        H[rows[active], L[active]] = q[active]
        L += active
    c = H[:, :-2, 0] * H[:, 1:-1, 1] - H[:, 1:-1, 0] * H[:, :-2, 1]
    # each chain summed over its own L - 1 terms (numpy's pairwise order for that length), not over
    # the batch's padded N - 1: the order, so the bits, would depend on the other robots' sizes
    out = np.zeros(B)
    for m in np.unique(L - 1):
        if m > 0:
            sel = np.flatnonzero(L - 1 == m)
            out[sel] = c[sel, :m].sum(axis=1)
    return out


def hull_area(points: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """(B,) area of the convex hull of each world's points (B, N, 2) where mask (B, N): by
    `tasks.kernels.hull_areas` (the same bits) once Taichi runs, the mask is each world's first
    points (a body's, in `Measure`) and they are finite (numpy's sort puts a NaN after the
    padding, the kernel's would not), else by `hull_area_numpy`."""
    B, N = mask.shape
    n = mask.sum(axis=1)
    if not (runtime.started() and 2 <= N <= 129 and np.array_equal(mask, np.arange(N)[None, :] < n[:, None])
            and (np.isfinite(points).all() or np.isfinite(points[mask]).all())):
        return hull_area_numpy(points, mask)
    out = np.empty(B)
    EK.hull_areas(np.ascontiguousarray(points).reshape(-1), N, n.astype(np.int32), np.empty((B, N), np.int32),
                  np.empty((B, 2 * N + 2)), np.empty(B * (N - 1)), out, ARCHS[runtime.resolved_arch()].host)
    return out


def _hull(m: Measure) -> np.ndarray:
    """The robots' hull areas of a measure (once per measure): by the kernel where the env's kernel
    path made it, by numpy where its numpy path (the oracle) did."""
    return m.derived("hull_area", lambda m: (hull_area if m.kernels else hull_area_numpy)(m.points, m.mask))


def hull_area_numpy(points: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """(B,) area of the convex hull of each world's points (B, N, 2) where mask (B, N), batched:
    Andrew's monotone chain (collinear points dropped), lower and upper halves, shoelace area.
    evogym uses gift wrapping; the hull and its area are the same up to rounding. The test oracle
    of `hull_area`."""
    x = np.where(mask, points[:, :, 0], np.inf)
    y = np.where(mask, points[:, :, 1], np.inf)
    order = np.lexsort((y, x), axis=1)
    P = np.take_along_axis(points, order[:, :, None], axis=1)
    n = mask.sum(axis=1)
    return 0.5 * (_chain(P, n, reverse=False) + _chain(P, n, reverse=True))


def _extent(m: Measure, axis: int) -> np.ndarray:
    """The robots' extent along `axis` (max - min of their points), once per measure."""
    def compute(m: Measure) -> np.ndarray:
        v = m.points[:, :, axis]
        return np.where(m.mask, v, -np.inf).max(axis=1) - np.where(m.mask, v, np.inf).min(axis=1)
    return m.derived(f"extent{axis}", compute)


def area_max(before: Measure, after: Measure):
    """10 x the growth of the robot's convex hull area."""
    return (_hull(after) - _hull(before)) * 10


def area_min(before: Measure, after: Measure):
    """10 x the shrinking of the robot's convex hull area."""
    return -(_hull(after) - _hull(before)) * 10


def wingspan(before: Measure, after: Measure):
    """Growth of the robot's horizontal extent (max x - min x of its points)."""
    return _extent(after, 0) - _extent(before, 0)


def height(before: Measure, after: Measure):
    """Growth of the robot's vertical extent (max y - min y of its points)."""
    return _extent(after, 1) - _extent(before, 1)


def _spec(name: str, reward, steps: int) -> TaskSpec:
    return TaskSpec(name=name, world="ShapeChange.json", origin=(7, 1), paper_steps=steps,
                    evogym_steps=steps, observation=(O.POINTS,), reward=reward)


AREA_MAX = _spec("AreaMaximizer-v0", area_max, 600)
AREA_MIN = _spec("AreaMinimizer-v0", area_min, 600)
WINGSPAN = _spec("WingspanMazimizer-v0", wingspan, 600)
HEIGHT = _spec("HeightMaximizer-v0", height, 500)
