"""A run that starts from another run's population at a new size (`start_from`, `sgr evolve
--from`): it evolves the very genomes of the other run's checkpoint, unscored, at its own
robot_shape, counts generations on from there, and its config records where it came from."""

import json

import pytest
import yaml

from evolve.cli import main
from evolve.records.rundir import read_checkpoint_file
from evolve.runs.experiment import Experiment

TINY = {"method": "sgr", "task": "Walker-v0", "generations": 2, "pop_size": 8, "seed": 3,
        "episode_steps": 20, "workers": 1, "render_champion": False, "robust": None, "final_selection": None}


@pytest.fixture(scope="module")
def source(tmp_path_factory):
    d = tmp_path_factory.mktemp("continuation") / "src"
    with Experiment.from_config(TINY, d, quiet=True) as exp:
        exp.run_all()
    return d


def test_the_continuation_records_its_origin_and_evolves_that_population_at_the_new_size(source, tmp_path):
    out = tmp_path / "cont"
    assert main(["evolve", "--from", str(source), "--shape", "8x8", "--generations", "4",
                 "--out", str(out), "--quiet"]) == 0
    raw = yaml.safe_load((out / "config.yaml").read_text())
    assert raw["start_from"] == {"run": str(source.resolve()), "generation": 2}
    assert raw["robot_shape"] == [8, 8] and raw["generations"] == 4
    rows = (out / "generations.csv").read_text().splitlines()[1:]
    assert [r.split(",")[0] for r in rows] == ["3", "4"]  # counted on from the source's generation 2
    assert len(json.loads((out / "champion.json").read_text())["body"]) == 8
    # its first population is the source's checkpoint after generation 2: the same genomes, unscored
    old = read_checkpoint_file(source / "checkpoints" / "gen-00002.json.gz")["search"]
    new = read_checkpoint_file(out / "checkpoints" / "gen-00002.json.gz")["search"]
    assert new["population"] == old["population"] and new["random"] == old["random"]
    for column in ("key", "node_key", "node_float", "conn_int", "conn_weight", "conn_enabled"):
        assert new["genomes"][column] == old["genomes"][column], column
    assert any(f is not None for f in old["genomes"]["fitness"])
    assert all(f is None for f in new["genomes"]["fitness"]) and new["best"] is None


def test_a_continued_run_resumes_like_any_run(source, tmp_path):
    out = tmp_path / "cont"
    cfg = {**TINY, "generations": 3, "robot_shape": [6, 6], "start_from": {"run": str(source)}}
    with Experiment.from_config(cfg, out, quiet=True) as exp:
        exp.run_all()
    assert main(["evolve", "--resume", str(out), "--generations", "4", "--quiet"]) == 0
    rows = (out / "generations.csv").read_text().splitlines()[1:]
    assert [r.split(",")[0] for r in rows] == ["3", "4"]


@pytest.mark.parametrize("changes, message", [
    ({"method": "direct"}, "only sgr runs start from another run's population"),
    ({"generations": 2}, "key 'generations' counts from the start of"),
    ({"start_from": {"run": "nowhere"}}, "is not a run folder"),
    ({"start_from": {"generation": 1}}, "must be {run: PATH, generation: G}"),
])
def test_a_bad_start_from_is_one_line(source, tmp_path, capsys, changes, message):
    cfg = {**TINY, "generations": 4, "start_from": {"run": str(source)}, **changes}
    (tmp_path / "c.yaml").write_text(yaml.safe_dump(cfg))
    assert main(["evolve", "--config", str(tmp_path / "c.yaml"), "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err, err
    assert not (tmp_path / "r").exists()
