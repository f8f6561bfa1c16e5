"""A sweep folder is data from a stranger (docs/RELIABILITY.md, "Trust"): `sgr sweep` resumes only
the runs it made (its record, sweep-runs.json, with each run's config.yaml sha256), passes
--trust-imports to a run only for its own imports, follows no link in the folder, deletes nothing it
did not make, and runs a folder only while no other sweep does. Each attack below is refused in one
line before any run starts: no planted code ran, no file outside the folder changed, nothing was
deleted (tests/evolve/attack.py)."""

from __future__ import annotations

import fcntl
import hashlib
import json
import os
import shutil
from collections.abc import Callable
from pathlib import Path

import pytest
import yaml

from evolve.records.rundir import RunDir
from evolve.sweeps.sweep import Sweep
from tests.evolve.attack import Attack

# sweeps start their runs as processes (the attacks below are refused before any would start)
pytestmark = [pytest.mark.slow, pytest.mark.subprocess]

RUN = "sgr-Walker-v0-s0"
RECORD_FILE = "sweep-runs.json"  # evolve.sweeps.sweep.RECORD_FILE: the runs a sweep made
SWEEP = {"methods": ["sgr"], "tasks": ["Walker-v0"], "seeds": [0], "imports": ["own_tasks.py"],
         "overrides": {"generations": 2, "pop_size": 8, "episode_steps": 20, "workers": 1,
                       "render_champion": False, "robust": None, "final_selection": None}}


@pytest.fixture(scope="module")
def made(tmp_path_factory) -> Path:
    """A sweep folder made by `Sweep.create` from a sweep file naming imports (a harmless module of
    the user's), with its one run made (config, checkpoint 0) and recorded; not run."""
    base = tmp_path_factory.mktemp("made")
    (base / "own_tasks.py").write_text("OWN = 1  # the user's own module: registers nothing\n")
    (base / "sweep.yaml").write_text(yaml.safe_dump(SWEEP))
    sweep = Sweep.create(base / "sweep.yaml", base / "sw")
    sweep.prepare(sweep.runs[0])
    return base / "sw"


def copy_of(made: Path, tmp_path: Path) -> Path:
    """A copy of the made sweep folder (links kept as links), for one attack."""
    sw = tmp_path / "sw"
    shutil.copytree(made, sw, symlinks=True)
    return sw


def record(sw: Path) -> dict:
    return json.loads((sw / RECORD_FILE).read_text())


def write_record(sw: Path, runs: dict) -> None:
    (sw / RECORD_FILE).write_text(json.dumps({"runs": runs}))


def plant_imports(attack: Attack, run: Path) -> None:
    """The run's config.yaml names a task of the attacker's and a module that registers it (the
    module leaves the marker when imported)."""
    evil = attack.tmp / "evil.py"
    evil.write_text(attack.code())
    raw = yaml.safe_load((run / "config.yaml").read_text())
    (run / "config.yaml").write_text(yaml.safe_dump({**raw, "task": "Planted-v0", "imports": [str(evil)]}))


def _planted_found_run(attack: Attack, sw: Path) -> None:  # a tarball's folder: no record at all
    plant_imports(attack, sw / "runs" / RUN)
    (sw / RECORD_FILE).unlink(missing_ok=True)


def _planted_changed_config(attack: Attack, sw: Path) -> None:  # a run the sweep made, changed since
    plant_imports(attack, sw / "runs" / RUN)


def _planted_forged_record(attack: Attack, sw: Path) -> None:  # ... and the record changed to match
    plant_imports(attack, sw / "runs" / RUN)
    write_record(sw, {RUN: hashlib.sha256((sw / "runs" / RUN / "config.yaml").read_bytes()).hexdigest()})


@pytest.mark.parametrize("plant, message", [
    (_planted_found_run, f"runs/{RUN}: {{sw}} was made by an older sgr, which kept no record of the "
                         f"runs it made ({RECORD_FILE}); if its runs are yours, record them with: "
                         "sgr migrate {sw}"),
    (_planted_changed_config, f"runs/{RUN}/config.yaml is not the config this sweep made for the run"),
    (_planted_forged_record, f"runs/{RUN}/config.yaml names other imports than {{sw}}/sweep.yaml"),
], ids=["found-run", "changed-config", "forged-record"])
def test_a_resumed_sweep_trusted_with_its_imports_runs_no_import_a_run_folder_names(
        tmp_path, capsys, made, plant: Callable, message: str):
    """`sgr sweep --resume DIR --trust-imports` trusts the imports sweep.yaml names, never those of a
    run folder it finds or that changed since the sweep made it: one line, no run started, no
    planted code run."""
    attack = Attack(tmp_path)
    sw = copy_of(made, tmp_path)
    plant(attack, sw)
    with attack.watching(sw):
        r = attack.main("sweep", "--resume", str(sw), "--trust-imports", "--quiet", capsys=capsys, timeout=60)
    line = r.error_line()
    assert message.format(sw=sw) in line, line
    assert not (sw / "runs" / RUN / "log.txt").exists()  # no run process was started


