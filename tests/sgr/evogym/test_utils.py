"""sgr.evogym.utils against evogym itself (tests/data/evogym_api/samples.json, recorded by
references/evogym_api_reference.py): a seeded script samples evogym's robots."""

import json
import random
from pathlib import Path

import numpy as np
import pytest

from sgr.evogym import Pair, draw, get_full_connectivity, hashable, sample_robot

DATA = Path(__file__).resolve().parents[2] / "data" / "evogym_api"
REF = json.loads((DATA / "samples.json").read_text())


@pytest.mark.parametrize("case", REF["seeds"], ids=lambda c: f"seed{c['seed']}")
def test_seeded_sample_robot_gives_evogyms_robot_and_connections(case):
    random.seed(case["seed"])
    body, conn = sample_robot((5, 5))
    assert body.dtype == np.float64
    np.testing.assert_array_equal(body, np.array(case["body"]))
    np.testing.assert_array_equal(conn, np.array(case["connections"]))


def test_custom_distribution_and_draws_follow_evogyms_random_stream():
    c = REF["custom"]
    random.seed(c["seed"])
    body, conn = sample_robot((4, 6), np.array(c["pd"]))
    np.testing.assert_array_equal(body, np.array(c["body"]))
    np.testing.assert_array_equal(conn, np.array(c["connections"]))
    d = REF["draws"]
    random.seed(d["seed"])
    assert [draw(d["pd"]) for _ in d["values"]] == d["values"]


def test_hashable_and_empty_connectivity_and_pair_arithmetic():
    assert hashable(np.array([[1.0, 0.0], [3.0, 4.0]])) == "1034"
    empty = get_full_connectivity(np.zeros((2, 2)))
    assert empty.shape == (2, 0)
    assert Pair(7, 3) / 2 == Pair(3, 1)
    assert Pair(1, 2) + 1 == Pair(2, 3) and Pair(1, 2) * Pair(3, 3) == Pair(3, 6)
    assert {Pair(1, 2): "a"}[Pair(1, 2)] == "a"
    with pytest.raises(TypeError):
        Pair(1.5, 2)


def test_bad_distributions_are_one_line_value_errors():
    with pytest.raises(ValueError, match="actuator"):
        sample_robot((3, 3), np.array([1.0, 1, 1, 0, 0]))
    with pytest.raises(ValueError, match="actuator must"):  # evogym checks actuators first
        sample_robot((3, 3), np.array([1.0, 0, 0, 0, 0]))
    with pytest.raises(ValueError, match="shape"):
        sample_robot((3, 3), np.ones(4))
    with pytest.raises(ValueError, match="non-negative"):
        draw([0.5, -1])
