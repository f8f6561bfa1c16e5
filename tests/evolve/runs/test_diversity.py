"""generations.csv's body_diversity: the mean pairwise body distance of each generation's valid
genomes (eq. 2 of the SGR paper per cell), recorded by every method with bodies, and an older
run's file taking the column on when it is resumed, its other values untouched."""

from __future__ import annotations

import csv
import itertools
import math

import numpy as np
import pytest

from evolve.runs.experiment import Experiment
from evolve.search.body_distance import body_distance, mean_pairwise_body_distance
from tests.evolve.conftest import TINY


def test_three_bodies_worked_by_hand():
    """[0 1], [0 2], [3 0]: the first two differ in one cell between two materials (0.5), each of
    them and the third in two cells empty against filled (2 each): 4.5 over 3 pairs and 2 cells."""
    bodies = [np.array([[0, 1]]), np.array([[0, 2]]), np.array([[3, 0]])]
    assert mean_pairwise_body_distance(bodies) == 4.5 / 3 / 2
    assert mean_pairwise_body_distance(bodies[:1]) != mean_pairwise_body_distance(bodies[:1])  # NaN
    assert mean_pairwise_body_distance([bodies[0]] * 5) == 0.0


def test_counting_equals_comparing_every_pair_with_eq_2():
    rng = np.random.default_rng(0)
    for n, shape in ((2, (5, 5)), (9, (5, 5)), (30, (10, 10)), (17, (3, 7))):
        bodies = [rng.integers(0, 5, shape) for _ in range(n)]
        bodies[1] = bodies[0]  # a repeated body, as elites give
        pairs = [body_distance(a, b) for a, b in itertools.combinations(bodies, 2)]
        assert mean_pairwise_body_distance(bodies) == pytest.approx(np.mean(pairs) / (shape[0] * shape[1]),
                                                                   rel=1e-12)


@pytest.mark.slow
@pytest.mark.parametrize("method", ["sgr", "direct", "nested"])
def test_every_method_with_bodies_records_it(tmp_path, method):
    with Experiment.from_config({"method": method, **TINY}, tmp_path / "run", quiet=True) as exp:
        exp.run_all()
    rows = list(csv.DictReader((tmp_path / "run" / "generations.csv").open()))
    values = [float(r["body_diversity"]) for r in rows]
    assert len(values) == TINY["generations"] and all(0.0 <= v <= 1.0 for v in values)


def test_an_older_run_resumed_gains_the_column_and_keeps_every_other_value(tmp_path):
    """A run whose generations.csv lacks body_diversity (an older sgr's), resumed for one more
    generation: the header gains the column, the old rows keep their values with the new cell
    empty, and the rows equal those of the same run made in one go."""
    cfg = {"method": "sgr", **TINY, "checkpoint_every": 1}
    with Experiment.from_config(cfg, tmp_path / "whole", quiet=True) as exp:
        exp.run_all()
    whole = list(csv.DictReader((tmp_path / "whole" / "generations.csv").open()))
    with Experiment.from_config({**cfg, "generations": 1}, tmp_path / "old", quiet=True) as exp:
        exp.run_all()
    f = tmp_path / "old" / "generations.csv"
    f.write_text("".join(line.rsplit(",", 1)[0] + "\n" for line in f.read_text().splitlines()))
    with Experiment.resume(str(tmp_path / "old"), quiet=True, generations=2) as exp:
        exp.run_all()
    rows = list(csv.DictReader(f.open()))
    assert f.read_text().splitlines()[0].endswith(",body_diversity")
    assert rows[0]["body_diversity"] == "" and rows[1]["body_diversity"] == whole[1]["body_diversity"]
    for old, new in zip(rows, whole, strict=True):
        for column in ("generation", "best", "mean", "median", "n_species", "n_valid", "n_invalid",
                       "episodes"):
            assert old[column] == new[column], column
    assert not math.isnan(float(whole[0]["body_diversity"]))


class BodiesBeforeEachGeneration:
    """A reporter: the valid bodies of the population about to be evaluated, at the loop's start
    and after each generation (the search has bred and decoded the next one by then)."""

    def __init__(self):
        self.bodies: list[list[np.ndarray]] = []

    def start(self, exp):
        self._see(exp)

    def generation(self, exp, row):
        self._see(exp)

    def _see(self, exp):
        s = exp.search
        self.bodies.append([s.phenotypes[k].body for k in s.population if s.phenotypes[k].valid])


def test_each_rows_body_diversity_is_that_of_the_valid_bodies_the_generation_evaluated(tmp_path):
    """Recomputed pair by pair with eq. 2 from the bodies each generation held: the mean distance
    per cell over every pair of its valid bodies."""
    seen = BodiesBeforeEachGeneration()
    cfg = {"method": "sgr", **TINY, "generations": 3}
    with Experiment.from_config(cfg, tmp_path / "run", quiet=True) as exp:
        exp.add_reporter(seen)
        exp.run_all()
    rows = list(csv.DictReader((tmp_path / "run" / "generations.csv").open()))
    assert len(rows) == 3
    for row, bodies in zip(rows, seen.bodies, strict=False):
        cells = bodies[0].size
        pairs = [body_distance(a, b) / cells for a, b in itertools.combinations(bodies, 2)]
        assert len(bodies) == int(row["n_valid"]) and len(pairs) > 0
        assert float(row["body_diversity"]) == pytest.approx(float(np.mean(pairs)), rel=1e-12)
