"""A run killed with SIGKILL and resumed in a new process is exactly the run it would have been.

The resumed process rebuilds everything from the run directory alone, so any run state that only
lives in memory (neat-python keeps node keys on its genome config, species and genome keys in
counters, innovation numbers in a tracker) shows up here as a crash or as different numbers.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from evolve.records.rundir import COLUMNS, RunDir
from evolve.runs.checkpoint import load_checkpoint
from evolve.runs.experiment import Experiment

FITNESS_COLUMNS = ["generation", "best", "mean", "median", "n_species", "n_valid", "n_invalid", "episodes"]
GENERATIONS = 12
KILL_AT_ROWS = 8  # killed while evaluating generation 8; the newest checkpoint is generation 6

# populations large enough for node additions after the resume point (asserted below)
METHODS = {
    "sgr": {"neat_config": "configs/neat/sgr.ini", "pop_size": 64},
    "direct": {"neat_config": "configs/neat/direct.ini", "pop_size": 64},
    "nested": {"neat_config": "configs/neat/nested-body.ini", "pop_size": 10, "inner_pop_size": 10,
               "inner_generations": 1, "controller_neat_config": "configs/neat/nested-controller.ini",
               "inner_keep_generations": 2},  # inner populations are forgotten before and after the resume
}


def write_config(tmp_path: Path, repo_root: Path, method: str, **changes) -> Path:
    raw = {"method": method, "task": "Walker-v0", "generations": GENERATIONS, "seed": 3,
           "episode_steps": 12, "checkpoint_every": 3, "render_champion": False, "workers": 1,
           "robust": None, "final_selection": None, **METHODS[method], **changes}
    for key in ("neat_config", "controller_neat_config"):
        if key in raw:
            raw[key] = str(repo_root / raw[key])
    p = tmp_path / f"{method}.yaml"
    p.write_text(yaml.safe_dump(raw))
    return p


def sgr(*args: str, **kw) -> subprocess.Popen:
    env = {**os.environ, "PYTHONHASHSEED": "random"}  # a new process in every respect
    return subprocess.Popen([sys.executable, "-m", "evolve.cli", *args], env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, **kw)


def kill_when(proc: subprocess.Popen, run: RunDir, rows: int) -> None:
    """SIGKILL the run's process (by its PID) once generations.csv holds `rows` rows."""
    deadline = time.monotonic() + 120
    while len(run.rows()) < rows:
        assert proc.poll() is None, f"the run ended before it could be killed: {proc.stderr.read()}"
        assert time.monotonic() < deadline
        time.sleep(0.002)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()


def fitness_rows(run: RunDir) -> list[list[str]]:
    return [[r[c] for c in FITNESS_COLUMNS] for r in run.rows()]


def genomes_and_species(state: dict) -> dict:
    """Every genome's genes (node keys, connections with weights) and every species' members, of a
    checkpoint's population(s): two runs that are the same run agree on all of it."""
    def of(st: dict) -> tuple:
        genomes = {k: (sorted(g.nodes), sorted((c.key, c.weight, c.enabled) for c in g.connections.values()))
                   for k, g in st["population"].items()}
        species = st["species"]
        species = species if isinstance(species, dict) else vars(species)
        return genomes, {sid: sorted(s.members) for sid, s in species["species"].items()}
    inner = state.get("problem", {}).get("inner", {})
    return {"outer": of(state), **{key: of(st) for key, (st, _) in inner.items()}}


def max_node_key(state: dict) -> int:
    """Largest node key in a checkpoint's population(s), inner controller populations included."""
    keys = [k for g in state["population"].values() for k in g.nodes]
    for inner, _ in state.get("problem", {}).get("inner", {}).values():
        keys += [k for g in inner["population"].values() for k in g.nodes]
    return max(keys)


@pytest.mark.slow
@pytest.mark.subprocess
@pytest.mark.parametrize("method", [pytest.param(m, marks=pytest.mark.long) if m == "direct" else m
                                    for m in METHODS])  # direct: NEAT as sgr's, on another genome
