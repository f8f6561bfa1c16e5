"""f32's initial coordinates (`tsim.rounding`): float32 pairs hi + lo that hold evogym's float64
placements to ~1e-15 and in their order (the rests rounded by `to_real`, which keeps the order and
the ties of what it rounds), which decides contacts from the first substep on."""

import itertools

import numpy as np

from tsim.rounding import rest, to_pair, to_real

# Climber-v1: the robot's bottom rests 3.4e-16 above its pipe's floor, whose top lies below the
# grid line 0.1; the robot's right side 1.1e-16 left of the pipe's wall at 6 * 0.1
CLIMBER = np.array([0.09999999999999998, 0.09999999999999964, 0.1, 0.10000000000000003,
                    0.6, 0.6000000000000001, 0.39999999999999947, 0.39999999999999997, 0.4])


def _orders(x: np.ndarray) -> np.ndarray:
    return np.sign(x[:, None] - x[None, :])


def test_float32_keeps_the_order_and_the_ties_of_evogyms_placements():
    """Plain float32 rounds the robot's bottom and the pipe's floor (0.09999999999999998 and
    ...964) to the same number: the robot would start on the floor's edge, inside it."""
    r = to_real(CLIMBER, np.float32)
    assert r.dtype == np.float32
    assert np.array_equal(_orders(r.astype(np.float64)), _orders(CLIMBER))
    # each within a few float32 ulps of plain rounding
    ulp = np.spacing(np.abs(CLIMBER).astype(np.float32)).astype(np.float64)
    assert np.all(np.abs(r.astype(np.float64) - CLIMBER) <= 3 * ulp)


def test_the_order_holds_for_clusters_of_placements_around_every_grid_line():
    """Values a few float64 ulps either side of k * 0.1 (as evogym's sums of 0.1s give), equal
    values repeated: every pair keeps its order or its tie."""
    rng = np.random.default_rng(3)
    k = rng.integers(0, 80, 400)
    x = k * 0.1 + rng.integers(-40, 41, 400) * np.spacing(k * 0.1 + 0.05)
    x = np.concatenate([x, x[:50], rng.uniform(0, 8, 100)])
    r = to_real(x, np.float32).astype(np.float64)
    for i, j in itertools.islice(itertools.combinations(range(len(x)), 2), 0, None, 7):
        assert np.sign(r[i] - r[j]) == np.sign(x[i] - x[j]), (x[i], x[j], r[i], r[j])


def test_fixed_values_keep_their_rounding_and_bodies_order_against_them():
    """A world's bodies are rounded against the terrain, which was rounded once for the batch."""
    terrain = np.array([0.09999999999999964, 0.2, 0.6000000000000001])
    t32 = to_real(terrain, np.float32)
    body = np.array([0.09999999999999998, 0.09999999999999964, 0.6, 0.6000000000000001, 0.2])
    b32 = to_real(body, np.float32, fixed=(terrain, t32)).astype(np.float64)
    both = np.concatenate([terrain, body])
    assert np.array_equal(_orders(np.concatenate([t32.astype(np.float64), b32])), _orders(both))
    assert b32[1] == t32[0] and b32[3] == t32[2] and b32[4] == t32[1]


def test_f64_keeps_the_placement_itself():
    assert to_real(CLIMBER, np.float64) is CLIMBER


def _sums(hi: np.ndarray, lo: np.ndarray) -> np.ndarray:
    return hi.astype(np.float64) + lo.astype(np.float64)


def test_pairs_hold_the_placement_and_its_order_against_the_terrain():
    """Lifter-v0's robot side at 0.6 stands 1.1e-16 left of its slot's wall at 0.6000000000000001;
    a float32 number alone puts both at 0.6000000238 (or, keeping the order, 6e-8 apart). The
    pairs keep the wall on its side of the robot, each sum within 4e-15 of float64's, and equal
    coordinates equal; the robot's are rounded against the terrain's rests (rounded once)."""
    terrain = np.concatenate([CLIMBER[[1, 5, 7]], [20.000000000000004]])
    t_hi, t_lo = to_pair(terrain, np.float32)
    body = np.concatenate([CLIMBER, [0.5, 0.5, 20.0, 20.000000000000004]])
    b_hi, b_lo = to_pair(body, np.float32, (rest(terrain, t_hi), t_lo))
    assert b_hi.dtype == b_lo.dtype == np.float32
    sums = np.concatenate([_sums(t_hi, t_lo), _sums(b_hi, b_lo)])
    both = np.concatenate([terrain, body])
    assert np.array_equal(_orders(sums), _orders(both))
    assert np.abs(sums - both).max() < 4e-15
    # hi is plain rounding: the gap lives in lo, where a difference of two nearby pairs sees it
    assert np.array_equal(b_hi, body.astype(np.float32))
    i, j = list(body).index(0.6), list(body).index(0.6000000000000001)
    assert b_hi[i] == b_hi[j] and b_lo[i] < b_lo[j]


def test_pairs_keep_the_order_of_crowded_placements():
    """Hundreds of values a few float64 ulps around the grid lines (as in
    `test_the_order_holds_for_clusters_of_placements_around_every_grid_line`), out to x = 40. Rests
    closer than lo's own ulp (1e-13 at 40, against float64's 7e-15) are spread to keep their
    order: the sums then lie up to ~40 lo ulps off (measured 1.0e-13 relative), still far below
    float32's 6e-8."""
    rng = np.random.default_rng(4)
    k = rng.integers(0, 400, 500)
    x = k * 0.1 + rng.integers(-40, 41, 500) * np.spacing(k * 0.1 + 0.05)
    x = np.concatenate([x, x[:50]])
    s = _sums(*to_pair(x, np.float32))
    for i, j in itertools.islice(itertools.combinations(range(len(x)), 2), 0, None, 7):
        assert np.sign(s[i] - s[j]) == np.sign(x[i] - x[j]), (x[i], x[j], s[i], s[j])
    assert np.all(np.abs(s - x) <= 2e-13 * np.maximum(np.abs(x), 0.1))
