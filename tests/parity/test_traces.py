"""Trajectory parity with evogym's recorded traces (issue 2 acceptance 2, issue 3 acceptance 2).

Tolerances: per task the median final COM error <= 2x evogym's own chaos median, the median max
COM error over the first 50 steps <= 0.005 and every case's <= 0.05; observation length equal to
evogym's and the reset observation within 1e-9, the orientation entry included (evogym's reset
orientation is a rounding artefact of ~1e-3 that we reproduce by summing in Eigen's order, see
VALIDATION.md). Besides these chaos-based bounds, a
tight regression bound: every case's max COM error over the first 50 steps <= 1e-9 (achieved ~4e-15).
"""

import numpy as np
import pytest

from parity.harness import validate_traces

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def report(data_dir):
    return validate_traces(data_dir / "traces")


def test_every_task_within_chaos_floor(report):
    assert set(report["tasks"]) == {"Walker-v0", "ObstacleTraverser-v1", "Climber-v2", "Thrower-v0"}
    for task, t in report["tasks"].items():
        assert t["median_com_err_final"] <= 2 * t["chaos_median"], task
        assert t["median_com_err_max50"] <= 0.005, task


def test_every_case_close_over_first_50_steps(report):
    assert len(report["cases"]) == 16
    for c in report["cases"]:
        assert c["com_err_max50"] <= 0.05, c["file"]


def test_every_case_matches_evogym_to_rounding_over_first_50_steps(report):
    """Regression bound, far below the chaos-based ones: over the first 50 steps every case's COM
    stays within 1e-9 world units of evogym's (achieved: <= 4e-15, i.e. rounding). A physics change
    (a constant off by 1e-6 relative) shows up here even where it hides under evogym's chaos floor.
    The simulation is deterministic (one thread per world, no atomics), so this is not flaky."""
    for c in report["cases"]:
        assert c["com_err_max50"] <= 1e-9, c["file"]


def test_observation_length_and_reset_observation(report, data_dir):
    for c in report["cases"]:
        assert c["obs_dim"] == c["obs_dim_evogym"], c["file"]
        assert c["obs_err_step0"] <= 1e-9, c["file"]


def test_observation_matches_every_step_for_50_steps_orientation_included(report):
    """The whole observation over the first 50 steps, not only at reset: <= 1e-12 (achieved
    1.2e-13), and the orientation entry (ObstacleTraverser-v1, Climber-v2) <= 1e-12 (achieved
    4.5e-13). An orientation frozen at its reset value passed every test before (issue 28)."""
    for c in report["cases"]:
        assert c["obs_err_max50"] <= 1e-12, c["file"]
        assert c["obs_err_orientation_max50"] <= 1e-12, c["file"]


def test_reset_observation_matches_orientation_included(data_dir):
    from tasks.env import BatchEnv
    for name in ("case06_obstacle_sample1002_sq24h12col1", "case08_climber_walker_sin40col1"):
        z = np.load(data_dir / "traces" / f"{name}.npz", allow_pickle=False)
        env = BatchEnv(str(z["task"]), [z["body"]])
        obs, ref = env.robot_obs(0), z["obs"][0]
        keep = np.ones(len(ref), bool)
        keep[2] = False  # orientation
        assert np.abs(obs[keep] - ref[keep]).max() <= 1e-9
        assert abs(obs[2] - ref[2]) <= 1e-12  # was 9e-4 before the Eigen-order sums
