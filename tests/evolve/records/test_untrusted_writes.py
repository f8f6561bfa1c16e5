"""A folder's links never make sgr write elsewhere (docs/RELIABILITY.md, "A folder is data from a
stranger"): a run folder received with a file or folder inside it linked to a file or folder outside
(the user's shell start-up file, a folder of results) is refused in one line that names the link by
every command that would write into the run (`sgr evolve --resume`, `select-champion`), and a
report's gallery/ or archives/ planted as a link is refused by `sgr report`; the files outside stay
byte for byte, nothing in the folder is deleted, and no command hangs.

On the code before these checks, a linked `.lock` was truncated to the process id, a linked
generations.csv got a row appended, a linked checkpoints/ received the new checkpoints and a linked
gallery/ the report's pictures."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

from evolve.records.rundir import RunDir
from tests.evolve.attack import Attack, tree
from tests.evolve.conftest import tiny_run
from tsim.errors import SgrError
from tsim.files import atomic_write, make_folder, open_no_follow, refuse_links

pytestmark = [pytest.mark.slow]


@pytest.fixture(scope="module")
def finished(tmp_path_factory) -> Path:
    """A finished tiny SGR run (2 generations), to be copied by each test."""
    return tiny_run("sgr", tmp_path_factory.mktemp("untrusted-writes") / "run")


def received(finished: Path, attack: Attack) -> Path:
    """The run as received from a stranger: a copy in the attack's folder."""
    run = attack.tmp / "received"
    shutil.copytree(finished, run)
    return run


# a file of the run replaced by a link to the user's shell start-up file: a resume writes each
RUN_FILES = [".lock", "generations.csv", "champion.json", "config.yaml", "neat.ini", "segments.json"]


@pytest.mark.parametrize("name", RUN_FILES)
def test_a_run_file_linked_outside_is_refused_by_resume_and_the_target_is_unchanged(finished, tmp_path,
                                                                                    capsys, name):
    attack = Attack(tmp_path)
    run = received(finished, attack)
    target = attack.decoy / ".bashrc"
    (run / name).unlink(missing_ok=True)
    (run / name).symlink_to(target)
    with attack.watching(run):
        r = attack.main("evolve", "--resume", str(run), "--generations", "3", capsys=capsys)
    line = r.error_line()
    assert str(run / name) in line and "symbolic link" in line
    assert name == "generations.csv" or len(RunDir(run).rows()) == 2  # no generation was added


def test_a_linked_checkpoints_folder_is_refused_and_receives_no_checkpoint(finished, tmp_path, capsys):
    """checkpoints/ linked to a folder outside holding the run's real checkpoints: the resume would
    load them and then write its new ones there; it is refused before any generation."""
    attack = Attack(tmp_path)
    run = received(finished, attack)
    elsewhere = attack.decoy / "data" / "ckpts"
    shutil.move(run / "checkpoints", elsewhere)
    attack._decoy_before = tree(attack.decoy)  # the moved checkpoints are the decoy's now
    (run / "checkpoints").symlink_to(elsewhere, target_is_directory=True)
    with attack.watching(run):
        r = attack.main("evolve", "--resume", str(run), "--generations", "3", capsys=capsys)
    assert str(run / "checkpoints") in r.error_line()


def test_a_link_planted_inside_checkpoints_is_refused(finished, tmp_path, capsys):
    attack = Attack(tmp_path)
    run = received(finished, attack)
    (run / "checkpoints" / "gen-00099.json.gz").symlink_to(attack.decoy / "thesis.tex")
    with attack.watching(run):
        r = attack.main("evolve", "--resume", str(run), "--generations", "3", capsys=capsys)
    assert "gen-00099.json.gz" in r.error_line()


@pytest.mark.parametrize("folder", ["gallery", "archives"])
def test_a_report_folder_planted_as_a_link_is_refused_and_receives_nothing(finished, tmp_path, capsys,
                                                                           folder):
    """`sgr report RUN` writes its pictures into RUN/gallery/ (and a map-elites run's into
    RUN/archives/): planted as a link to a folder outside, each is refused in one line."""
    attack = Attack(tmp_path)
    run = received(finished, attack)
    (run / folder).symlink_to(attack.decoy / "data", target_is_directory=True)
    if folder == "archives":  # written only for a map-elites run: the folder check is the same
        with attack.watching(run), pytest.raises(SgrError, match="symbolic link"):
            make_folder(run / folder, run)
        return
    with attack.watching(run):
        r = attack.main("report", str(run), "--no-robustness", capsys=capsys)
    assert f"{run / folder}" in r.error_line()


def test_a_report_picture_planted_as_a_link_is_refused(finished, tmp_path, capsys):
    attack = Attack(tmp_path)
    run = received(finished, attack)
    (run / "gallery").mkdir()
    (run / "gallery" / "received-body.png").symlink_to(attack.decoy / "thesis.tex")
    with attack.watching(run):
        r = attack.main("report", str(run), "--no-robustness", capsys=capsys)
    assert "received-body.png" in r.error_line()


def test_an_honest_run_reached_through_a_link_the_user_made_resumes(finished, tmp_path, capsys):
    """The run folder itself may be a link (the user named it): only links inside it are refused."""
    attack = Attack(tmp_path)
    run = received(finished, attack)
    named = tmp_path / "my-run"
    named.symlink_to(run, target_is_directory=True)
    r = attack.main("evolve", "--resume", str(named), "--generations", "3", "--quiet", capsys=capsys)
    assert r.code == 0, r.err
    assert len(RunDir(run).rows()) == 3
    attack.check()


def test_the_write_guards_refuse_each_link_on_the_way_and_nothing_else(tmp_path):
    """refuse_links checks every part below the named folder and the file itself; the named folder
    may be a link; atomic_write with `inside` and open_no_follow refuse a link and write nothing."""
    real = tmp_path / "real"
    (real / "sub").mkdir(parents=True)
    named = tmp_path / "named"
    named.symlink_to(real, target_is_directory=True)
    assert refuse_links(named / "sub" / "f", named) == named / "sub" / "f"
    (real / "linked").symlink_to(real / "sub", target_is_directory=True)
    with pytest.raises(SgrError, match="linked: a symbolic link"):
        refuse_links(named / "linked" / "f", named)
    target = tmp_path / "target.txt"
    target.write_text("mine")
    (real / "sub" / "f").symlink_to(target)
    with pytest.raises(SgrError, match="symbolic link"):
        atomic_write(named / "sub" / "f", b"theirs", inside=named)
    with pytest.raises(SgrError, match="symbolic link"):
        open_no_follow(named / "sub" / "f", os.O_WRONLY | os.O_APPEND)
    assert target.read_text() == "mine"
    atomic_write(named / "sub" / "g", b"ok", inside=named)
    assert (real / "sub" / "g").read_bytes() == b"ok"
