"""The ga-ppo method's genetic algorithm (evolve/methods/ga_ppo.py): evogym's mutation and
survival schedule, its settings checked in one line."""

from __future__ import annotations

import numpy as np
import pytest

from evolve.methods.ga_ppo import GaPpoProblem, GaSearch, GaSettings, mutate
from evolve.runs.config import config_from_dict
from tsim.body import has_actuator, is_connected
from tsim.errors import SgrError

pytest.importorskip("torch", reason="method ga-ppo needs torch: pip install 'sgr[rl]'")

PARENT = np.array([[3, 3, 3, 3, 3], [1, 1, 1, 1, 1], [3, 0, 0, 0, 3], [3, 0, 0, 0, 3], [3, 0, 0, 0, 3]])


def test_mutants_are_valid_robots_that_differ_from_their_parent_by_about_the_rate():
    rng = np.random.default_rng(0)
    made = [mutate(PARENT, 0.1, rng) for _ in range(400)]
    kids = [k for k in made if k is not None]  # None: no valid mutant in 50 tries (evogym's rule)
    assert len(kids) > 350 and all(is_connected(k) and has_actuator(k) for k in kids)
    # a redrawn voxel keeps its material with probability 1/7 (empty: 3/7): ~0.1 x 0.8 of the voxels
    # changed by one try (2 of 25); more where the first tries gave no valid robot
    changed = np.median([np.sum(k != PARENT) for k in kids])
    assert 1 <= changed <= 3, changed
    assert np.array_equal(mutate(PARENT, 0.0, rng), PARENT)


def search(pop: int, generations: int, **ga) -> GaSearch:
    cfg = config_from_dict({"method": "ga-ppo", "task": "Walker-v0", "pop_size": pop,
                            "generations": generations, "ga": ga})
    return GaSearch(GaPpoProblem(cfg), seed=0)


def test_survivors_fall_linearly_from_sixty_percent_to_two_over_the_generations():
    s = search(10, 5)
    got = []
    for g in range(1, 5):
        s.generation = g
        got.append(s.survivors())
    assert got == [5, 3, 2, 2]  # ceil(10 x 0.6 x (5-1-g)/4): 4.5, 3, 1.5 -> 2, 0 -> 2


def test_with_max_evaluations_survivors_fall_over_the_bodies_evaluated():
    """evogym's run_ga.py: the fraction 0.6 x (M - n - 1) / (M - 1) after n bodies of M."""
    s = search(25, 100, max_evaluations=750)
    s.evaluations = 25
    assert s.survivors() == 15  # ceil(25 x 0.6 x 724 / 749) = ceil(14.499)
    s.evaluations = 740
    assert s.survivors() == 2


def test_the_first_generation_is_pop_size_distinct_valid_bodies():
    s = search(12, 3)
    new = s._first()
    assert len(new) == 12 == len({r.body.tobytes() for r in new}) == len(s.seen)
    assert all(is_connected(r.body) and has_actuator(r.body) for r in new)
    assert [r.key for r in new] == list(range(1, 13))


@pytest.mark.parametrize(("raw", "match"), [
    ({"mutation_rate": 2}, "ga.mutation_rate' must be a number from 0 to 1"),
    ({"max_evaluations": 3}, r"ga.max_evaluations' must be null or an int from pop_size \(16\)"),
    ({"rate": 0.1}, "unknown key 'rate'; known keys: mutation_rate, survival, max_evaluations"),
])
def test_a_bad_ga_setting_is_one_line(raw, match):
    with pytest.raises(SgrError, match=match):
        GaSettings.from_config(raw, 16, "run.yaml")
