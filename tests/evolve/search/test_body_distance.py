"""Body distance of the paper's eq. 2 on hand-made bodies, and its place in the speciation distance."""

import numpy as np
import pytest

from evolve.search.body_distance import body_distance

A = np.array([[1, 2], [3, 0]])


@pytest.mark.parametrize("b, expected", [
    (np.array([[1, 2], [3, 0]]), 0.0),  # identical
    (np.array([[2, 2], [3, 0]]), 0.5),  # rigid vs soft
    (np.array([[1, 2], [4, 0]]), 0.5),  # H vs V actuator
    (np.array([[0, 2], [3, 0]]), 1.0),  # rigid vs empty
    (np.array([[1, 2], [3, 4]]), 1.0),  # empty vs actuator
    (np.array([[2, 1], [0, 3]]), 0.5 + 0.5 + 1.0 + 1.0),
    (np.zeros((2, 2), dtype=int), 3.0),
])
def test_eq2_values(b, expected):
    assert body_distance(A, b) == expected
    assert body_distance(b, A) == expected


def test_shapes_must_match():
    with pytest.raises(ValueError, match="different shapes"):
        body_distance(A, np.zeros((3, 3)))
