"""`sgr migrate RUN [--trust-pickle]`: one command for an older sgr's files (pickles and champion
files in the older layout), the two older commands its aliases; a folder holding pickles is refused
without --trust-pickle before anything is changed."""

import json
import shutil

from evolve.cli import main
from evolve.methods.formats import controller_of
from evolve.records.compact import same_controller
from tasks.registry import OLD_TASK_FILE

OLD = "tests/data/champions/sgr-Walker-v0-paper-s0"  # a champion file as an older sgr wrote it


def _old_run(tmp_path, repo_root):
    run = tmp_path / "run"
    shutil.copytree(repo_root / OLD, run)
    return run


def test_migrate_rewrites_an_older_champion_file_as_the_same_controller(tmp_path, repo_root, capsys):
    run = _old_run(tmp_path, repo_root)
    before = (run / "champion.json").read_text()
    assert main(["migrate", str(run)]) == 0
    after = (run / "champion.json").read_text()
    assert len(after) < len(before) / 4  # the dense layers recorded as the genome's decoding
    assert json.loads(after)["controller"]["format"] == "sgr-hyperneat-controller-1"
    assert same_controller(controller_of(json.loads(before)), controller_of(json.loads(after)))
    out = capsys.readouterr().out
    assert f"{run / 'champion.json'}: {len(before.encode())} -> {len(after.encode())} bytes" in out
    assert main(["migrate", str(run)]) == 0  # again: nothing left to do
    assert (run / "champion.json").read_text() == after


def test_a_folder_with_pickles_is_refused_without_trust_and_nothing_changes(tmp_path, repo_root, capsys):
    run = _old_run(tmp_path, repo_root)
    (run / OLD_TASK_FILE).write_bytes(b"not loaded")
    before = (run / "champion.json").read_bytes()
    assert main(["migrate", str(run)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--trust-pickle only if you trust" in err
    assert (run / "champion.json").read_bytes() == before and (run / OLD_TASK_FILE).is_file()


def test_the_old_command_names_are_aliases_saying_so_in_one_line(tmp_path, repo_root, capsys):
    run = _old_run(tmp_path, repo_root)
    before = (run / "champion.json").read_text()
    assert main(["convert-checkpoints", str(run)]) == 0
    err = capsys.readouterr().err.splitlines()
    assert err == [f"sgr: note: convert-checkpoints is an alias of: sgr migrate {run}"]
    assert len((run / "champion.json").read_text()) < len(before) / 4  # it migrated
    from evolve.records.compact import main as compact_main

    assert compact_main([str(run)]) == 0
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and "alias of: sgr migrate" in err[0]


def test_a_folder_with_nothing_to_migrate_says_so(tmp_path, capsys):
    """An empty folder (or a typo'd one holding no sgr files) printed nothing and exited 0."""
    assert main(["migrate", str(tmp_path)]) == 0
    assert capsys.readouterr().out.splitlines() == [
        f"{tmp_path}: nothing to migrate (no pickled checkpoints, task.pkl or champion files)"]