def test_sigkilled_run_resumes_in_a_new_process_to_the_same_run(tmp_path, repo_root, method):
    cfg = write_config(tmp_path, repo_root, method)
    crashed = RunDir(tmp_path / "crashed")
    proc = sgr("evolve", "--config", str(cfg), "--out", str(crashed.path), "--quiet")
    kill_when(proc, crashed, KILL_AT_ROWS)
    full = Experiment.create(str(cfg), str(tmp_path / "full"), {}, quiet=True)  # the reference
    full.run_all()
    full.close()

    resume_from = load_checkpoint(crashed)
    assert resume_from["generation"] == 6
    resumed = sgr("evolve", "--resume", str(crashed.path), "--quiet")
    _, err = resumed.communicate(timeout=300)
    assert resumed.returncode == 0, err

    final = load_checkpoint(crashed)
    assert final["generation"] == GENERATIONS
    assert max_node_key(final) > max_node_key(resume_from), "no node was added after the resume"
    assert fitness_rows(crashed) == fitness_rows(RunDir(tmp_path / "full"))
    assert genomes_and_species(final) == genomes_and_species(load_checkpoint(RunDir(tmp_path / "full")))
    assert len(crashed.rows()) == GENERATIONS
    assert crashed.champion() == RunDir(tmp_path / "full").champion()


def test_damaged_newest_checkpoint_falls_back_to_the_previous_one(tmp_path, repo_root, capsys):
    cfg = write_config(tmp_path, repo_root, "sgr", generations=6, pop_size=16, checkpoint_every=2)
    full = Experiment.create(str(cfg), str(tmp_path / "full"), {}, quiet=True)
    full.run_all()
    full.close()

    damaged = Experiment.create(str(cfg), str(tmp_path / "damaged"), {"generations": 4}, quiet=True)
    damaged.run_all()  # checkpoints of generations 2 and 4
    damaged.close()
    newest = damaged.run.ckpt_dir / "gen-00004.json.gz"
    newest.write_bytes(newest.read_bytes()[:1000])  # a copy cut short
    assert os.path.getsize(damaged.run.ckpt_dir / "gen-00002.json.gz") > 1000

    exp = Experiment.resume(str(tmp_path / "damaged"), quiet=True, generations=6)
    err = capsys.readouterr().err
    assert exp.search.generation == 2
    assert err.count("\n") == 1 and err.startswith("sgr: warning: skipped gen-00004.json.gz (damaged, ")
    assert err.endswith("resuming from gen-00002.json.gz\n")
    exp.run_all()
    exp.close()
    assert fitness_rows(exp.run) == fitness_rows(RunDir(tmp_path / "full"))


@pytest.mark.slow
@pytest.mark.subprocess
def test_no_usable_checkpoint_is_one_error_line(tmp_path, repo_root):
    cfg = write_config(tmp_path, repo_root, "sgr", generations=2, pop_size=8, checkpoint_every=1)
    run = RunDir(tmp_path / "run")
    exp = Experiment.create(str(cfg), str(run.path), {}, quiet=True)
    exp.run_all()
    exp.close()
    for f in run.ckpt_dir.glob("gen-*.json.gz"):
        f.write_bytes(b"not a checkpoint")
    proc = sgr("evolve", "--resume", str(run.path))
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 2
    assert err.startswith("sgr: error: no usable checkpoint") and err.count("\n") == 1, err
    assert "gen-00001.json.gz" in err and "gen-00002.json.gz" in err


@pytest.mark.slow
def test_a_finished_run_is_extended_exactly_by_resume_with_more_generations(tmp_path, repo_root, capsys):
    from evolve.cli import main

    cfg = write_config(tmp_path, repo_root, "sgr", pop_size=16, checkpoint_every=2)
    short, long_ = str(tmp_path / "short"), str(tmp_path / "long")
    assert main(["evolve", "--config", str(cfg), "--generations", "3", "--out", short, "--quiet"]) == 0
    assert main(["evolve", "--resume", short, "--quiet"]) == 2
    assert "is finished (3 of 3 generations); add --generations N" in capsys.readouterr().err
    assert main(["evolve", "--resume", short, "--generations", "5", "--quiet"]) == 0
    assert main(["evolve", "--config", str(cfg), "--generations", "5", "--out", long_, "--quiet"]) == 0
    assert fitness_rows(RunDir(short)) == fitness_rows(RunDir(long_))
    assert RunDir(short).config()["generations"] == 5


