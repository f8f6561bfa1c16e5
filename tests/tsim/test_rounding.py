"""f32's initial coordinates (`tsim.rounding`): float32 numbers that keep the order float64 gives
evogym's placements, which decides contacts from the first substep on."""

import itertools

import numpy as np

from tsim.sim import to_real

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
