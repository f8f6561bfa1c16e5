"""Statistical parity on evogym's 160 random robots (issue 2 acceptance 3, issue 3 acceptance 3):
per task Spearman(ours, evogym) >= 0.9 x evogym's Spearman against its own +1e-6 rerun, and the
median |return difference| <= 4 x evogym's own pooled chaos median; and, as a tight regression bound,
the median |return difference| <= 1e-8 (achieved 2e-14, 7e-13, 2e-16 and 7e-11 for Walker,
ObstacleTraverser, Climber and Thrower)."""

import pytest

from parity.harness import validate_returns

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def report(data_dir):
    return validate_returns(data_dir / "returns")["tasks"]


def test_all_four_tasks_present(report):
    assert set(report) == {"Walker-v0", "ObstacleTraverser-v1", "Climber-v2", "Thrower-v0"}


@pytest.mark.parametrize("task", ["Walker-v0", "ObstacleTraverser-v1", "Climber-v2", "Thrower-v0"])
def test_returns_rank_and_size_like_evogym(report, task):
    t = report[task]
    assert t["spearman"] >= 0.9 * t["spearman_evogym_vs_perturbed"]
    assert t["median_abs_diff"] <= 4 * t["chaos_median_abs_return_diff"]


@pytest.mark.parametrize("task", ["Walker-v0", "ObstacleTraverser-v1", "Climber-v2", "Thrower-v0"])
def test_median_return_matches_evogym_to_near_rounding(report, task):
    """Regression bound, far below evogym's chaos median (>= 1.8e-4): half of the 40 robots' returns
    equal evogym's within 1e-8. A physics constant off by 1e-6 relative breaks it while the chaos
    bound above still holds. The simulation is deterministic, so the bound is not flaky."""
    assert report[task]["median_abs_diff"] <= 1e-8
