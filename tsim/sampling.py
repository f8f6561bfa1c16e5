"""Random robot bodies with evogym's default distribution (`sample_robot`), seeded with numpy.

`sample_robots` draws many at once: the same bodies, from the same stream, as that many calls of
`sample_robot` in a row, leaving the generator where they would: ~65x faster per body at 5x5
and ~40x at 10x10 (2.2 against 143 us, 0.24 against 8.9 ms, on an AMD EPYC VM)."""

from __future__ import annotations

import numbers
import operator

import numpy as np

from tsim.body import has_actuator, is_connected, is_connected_batch

DEFAULT_PD = (0.6, 0.2, 0.2, 0.2, 0.2)  # empty, rigid, soft, H, V (normalised: 3/7, 1/7 x 4)


def _normalised(pd: tuple[float, ...]) -> np.ndarray:
    p = np.asarray(pd, dtype=float)
    if (p.shape != (5,) or not np.isfinite(p).all() or np.any(p < 0) or p[1:].sum() <= 0
            or p[3:].sum() <= 0):
        raise ValueError(f"bad voxel distribution {pd}: need 5 finite non-negative weights with "
                         "non-zero non-empty and actuator mass")
    return p / p.sum()


def _count(name: str, value: object) -> int:
    """`value` as a non-negative int (numpy's integers and whole floats too: 2.0 is 2), or
    ValueError naming `name` (2.7 bodies are not 2)."""
    n = None
    if not isinstance(value, bool | np.bool_):
        try:
            n = operator.index(value)
        except TypeError:
            if isinstance(value, numbers.Real) and float(value).is_integer():
                n = int(value)
    if n is None or n < 0:
        raise ValueError(f"{name} must be a non-negative integer, got {value!r}")
    return n


def _shape(shape: object) -> tuple[int, int]:
    """`shape` as (rows, columns) of positive ints, or ValueError."""
    try:
        h, w = shape  # type: ignore[misc]
        h, w = _count("rows", h), _count("columns", w)
    except (TypeError, ValueError):
        h = w = 0
    if h < 1 or w < 1:
        raise ValueError(f"shape must be (rows, columns) of positive integers, got {shape!r}")
    return h, w


def sample_robot(shape: tuple[int, int], rng: np.random.Generator,
                 pd: tuple[float, ...] = DEFAULT_PD, max_tries: int = 100_000) -> np.ndarray:
    """Draw a random robot body as evogym does (rejection sampling).

    Each cell is drawn independently from `pd`; the whole matrix is drawn again until it is
    connected and has an actuator.

    Args:
        shape: (rows, columns) of the body matrix.
        rng: The generator to draw from.
        pd: The weights of the materials 0 to 4 (empty, rigid, soft, H_ACT, V_ACT), normalised here;
            evogym's by default.
        max_tries: How many matrices to draw before giving up.

    Returns:
        An (H, W) int64 body matrix.

    Raises:
        ValueError: When `shape` or `pd` is bad.
        RuntimeError: When no valid robot was found in `max_tries` draws.
    """
    p, shape = _normalised(pd), _shape(shape)
    for _ in range(max_tries):
        m = rng.choice(5, size=shape, p=p)
        if is_connected(m) and has_actuator(m):
            return m.astype(np.int64)
    raise RuntimeError(f"no valid robot found in {max_tries} draws")


