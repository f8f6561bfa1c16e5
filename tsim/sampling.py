"""Random robot bodies with evogym's default distribution (`sample_robot`), seeded with numpy.

`sample_robots` draws many at once: the same bodies, from the same stream, as that many calls of
`sample_robot` in a row, leaving the generator where they would (~100x faster per body)."""

from __future__ import annotations

import numpy as np

from tsim import constants as C
from tsim.body import has_actuator, is_connected, is_connected_batch

DEFAULT_PD = (0.6, 0.2, 0.2, 0.2, 0.2)  # empty, rigid, soft, H, V (normalised: 3/7, 1/7 x 4)


def _normalised(pd: tuple[float, ...]) -> np.ndarray:
    p = np.asarray(pd, dtype=float)
    if p.shape != (5,) or np.any(p < 0) or p[1:].sum() <= 0 or p[3:].sum() <= 0:
        raise ValueError(f"bad voxel distribution {pd}: need 5 non-negative weights with non-zero "
                         "non-empty and actuator mass")
    return p / p.sum()


def sample_robot(shape: tuple[int, int], rng: np.random.Generator,
                 pd: tuple[float, ...] = DEFAULT_PD, max_tries: int = 100_000) -> np.ndarray:
    """Draw cells independently from `pd`, redrawing the whole matrix until it is connected and
    has an actuator (evogym's rejection sampling)."""
    p = _normalised(pd)
    for _ in range(max_tries):
        m = rng.choice(5, size=shape, p=p)
        if is_connected(m) and has_actuator(m):
            return m.astype(np.int64)
    raise RuntimeError(f"no valid robot found in {max_tries} draws")


def sample_robots(n: int, shape: tuple[int, int], rng: np.random.Generator,
                  pd: tuple[float, ...] = DEFAULT_PD, max_tries: int = 100_000) -> np.ndarray:
    """(n, H, W) int64: exactly the bodies of n calls `sample_robot(shape, rng, pd, max_tries)` in a
    row, and `rng` left where those calls leave it.

    `Generator.choice(5, size, p)` is `cdf.searchsorted(rng.random(size), 'right')`; so whole
    chunks of draws are made at once, tested together (`is_connected_batch`), and the generator is
    then rewound and advanced by exactly the draws the n bodies took."""
    n = int(n)
    if n < 0:
        raise ValueError(f"n must be >= 0, got {n}")
    p = _normalised(pd)
    # numpy's own choice(): p as given to it (normalised above), then its cdf
    cdf = p.cumsum()
    cdf /= cdf[-1]
    h, w = int(shape[0]), int(shape[1])
    out = np.empty((n, h, w), dtype=np.int64)
    got = 0
    failed = 0  # draws since the last accepted body (sample_robot's max_tries counts these)
    rate = 0.2  # accepted fraction, re-estimated from every chunk
    while got < n:
        need = n - got
        k = int(min(max(need / max(rate, 1e-3) * 1.15 + 16, 64), 1 << 20))
        k = max(1, min(k, max(1, (1 << 24) // max(h * w, 1))))
        saved = rng.bit_generator.state
        m = cdf.searchsorted(rng.random((k, h, w)), side="right")
        ok = _valid(m)
        idx = np.flatnonzero(ok)
        rate = max(len(idx) / k, 1e-4)
        # the max_tries rule: a run of max_tries failures before the next acceptance
        starts = np.concatenate(([-1], idx))
        gaps = np.diff(starts) - 1  # failures before each accepted draw
        gaps[0] += failed
        over = np.flatnonzero(gaps >= max_tries)
        take = idx[:need]
        if len(over) and over[0] < len(take):
            raise RuntimeError(f"no valid robot found in {max_tries} draws")
        if len(take) < need and failed + (k - 1 - (idx[-1] if len(idx) else -1)) >= max_tries:
            raise RuntimeError(f"no valid robot found in {max_tries} draws")
        out[got:got + len(take)] = m[take]
        got += len(take)
        if len(take) == need:
            used = int(take[-1]) + 1
            if used < k:  # rewind, then advance by the draws the bodies took
                rng.bit_generator.state = saved
                rng.random((used, h, w))
            break
        failed = k - 1 - int(idx[-1]) if len(idx) else failed + k
    return out


def _valid(m: np.ndarray) -> np.ndarray:
    """(N,) bool: which of the (N, H, W) matrices `sample_robot` accepts."""
    flat = m.reshape(len(m), -1)
    act = ((flat == C.H_ACT) | (flat == C.V_ACT)).any(axis=1)
    ok = np.zeros(len(m), dtype=bool)
    sel = np.flatnonzero(act)
    ok[sel] = is_connected_batch(m[sel])
    return ok
