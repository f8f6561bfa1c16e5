"""A run's resources and files: checkpoints are found by one name pattern (generations past 99,999
included, an older sgr's pickles never), and an Experiment used in a `with` block lets go of its
run directory however the block ends."""

import pytest

from evolve.records.rundir import RunDir, checkpoint_generation
from evolve.runs.experiment import Experiment


def test_checkpoint_names_are_parsed_by_one_pattern():
    assert checkpoint_generation("gen-00042.json.gz") == 42
    assert checkpoint_generation("gen-123456.json.gz") == 123456  # six digits: generation 123,456
    for other in ("gen-00042.pkl", "gen-0042.json.gz", "gen-00042.json.gz.tmp", "notes-00042.json.gz",
                  ".gen-00042.json.gz"):
        assert checkpoint_generation(other) is None, other


def test_the_newest_checkpoint_is_the_highest_generation_and_pickles_do_not_count(tmp_path):
    run = RunDir(tmp_path / "r")
    assert run.last_checkpoint_generation() is None
    run.ckpt_dir.mkdir(parents=True)
    (run.ckpt_dir / "gen-99999.pkl").write_bytes(b"\x80")  # an older sgr's, never a checkpoint of ours
    assert run.last_checkpoint_generation() is None
    for g in (99998, 100001):
        (run.ckpt_dir / f"gen-{g:05d}.json.gz").write_bytes(b"")
    assert run.last_checkpoint_generation() == 100001  # f.name[4:9] would have read 10000
    assert [f.name for f in run.checkpoints()] == ["gen-100001.json.gz", "gen-99998.json.gz"]


def tiny(repo_root) -> dict:
    return {"method": "sgr", "task": "Walker-v0", "generations": 1, "pop_size": 4, "episode_steps": 2,
            "render_champion": False, "workers": 1, "neat_config": str(repo_root / "configs/neat/sgr.ini"),
            "robust": None, "final_selection": None}


def test_an_experiment_in_a_with_block_lets_go_of_its_run_however_the_block_ends(tmp_path, repo_root):
    with pytest.raises(RuntimeError, match="in the block"):
        with Experiment.from_config(tiny(repo_root), tmp_path / "a", quiet=True):
            with pytest.raises(ValueError, match="being run by another process"):
                RunDir(tmp_path / "a").lock()  # held while inside
            raise RuntimeError("in the block")
    RunDir(tmp_path / "a").lock()  # let go of
    with Experiment.from_config(tiny(repo_root), tmp_path / "b", quiet=True) as exp:
        exp.run_all()
    RunDir(tmp_path / "b").lock()


def test_a_run_that_cannot_be_resumed_lets_go_of_its_directory(tmp_path, repo_root):
    with Experiment.from_config(tiny(repo_root), tmp_path / "r", quiet=True) as exp:
        exp.run_all()
    with pytest.raises(ValueError, match="is finished"):
        Experiment.resume(tmp_path / "r")
    RunDir(tmp_path / "r").lock()


def test_a_closed_experiment_runs_nothing_more(tmp_path, repo_root):
    """close() let go of the run, yet run_all() went on: another process resumed it meanwhile, and
    generations.csv held each generation twice."""
    from tsim.errors import SgrError

    exp = Experiment.from_config(tiny(repo_root), tmp_path / "r", quiet=True)
    exp.close()
    other = Experiment.resume(tmp_path / "r")
    with pytest.raises(SgrError, match=r"is closed .* continue the run with Experiment.resume"):
        exp.run_all()
    other.run_all()
    other.close()
    rows = RunDir(tmp_path / "r").check_rows()  # each generation once, in order
    assert [int(r["generation"]) for r in rows] == list(range(1, other.cfg.generations + 1))


def test_finish_after_a_with_block_writes_the_end_files(tmp_path, repo_root):
    """A with block closes the Experiment; finish() after it only writes files, and does."""
    with Experiment.from_config(tiny(repo_root), tmp_path / "r", quiet=True) as exp:
        exp.run_all()
    exp.finish()
    assert (tmp_path / "r" / "fitness.png").stat().st_size > 0


@pytest.mark.parametrize("generations", [2.5, True, "5", 0])
def test_resume_with_generations_that_are_not_a_positive_integer_changes_nothing(tmp_path, repo_root,
                                                                                   generations):
    """2.5 ran 3 generations and wrote 2.5 into config.yaml; True was written before the error."""
    from tsim.errors import SgrError

    with Experiment.from_config(tiny(repo_root), tmp_path / "r", quiet=True) as exp:
        exp.run_all()
    before = (tmp_path / "r" / "config.yaml").read_bytes()
    with pytest.raises(SgrError, match="generations must be a positive integer"):
        Experiment.resume(tmp_path / "r", generations=generations)
    assert (tmp_path / "r" / "config.yaml").read_bytes() == before
    RunDir(tmp_path / "r").lock()  # let go of