def test_a_new_sweep_trusted_with_its_own_imports_refuses_a_run_folder_planted_under_out(
        tmp_path, capsys, made):
    """`sgr sweep --config FILE --out DIR` trusts FILE's imports; a run folder already under DIR/runs
    (its config naming planted code) is none of the new sweep's: one line, nothing written to it."""
    attack = Attack(tmp_path)
    out = tmp_path / "out"
    shutil.copytree(made / "runs", out / "runs", symlinks=True)
    plant_imports(attack, out / "runs" / RUN)
    with attack.watching(out):
        r = attack.main("sweep", "--config", str(made.parent / "sweep.yaml"), "--out", str(out), "--quiet",
                        capsys=capsys, timeout=60)
    line = r.error_line()
    assert f"{out}/runs/{RUN} is not a run this sweep made" in line, line
    assert not (out / "sweep.yaml").exists() and not (out / "runs" / RUN / "log.txt").exists()


def _link_log(attack: Attack, sw: Path) -> Path:
    (sw / "runs" / RUN / "log.txt").symlink_to(attack.decoy / ".bashrc")
    return sw / "runs" / RUN / "log.txt"


def _link_runs(attack: Attack, sw: Path) -> Path:
    shutil.rmtree(sw / "runs")
    (sw / "runs").symlink_to(attack.decoy / "data", target_is_directory=True)
    return sw / "runs"


def _link_run(attack: Attack, sw: Path) -> Path:
    shutil.rmtree(sw / "runs" / RUN)
    (sw / "runs" / RUN).symlink_to(attack.decoy / "data", target_is_directory=True)
    return sw / "runs" / RUN


def _link_lock(attack: Attack, sw: Path) -> Path:
    (sw / ".lock").unlink(missing_ok=True)
    (sw / ".lock").symlink_to(attack.decoy / ".bashrc")
    return sw / ".lock"


@pytest.mark.parametrize("plant", [_link_log, _link_runs, _link_run, _link_lock],
                         ids=["log.txt", "runs", "run-folder", "sweep-lock"])
def test_a_resumed_sweep_writes_through_no_link_in_its_folder(tmp_path, capsys, made, plant: Callable):
    """A linked log.txt (-> the user's .bashrc), runs/ or run folder (-> a folder outside) or the
    sweep's .lock: `sgr sweep --resume` names the link in one line and follows none of them."""
    attack = Attack(tmp_path)
    sw = copy_of(made, tmp_path)
    link = plant(attack, sw)
    with attack.watching(sw):
        r = attack.main("sweep", "--resume", str(sw), "--quiet", capsys=capsys, timeout=60)
    assert f"{link} is a link; sgr does not follow links in a sweep folder" in r.error_line()


def test_a_fifo_as_a_runs_log_txt_is_refused_not_opened(tmp_path, capsys, made):
    """A FIFO planted as a run's log.txt would block the sweep opening it for ever: one line names
    it, before any run starts."""
    attack = Attack(tmp_path)
    sw = copy_of(made, tmp_path)
    os.mkfifo(sw / "runs" / RUN / "log.txt")
    with attack.watching(sw):
        r = attack.main("sweep", "--resume", str(sw), "--quiet", capsys=capsys, timeout=20)
    assert f"{sw}/runs/{RUN}/log.txt is not a regular file" in r.error_line()


