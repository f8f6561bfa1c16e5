"""evogym's orientation estimate (`object_orientation_at_time`), batched, summed in Eigen's order."""

from __future__ import annotations

import numpy as np

PI_EVOGYM = 3.1415926


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
    """evogym's orientation of each robot (`object_orientation_at_time`).

    It is the mass-weighted mean unsigned angle of the centred points against time 0, with evogym's
    clamps, pi = 3.1415926 and the sign taken from the summed cross products. It sums in Eigen's
    order (`_eigen_com`, `_eigen_sum`), so that the points of an undeformed body whose dot products
    round above 1 (clamped to arccos(0.99999)) are the same as evogym's: the result then equals
    evogym's to rounding, at reset too.

    Args:
        pos: (B, N, 2) the robots' point positions, zero-padded.
        pos0: (B, N, 2) their positions at time 0.
        mask: (B, N) which points are real.

    Returns:
        (B,) angles in radians.
    """
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