def sample_robots(n: int, shape: tuple[int, int], rng: np.random.Generator,
                  pd: tuple[float, ...] = DEFAULT_PD, max_tries: int = 100_000) -> np.ndarray:
    """Draw n random robot bodies: exactly those of n calls of `sample_robot` in a row.

    `rng` is left where those calls leave it (where they raise, too).
    `Generator.choice(5, size, p)` is `cdf.searchsorted(rng.random(size), 'right')`; so whole
    chunks of draws are made at once, tested together (`is_connected_batch`), and the generator is
    then rewound and advanced by exactly the draws the n bodies took.

    Args:
        n: How many bodies.
        shape: As `sample_robot`'s.
        rng: As `sample_robot`'s.
        pd: As `sample_robot`'s.
        max_tries: As `sample_robot`'s, for each body.

    Returns:
        An (n, H, W) int64 array, the bodies of `sample_robot(shape, rng, pd, max_tries)`.

    Raises:
        ValueError: When `n`, `shape` or `pd` is bad.
        RuntimeError: As `sample_robot`, when one of the calls would.
    """
    n = _count("n", n)
    p = _normalised(pd)
    # numpy's own choice(): p as given to it (normalised above), then its cdf
    cdf = p.cumsum()
    cdf /= cdf[-1]
    h, w = _shape(shape)
    out = np.empty((n, h, w), dtype=np.int64)
    got = 0
    failed = 0  # draws since the last accepted body (sample_robot's max_tries counts these)
    rate = 0.2  # accepted fraction, re-estimated from every chunk
    while got < n:
        need = n - got
        k = int(min(max(need / max(rate, 1e-3) * 1.15 + 16, 64), 1 << 20))
        k = max(1, min(k, max(1, (1 << 24) // max(h * w, 1))))
        saved = rng.bit_generator.state
        r = rng.random((k, h, w))
        ok = _valid(r, cdf)
        idx = np.flatnonzero(ok)
        rate = max(max(len(idx), 0.5) / k, 1e-6)  # none accepted: at most half of one per chunk
        # the max_tries rule: sample_robot gives up after a run of max_tries failed draws, having
        # made exactly those draws; `failed` draws of the run came before this chunk (< max_tries)
        if not len(idx):  # a chunk of failures (common at 10x10: ~1 draw in 230 is accepted)
            if failed + k >= max_tries:
                _give_up(rng, saved, max_tries - failed, h, w, max_tries)
            failed += k
            continue
        starts = np.concatenate(([-1], idx))
        gaps = np.diff(starts) - 1  # failures before each accepted draw
        gaps[0] += failed
        over = np.flatnonzero(gaps >= max_tries)
        take = idx[:need]
        if len(over) and over[0] < len(take):
            j = int(over[0])  # the body sample_robot does not find: its run starts after body j - 1
            _give_up(rng, saved, int(starts[j]) + 1 - (failed if j == 0 else 0) + max_tries, h, w,
                     max_tries)
        if len(take) < need and k - 1 - int(idx[-1]) >= max_tries:  # the run after the last body
            _give_up(rng, saved, int(idx[-1]) + 1 + max_tries, h, w, max_tries)
        out[got:got + len(take)] = cdf.searchsorted(r[take], side="right")
        got += len(take)
        if len(take) == need:
            used = int(take[-1]) + 1
            if used < k:  # rewind, then advance by the draws the bodies took
                rng.bit_generator.state = saved
                rng.random((used, h, w))
            break
        failed = k - 1 - int(idx[-1])
    return out


def _give_up(rng: np.random.Generator, saved: dict, used: int, h: int, w: int, max_tries: int) -> None:
    """Raise as `sample_robot` does, the generator left where it leaves it: rewound to the chunk's
    start, then advanced by the `used` draws of it that the calls made."""
    rng.bit_generator.state = saved
    rng.random((max(used, 0), h, w))
    raise RuntimeError(f"no valid robot found in {max_tries} draws")


def _valid(r: np.ndarray, cdf: np.ndarray) -> np.ndarray:
    """(N,) bool: which of the matrices `cdf.searchsorted(r, "right")` `sample_robot` accepts,
    read from the uniform draws `r` (N, H, W) themselves.

    A cell is filled where r >= cdf[0] and an actuator (3 or 4) where r >= cdf[2]: those are the
    searchsorted values' own tests, so only accepted draws are turned into materials. A filled cell
    with no filled neighbour among several filled cells rules a body out before the flood fill,
    which most draws at 10x10 fail (~1 in 230 is accepted there)."""
    n = len(r)
    filled = r >= cdf[0]
    act = (r >= cdf[2]).reshape(n, -1).any(axis=1)
    ok = np.zeros(n, dtype=bool)
    sel = np.flatnonzero(act & ~_has_lone_cell(filled))
    ok[sel] = is_connected_batch(filled[sel])
    return ok


def _has_lone_cell(filled: np.ndarray) -> np.ndarray:
    """(N,) bool: the (N, H, W) masks with a filled cell whose four neighbours are empty while some
    other cell is filled (such a body is not connected)."""
    near = np.zeros_like(filled)
    near[:, 1:, :] |= filled[:, :-1, :]
    near[:, :-1, :] |= filled[:, 1:, :]
    near[:, :, 1:] |= filled[:, :, :-1]
    near[:, :, :-1] |= filled[:, :, 1:]
    n = len(filled)
    lone = (filled & ~near).reshape(n, -1).any(axis=1)
    return lone & (filled.reshape(n, -1).sum(axis=1) > 1)