def test_a_new_sweep_refuses_a_linked_runs_folder_under_out(tmp_path, capsys, made):
    """`--out DIR` where DIR/runs links to a folder outside: one line; nothing is made there."""
    attack = Attack(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    (out / "runs").symlink_to(attack.decoy / "data", target_is_directory=True)
    with attack.watching(out):
        r = attack.main("sweep", "--config", str(made.parent / "sweep.yaml"), "--out", str(out), "--quiet",
                        capsys=capsys, timeout=60)
    assert f"{out}/runs is a link; sgr does not follow links in a sweep folder" in r.error_line()


def _no_config(sw: Path) -> None:
    (sw / "runs" / RUN / "config.yaml").unlink()


def _no_checkpoint(sw: Path) -> None:
    for f in (sw / "runs" / RUN / "checkpoints").iterdir():
        f.unlink()


def _not_recorded(sw: Path) -> None:  # a folder of the user's where the run would go
    shutil.rmtree(sw / "runs" / RUN)
    (sw / "runs" / RUN).mkdir()
    write_record(sw, {})


def _half_made_and_more(sw: Path) -> None:  # recorded as being made, holding a file making does not write
    _no_checkpoint(sw)
    write_record(sw, {RUN: None})


@pytest.mark.parametrize("damage, message", [
    (_no_config, f"runs/{RUN} has no config.yaml; sgr neither resumes nor removes it"),
    (_no_checkpoint, f"runs/{RUN} has no checkpoint; sgr neither resumes nor removes it"),
    (_not_recorded, f"runs/{RUN} is not a run this sweep made"),
    (_half_made_and_more, f"runs/{RUN} was being made by this sweep, but holds notes.txt, which making a "
                          "run does not write; sgr neither resumes nor removes it"),
], ids=["no-config", "no-checkpoint", "not-recorded", "half-made-with-a-users-file"])
def test_a_run_folder_a_resumed_sweep_cannot_resume_is_reported_and_not_deleted(
        tmp_path, capsys, made, damage: Callable, message: str):
    """A run folder without config.yaml or checkpoint, one the record does not name, or a half-made
    one holding a file of the user's: `sgr sweep --resume` names it in one line and stops before any
    run starts; the folder and the user's file stay."""
    attack = Attack(tmp_path)
    sw = copy_of(made, tmp_path)
    damage(sw)
    (sw / "runs" / RUN / "notes.txt").write_text("the user's notes\n")
    with attack.watching(sw):
        r = attack.main("sweep", "--resume", str(sw), "--quiet", capsys=capsys, timeout=60)
    assert message in r.error_line()
    assert (sw / "runs" / RUN / "notes.txt").read_text() == "the user's notes\n"


def test_the_sweeps_own_half_made_run_is_made_anew_by_removing_only_what_making_it_wrote(tmp_path, made):
    """A run the record says was being made (the sweep was killed before checkpoint 0), its folder
    holding only what making a run writes (a temporary file of atomic_write among them): the sweep
    makes it anew, and records its config.yaml's sha256."""
    sw = copy_of(made, tmp_path)
    run = sw / "runs" / RUN
    _no_checkpoint(sw)
    (run / ".config.yaml.k2j4h1x0").write_text("cut short")
    write_record(sw, {RUN: None})
    sweep = Sweep.open(sw)
    sweep.prepare(sweep.runs[0])
    assert RunDir(run).has_checkpoint() and not (run / ".config.yaml.k2j4h1x0").exists()
    assert record(sw)["runs"] == {RUN: hashlib.sha256((run / "config.yaml").read_bytes()).hexdigest()}


def test_a_second_sweep_on_a_folder_another_sweep_runs_is_one_line_and_changes_nothing(
        tmp_path, capsys, made):
    """While one sweep holds DIR/.lock, `sgr sweep --resume DIR` says who holds it and stops: it
    neither runs nor makes nor removes any run (here a half-made one the other sweep is making)."""
    attack = Attack(tmp_path)
    sw = copy_of(made, tmp_path)
    _no_checkpoint(sw)
    write_record(sw, {RUN: None})
    fd = os.open(sw / ".lock", os.O_RDWR | os.O_CREAT)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        os.write(fd, b"4242")
        with attack.watching(sw):
            r = attack.main("sweep", "--resume", str(sw), "--quiet", capsys=capsys, timeout=60)
    finally:
        os.close(fd)
    assert r.error_line() == f"sgr: error: {sw} is being run by another sweep (pid 4242)"
    assert not (sw / "runs" / RUN / "checkpoints" / "gen-00000.json.gz").exists()  # not made meanwhile


def test_an_honest_sweep_resumed_with_trust_imports_trusts_its_runs_with_its_imports_alone(tmp_path, made):
    """The control: the sweep's own run, unchanged, is kept for resuming, and its process gets
    --trust-imports only when the sweep is resumed with it (its config names the sweep's imports)."""
    from evolve.sweeps.sweep import trust_flag
    from tasks.registry import trust_imports

    sw = copy_of(made, tmp_path)
    trust_imports()
    try:
        trusted = Sweep.open(sw)
    finally:
        trust_imports(False)
    before = (sw / "runs" / RUN / "config.yaml").read_bytes()
    trusted.prepare(trusted.runs[0])  # resumable: kept as it is
    assert (sw / "runs" / RUN / "config.yaml").read_bytes() == before
    assert trust_flag(trusted) == ["--trust-imports"] and trust_flag(Sweep.open(sw)) == []


def test_an_older_sgrs_sweep_is_refused_until_its_owner_records_its_runs_with_migrate(made, tmp_path, capsys):
    """A sweep folder of an older sgr has no record: `sgr sweep --resume` names the one command
    that records its runs (`sgr migrate DIR`, the folder named by its owner in that command), and
    resumes them once it has."""
    from evolve.cli import main

    sw = copy_of(made, tmp_path)
    (sw / RECORD_FILE).unlink()
    attack = Attack(tmp_path)
    with attack.watching(sw):
        r = attack.main("sweep", "--resume", str(sw), capsys=capsys)
    line = r.error_line()
    assert "made by an older sgr" in line and f"sgr migrate {sw}" in line, line
    assert main(["migrate", str(sw)]) == 0
    assert f"{sw}: recorded its 1 run in {RECORD_FILE}" in capsys.readouterr().out
    digest = hashlib.sha256((sw / "runs" / RUN / "config.yaml").read_bytes()).hexdigest()
    assert record(sw) == {"runs": {RUN: digest}}
    sweep = Sweep.open(sw)  # checks every run: this one resumes
    assert sweep.made == {RUN: digest}
    assert main(["migrate", str(sw)]) == 0  # once recorded, the record is kept as it is
    assert record(sw) == {"runs": {RUN: digest}}
