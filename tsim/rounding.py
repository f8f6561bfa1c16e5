"""Initial coordinates in float32 pairs that hold evogym's float64 placement in its order (f32
only; f64 keeps the placement itself).

Why: evogym places bodies a few float64 ulps off the grid lines k * CELL, and which of two nearly
equal coordinates is the larger decides contacts from the first substep on. Climber-v1's robot
rests 3.4e-16 above its pipe's floor (y = 0.09999999999999998 over 0.09999999999999964): out of
contact in f64, while float32 rounds both to 0.099999994 and the robot's corners start on the
floor's edge, inside it (the point-in-voxel test counts the boundary), pushed up with >= 10,500
force units. Lifter-v0's robot stands 1.1e-16 left of its slot's wall (0.6 against
0.6000000000000001), and a tilt of 7.7e-12 in the first substep makes a contact there: float32
numbers alone cannot hold that gap, whether they tie (a contact at once) or keep the order 6e-8
apart (the tilt never reaches the wall).

So each coordinate x becomes a pair hi + lo (`to_pair`): hi its float32 rounding, lo the rest
x - hi (exact in float64) rounded to float32 by `to_real`, which keeps the order and the ties of
what it rounds. Among coordinates with one hi, the rests' order is the coordinates', so the pairs
keep float64's order and hold x to ~1e-15; the contacts read them as differences of pairs
(`tsim.kernels.narrowphase.corner_less`). `to_real`'s anchors, whose rounding is given: the grid
lines (plain rounding; a value keeps its side of them: for rests, 0) and `fixed` values (the
terrain's rests, rounded once for the whole batch, against which each world's bodies are
rounded; a grid line within 2 float32 numbers of a fixed value gives way to it, so that a value
between the two finds room).
"""

from __future__ import annotations

import numpy as np

from tsim import constants as C


def _keys(r: np.ndarray) -> np.ndarray:
    """float32 -> int64, increasing with the value and by 1 between neighbouring float32 numbers
    (-0.0 and 0.0 are both 0)."""
    i = r.astype(np.float32).view(np.int32).astype(np.int64)
    return np.where(i >= 0, i, -(i & 0x7FFFFFFF))


def _floats(k: np.ndarray) -> np.ndarray:
    """The inverse of `_keys`."""
    bits = np.where(k >= 0, k, (-k) | 0x80000000).astype(np.uint32)
    return bits.view(np.float32)


def to_real(x: np.ndarray, dtype: type, fixed: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """Coordinates x (float64, world units) in the real type `dtype`: for float64 x itself; for
    float32 each value rounded so that the order of any two values of x (and of x against the grid
    lines k * CELL and the `fixed` values) is float64's, as near plain rounding as that allows.
    `fixed`: (float64 values, their float32 roundings), which stay as they are (the terrain's,
    when a world's bodies are rounded). Equal values stay equal; two values that float32 cannot
    tell apart become neighbouring float32 numbers, moved away from the nearest grid line or fixed
    value (an order is lost, as a tie, only where more distinct values lie between two anchors than
    float32 has numbers there)."""
    if dtype == np.float64:
        return x
    x = np.asarray(x, dtype=np.float64)
    if x.size == 0:
        return x.astype(dtype)
    u, inv = np.unique(x, return_inverse=True)
    k0 = int(np.floor(u[0] / C.CELL)) - 1
    k1 = int(np.ceil(u[-1] / C.CELL)) + 1
    grid = np.arange(k0, k1 + 1) * C.CELL  # evogym's grid lines, as its placement computes them
    a_val, a_key = grid, _keys(grid)
    if fixed is not None and len(fixed[0]):
        f_val, first = np.unique(np.asarray(fixed[0], dtype=np.float64), return_index=True)
        f_key = _keys(np.asarray(fixed[1]))[first]
        # a fixed value anchors its neighbourhood: the grid lines next to one are left out (else a
        # value between the two might find no float32 number between theirs)
        sk = np.sort(f_key)
        near = np.searchsorted(sk, a_key)
        gap = np.minimum(np.abs(a_key - sk[np.minimum(near, len(sk) - 1)]),
                         np.abs(a_key - sk[np.maximum(near - 1, 0)]))
        keep = gap > 2
        a_val = np.concatenate([f_val, a_val[keep]])
        a_key = np.concatenate([f_key, a_key[keep]])
        order = np.argsort(a_val, kind="stable")
        a_val, a_key = a_val[order], a_key[order]
    naive = _keys(u)
    key = naive.copy()
    j = np.searchsorted(a_val, u, side="right") - 1  # a_val[j] <= u < a_val[j + 1]
    on = a_val[j] == u
    key[on] = a_key[j[on]]
    lo_key, hi_key = a_key[j], a_key[np.minimum(j + 1, len(a_val) - 1)]
    lower = ~on & (u - a_val[j] <= a_val[np.minimum(j + 1, len(a_val) - 1)] - u)
    upper = ~on & ~lower
    big = np.int64(1) << 40  # keys lie within +-2^31: offsets that keep the groups apart
    # values nearer their lower anchor, ascending per interval: each at least one float32 above
    # the anchor and above the value before it
    idx = np.nonzero(lower)[0]
    if len(idx):
        g = j[idx]
        rank = np.arange(len(idx)) - np.searchsorted(g, g)
        run = np.maximum.accumulate(np.maximum(naive[idx] - rank, lo_key[idx] + 1) + g * big) - g * big
        key[idx] = run + rank
    # values nearer their upper anchor, descending per interval: at least one below each
    idx = np.nonzero(upper)[0][::-1]
    if len(idx):
        g = j[idx]
        rank = np.arange(len(idx)) - np.searchsorted(-g, -g)
        run = np.minimum.accumulate(np.minimum(naive[idx] + rank, hi_key[idx] - 1) + g * big) - g * big
        key[idx] = run - rank
    # crowded intervals: never reverse an order (ties at worst) nor pass an anchor
    free = ~on
    key[free] = np.clip(key[free], np.minimum(lo_key[free] + 1, hi_key[free]),
                        np.maximum(hi_key[free] - 1, lo_key[free]))
    key = np.maximum.accumulate(key)
    return _floats(key)[inv].reshape(x.shape).astype(dtype)


def rest(x: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """x - hi in float64: exact (hi is x rounded to a nearby float32 number, Sterbenz)."""
    return np.asarray(x, dtype=np.float64) - np.asarray(hi).astype(np.float64)


def to_pair(x: np.ndarray, dtype: type,
            fixed_rest: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Coordinates x (float64) as float32 pairs hi + lo: hi plain rounding, lo the rest x - hi
    rounded by `to_real` (against `fixed_rest`: the terrain's rests and their roundings), so that
    the pairs hold x to ~1e-15 where hi alone is 6e-8 off at 0.6, and keep float64's order: among
    equal hi, the rests' order is the coordinates' (evogym's 0.6 and 0.6000000000000001 share a hi
    and keep their gap in lo, which the contacts read as a difference: `narrowphase.corner_less`)."""
    x = np.asarray(x, dtype=np.float64)
    hi = x.astype(dtype)
    return hi, to_real(rest(x, hi), dtype, fixed_rest)