@pytest.mark.parametrize("content, message", [
    (None, "is not a run directory (no config.yaml)"),
    ("- a list\n", "not a run config"),
    ("method: [unclosed\n", "not valid YAML"),
])
def test_resume_of_a_folder_that_is_not_a_run_is_one_error_line(tmp_path, capsys, content, message):
    from evolve.cli import main

    if content is not None:
        (tmp_path / "config.yaml").write_text(content)
    assert main(["evolve", "--resume", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("sgr: error:") and message in err and err.count("\n") == 1, err


def test_run_files_get_the_permissions_of_the_umask(tmp_path, repo_root):
    cfg = write_config(tmp_path, repo_root, "sgr", generations=1, pop_size=8)
    old = os.umask(0o022)
    try:
        exp = Experiment.create(str(cfg), str(tmp_path / "run"), {}, quiet=True)
        exp.run_all()
        exp.close()
    finally:
        os.umask(old)
    files = [f for f in (tmp_path / "run").rglob("*") if f.is_file()]
    assert {f.name for f in files} >= {"config.yaml", "neat.ini", "generations.csv", "champion.json",
                                       "gen-00001.json.gz"}
    assert {oct(f.stat().st_mode & 0o777) for f in files} == {"0o644"}


@pytest.mark.slow
def test_a_full_disk_stops_the_run_with_one_line_and_it_resumes_exactly(tmp_path, repo_root, capsys,
                                                                        monkeypatch):
    import errno

    import evolve.records.rundir
    from evolve.cli import main

    cfg = write_config(tmp_path, repo_root, "sgr", generations=5, pop_size=16, checkpoint_every=2)
    run = RunDir(tmp_path / "run")
    real_fsync, calls = os.fsync, {"n": 0}

    def fsync_until_full(fd):
        calls["n"] += 1
        if calls["n"] > 12:  # some generations in: every later write finds the disk full
            raise OSError(errno.ENOSPC, "No space left on device")
        real_fsync(fd)

    monkeypatch.setattr(evolve.records.rundir.os, "fsync", fsync_until_full)
    assert main(["evolve", "--config", str(cfg), "--out", str(run.path), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("sgr: error: cannot write ") and "No space left on device" in err
    assert f"sgr evolve --resume {run.path}" in err and err.count("\n") == 1
    assert [f.name for f in run.path.rglob(".*")] == [".lock"]  # no temporary file left behind
    rows_before = run.rows()
    assert 0 < len(rows_before) < 5  # the CSV is whole: the last complete version

    monkeypatch.setattr(evolve.records.rundir.os, "fsync", real_fsync)
    assert main(["evolve", "--resume", str(run.path), "--quiet"]) == 0
    assert main(["evolve", "--config", str(cfg), "--out", str(tmp_path / "full"), "--quiet"]) == 0
    assert fitness_rows(run) == fitness_rows(RunDir(tmp_path / "full"))


def test_a_run_advanced_by_another_process_is_refused_with_one_line(tmp_path, repo_root, capsys):
    from evolve.cli import main

    cfg = write_config(tmp_path, repo_root, "sgr", generations=2, pop_size=8)
    running = Experiment.create(str(cfg), str(tmp_path / "run"), {}, quiet=True)  # holds the run
    try:
        assert main(["evolve", "--resume", str(tmp_path / "run"), "--quiet"]) == 2
        err = capsys.readouterr().err
        assert f"is being run by another process (pid {os.getpid()})" in err and err.count("\n") == 1
    finally:
        running.close()
    assert main(["evolve", "--resume", str(tmp_path / "run"), "--quiet"]) == 0  # free once it stops


def test_generations_csv_is_appended_and_a_row_cut_short_is_no_row(tmp_path, repo_root, monkeypatch):
    cfg = write_config(tmp_path, repo_root, "sgr", generations=2, pop_size=8, checkpoint_every=1)
    full = Experiment.create(str(cfg), str(tmp_path / "full"), {"generations": 3}, quiet=True)
    full.run_all()
    full.close()
    exp = Experiment.create(str(cfg), str(tmp_path / "run"), {}, quiet=True)
    with monkeypatch.context() as m:  # appending a row reads nothing back: O(1) per generation
        m.setattr(RunDir, "rows", lambda self: pytest.fail("append_row re-read generations.csv"))
        exp.run_all()
    exp.close()
    csv_path = exp.run.path / "generations.csv"
    whole = csv_path.read_bytes()
    with csv_path.open("ab") as f:  # a kill or a full disk in the middle of writing generation 2's row
        f.write(b"3,1.2345")
    assert fitness_rows(exp.run) == fitness_rows(RunDir(tmp_path / "full"))[:2]
    from evolve.report.plots import read_generations
    assert len(read_generations(exp.run.path)["best"]) == 2
    resumed = Experiment.resume(str(exp.run.path), quiet=True, generations=3)
    assert csv_path.read_bytes() == whole  # the resume dropped the cut row
    resumed.run_all()
    resumed.close()
    assert fitness_rows(exp.run) == fitness_rows(RunDir(tmp_path / "full"))
    with csv_path.open("ab") as f:
        f.write(b"4,0.5")
    exp.run.append_row({**exp.run.rows()[-1], "generation": 4})  # a cut row is dropped on the next write
    lines = csv_path.read_text().splitlines()
    assert [r["generation"] for r in exp.run.rows()] == ["1", "2", "3", "4"]  # counted from 1
    assert len(lines) == 5 and all(line.count(",") == len(COLUMNS) - 1 for line in lines)
