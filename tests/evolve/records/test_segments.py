"""A run records where each part of its life ran (issue 45, item 4): segments.json gains one entry
per start and resume (arch, device, precision, workers), config.yaml no longer claims an arch, and
an older run's recorded arch moves into the file on its first resume."""

import json

import yaml

from evolve.records.segments import SEGMENTS_FILE, backend_summary, segments
from evolve.runs.experiment import Experiment
from tsim.backend import runtime

TINY = {"method": "sgr", "task": "Walker-v0", "generations": 1, "pop_size": 6, "episode_steps": 5,
        "workers": 1, "render_champion": False, "checkpoint_every": 1}


def run_then_resume(out, generations: int = 2) -> None:
    with Experiment.from_config(TINY, out, quiet=True) as exp:
        exp.run_all()
    with Experiment.resume(out, quiet=True, generations=generations) as exp:
        exp.run_all()


def test_a_start_and_a_resume_are_two_segments_and_config_yaml_claims_no_arch(tmp_path):
    out = tmp_path / "r"
    run_then_resume(out)
    found = json.loads((out / SEGMENTS_FILE).read_text())
    assert [s["after_generation"] for s in found] == [0, 1]
    name, software = runtime.device()
    for s in found:
        assert (s["arch"], s["device"], s["software"]) == ("cpu", name, False)
        assert s["precision"] == runtime.precision() and s["workers"] == 1 and s["started"].endswith("Z")
    assert "arch" not in yaml.safe_load((out / "config.yaml").read_text())
    assert segments(out) == found
    assert backend_summary(out) == f"cpu, {runtime.precision()}"


def test_an_older_run_made_for_cuda_and_resumed_here_says_both(tmp_path):
    """An older sgr wrote the creating arch into config.yaml and kept no segments: the first resume
    (here, on the CPU) moves it into segments.json, so that nothing claims the run ran on CUDA
    throughout."""
    out = tmp_path / "r"
    with Experiment.from_config(TINY, out, quiet=True) as exp:
        exp.run_all()
    (out / SEGMENTS_FILE).unlink()
    cfg = yaml.safe_load((out / "config.yaml").read_text())
    (out / "config.yaml").write_text(yaml.safe_dump({**cfg, "arch": "cuda"}, sort_keys=False))
    assert [s["arch"] for s in segments(out)] == ["cuda"]  # read from config.yaml meanwhile
    with Experiment.resume(out, quiet=True, generations=3) as exp:
        exp.run_all()
    found = segments(out)
    assert [(s["after_generation"], s["arch"]) for s in found] == [(0, "cuda"), (1, "cpu")]
    assert found[0]["device"] is None  # not recorded then
    assert "arch" not in yaml.safe_load((out / "config.yaml").read_text())
    assert backend_summary(out) == f"cuda, then cpu from generation 2, {runtime.precision()}"


def test_a_folder_without_a_record_has_no_segments(tmp_path):
    assert segments(tmp_path) == [] and backend_summary(tmp_path) == ""
