"""A disk that fills while a run writes its end files (fitness.png, champion.gif) leaves no file cut
short; the error names the file and says the generations are done; the command it advises
(`sgr evolve --resume DIR`) writes the end files whole. The full disk is a file-size limit
(RLIMIT_FSIZE, which needs no root) set while the end files are written: a write past it fails as
one past a full disk does (EFBIG instead of ENOSPC)."""

from __future__ import annotations

import resource
import signal
from pathlib import Path

import pytest
import yaml
from PIL import Image

from evolve.runs.experiment import Experiment

LIMIT = 64 << 10  # fitness.png (~35 KiB) fits, the 60-step champion.gif (~150 KiB) does not


def whole_image(path: Path) -> int:
    """Frames of an image file, every one decoded (a file cut short raises)."""
    with Image.open(path) as im:
        n = getattr(im, "n_frames", 1)
        for i in range(n):
            im.seek(i)
            im.load()
    return n


@pytest.fixture
def file_size_limit(monkeypatch):
    """While Experiment.finish runs: no file may grow past LIMIT bytes."""
    real_finish = Experiment.finish
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    old = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past it fails instead of killing us

    def limited(self):
        resource.setrlimit(resource.RLIMIT_FSIZE, (LIMIT, hard))
        try:
            real_finish(self)
        finally:
            resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))

    monkeypatch.setattr(Experiment, "finish", limited)
    yield
    monkeypatch.setattr(Experiment, "finish", real_finish)
    signal.signal(signal.SIGXFSZ, old)


def test_a_full_disk_at_the_run_end_cuts_no_gif_and_resume_writes_the_end_files(tmp_path, file_size_limit,
                                                                                  monkeypatch, capsys):
    from evolve.cli import main

    config = tmp_path / "tiny.yaml"
    config.write_text(yaml.safe_dump({"method": "sgr", "task": "Walker-v0", "generations": 2, "pop_size": 8,
                                      "episode_steps": 60, "workers": 1, "robust": None,
                                      "final_selection": None}))
    run = tmp_path / "run"
    assert main(["evolve", "--config", str(config), "--out", str(run), "--quiet"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert f"cannot write {run / 'champion.gif'}" in err[0] and "generations are done" in err[0], err
    assert "generation 3" not in err[0] and f"sgr evolve --resume {run}" in err[0], err
    assert not (run / "champion.gif").exists()  # not a GIF cut short
    assert not [f.name for f in run.iterdir() if f.name.startswith(".champion.gif")]  # no temporary file
    whole_image(run / "fitness.png")

    monkeypatch.undo()  # room again
    assert main(["evolve", "--resume", str(run), "--quiet"]) == 0
    assert whole_image(run / "champion.gif") == 61  # the reset state and 60 steps
    assert main(["evolve", "--resume", str(run), "--quiet"]) == 2  # and now the run is done
    assert "is finished (2 of 2 generations)" in capsys.readouterr().err


def test_a_kill_after_the_last_checkpoint_before_the_end_files_leaves_a_run_that_resume_finishes(tmp_path,
                                                                                               capsys):
    """A process killed just after its last generation's row, champion and checkpoint, before its
    end files began (simulated: a reporter that runs after the checkpoint raises SystemExit, which
    passes every handler as a kill would): `sgr evolve --resume` writes fitness.png and champion.gif,
    and only then calls the run finished. (Before: the marker was written when the end files began,
    so the run looked finished, without its plot and GIF.)"""
    from evolve.cli import main

    class Killed:
        def generation(self, exp, row):
            if exp.search.generation == exp.cfg.generations:
                raise SystemExit("killed")

    cfg = {"method": "sgr", "task": "Walker-v0", "generations": 2, "pop_size": 8, "episode_steps": 20,
           "workers": 1, "render_champion": True, "robust": None, "final_selection": None}
    run = tmp_path / "run"
    with pytest.raises(SystemExit), Experiment.from_config(cfg, run, quiet=True) as exp:
        exp.add_reporter(Killed())
        exp.run_all()
    from evolve.records.rundir import RunDir
    assert RunDir(run).last_checkpoint_generation() == 2 and len(RunDir(run).rows()) == 2
    assert not (run / "fitness.png").exists() and not (run / "champion.gif").exists()
    assert main(["evolve", "--resume", str(run), "--quiet"]) == 0, capsys.readouterr().err
    whole_image(run / "fitness.png")
    assert whole_image(run / "champion.gif") == 21  # the reset state and 20 steps
    assert len(RunDir(run).rows()) == 2  # nothing ran again
    assert main(["evolve", "--resume", str(run), "--quiet"]) == 2
    assert "is finished (2 of 2 generations)" in capsys.readouterr().err


def test_a_run_ended_without_finish_is_finished_as_before(tmp_path):
    """run_all without finish (a script that wants no plot), then the with block's end: the run is
    finished (no end files marked due), as it was before the mark moved."""
    from evolve.records.rundir import RunDir
    from tsim.errors import SgrError

    cfg = {"method": "sgr", "task": "Walker-v0", "generations": 1, "pop_size": 8, "episode_steps": 20,
           "workers": 1, "render_champion": False, "robust": None, "final_selection": None}
    with Experiment.from_config(cfg, tmp_path / "run", quiet=True) as exp:
        exp.run_all()
    assert not RunDir(tmp_path / "run").end_files_pending()
    with pytest.raises(SgrError, match="is finished"):
        Experiment.resume(tmp_path / "run")
