"""Cluster-friendly stops: SIGTERM (what a scheduler sends before SIGKILL) ends the generation under
way with a checkpoint, as a first Ctrl-C does, and the resumed run is the uninterrupted one; a second
signal stops at once; a sweep passes the stop on to its runs."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from evolve.cli import main
from evolve.records.rundir import RunDir
from evolve.runs.experiment import Experiment

pytestmark = [pytest.mark.slow, pytest.mark.subprocess]

# the deterministic columns (the rest are timings)
FITNESS_COLUMNS = ["generation", "best", "mean", "median", "n_species", "n_valid", "n_invalid", "episodes"]
GENERATIONS = 6


def write_config(tmp_path: Path, repo_root: Path, **changes) -> Path:
    cfg = {"method": "sgr", "task": "Walker-v0", "generations": GENERATIONS, "pop_size": 16, "seed": 7,
           "episode_steps": 12, "render_champion": False, "workers": 1,
           "checkpoint_every": 1000,  # no checkpoint is due before the end: the stop writes its own
           "neat_config": str(repo_root / "configs/neat/sgr.ini"), **changes}
    p = tmp_path / "cfg.yaml"
    p.write_text(yaml.safe_dump(cfg))
    return p


def start(*args: str, cwd: Path, **kw) -> subprocess.Popen:
    env = {k: v for k, v in os.environ.items() if k not in ("SGR_ARCH", "SGR_THREADS")}
    return subprocess.Popen([sys.executable, "-m", "evolve.cli", *args], cwd=cwd, env=env, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, **kw)


def wait_for_rows(proc: subprocess.Popen, run: RunDir, rows: int) -> None:
    deadline = time.monotonic() + 180
    while not (run.path.joinpath("generations.csv").is_file() and len(run.rows()) >= rows):
        assert proc.poll() is None, f"the run ended before the signal: {proc.stderr.read()}"
        assert time.monotonic() < deadline
        time.sleep(0.01)


def fitness_rows(run: RunDir) -> list[list[str]]:
    return [[r[c] for c in FITNESS_COLUMNS] for r in run.rows()]


def test_sigterm_checkpoints_the_generation_under_way_and_the_resumed_run_equals_the_uninterrupted(
        tmp_path, repo_root):
    """SIGTERM mid-run, to every process of the run as a scheduler sends it (its two rollout
    workers too, which ignore it: none dies and is started again): the generation under way ends,
    its checkpoint is written (none was due), the run exits 143 (128 + SIGTERM) with the resume
    command, and `sgr evolve --resume` then gives generations.csv's deterministic columns and the
    champion of the run nobody stopped (run on one worker: the worker count changes no result)."""
    cfg = write_config(tmp_path, repo_root, episode_steps=300)  # the workers busy most of the time
    stopped = RunDir(tmp_path / "stopped")
    proc = start("evolve", "--config", str(cfg), "--out", str(stopped.path), "--workers", "2", cwd=tmp_path,
                 start_new_session=True)  # its own process group, as a batch job's
    wait_for_rows(proc, stopped, 2)
    time.sleep(0.5)  # into generation 3's episodes
    os.killpg(proc.pid, signal.SIGTERM)
    out, err = proc.communicate(timeout=180)
    assert proc.returncode == 143, err
    n = len(stopped.rows())
    assert 3 <= n < GENERATIONS
    assert "SIGTERM: stopping after this generation, with a checkpoint" in err
    assert "died" not in err  # no rollout worker was lost (and started again) to the signal
    assert f"SIGTERM: stopped after generation {n} of {GENERATIONS}, with a checkpoint; continue with: " \
           f"sgr evolve --resume {stopped.path}" in err
    assert stopped.last_checkpoint_generation() == n  # written at the stop, not by the schedule

    assert main(["evolve", "--resume", str(stopped.path), "--quiet", "--workers", "1"]) == 0
    with Experiment.create(str(cfg), str(tmp_path / "whole"), {}, quiet=True) as whole:
        whole.run_all()
    assert len(stopped.rows()) == GENERATIONS
    assert fitness_rows(stopped) == fitness_rows(RunDir(tmp_path / "whole"))
    assert stopped.champion() == RunDir(tmp_path / "whole").champion()


def test_a_second_signal_stops_at_once_at_the_last_checkpoint(tmp_path, repo_root):
    """SIGTERM, then SIGTERM again before the generation under way ends: the run stops at once,
    without finishing that generation (no row, no checkpoint for it), having written the checkpoint
    of the last finished generation (none was due), exits 143 and names it to resume from.
    Generations here take seconds (long episodes), the signals come 0.3 s apart, half a second into
    generation 2."""
    cfg = write_config(tmp_path, repo_root, episode_steps=2000, pop_size=24)
    run = RunDir(tmp_path / "run")
    proc = start("evolve", "--config", str(cfg), "--out", str(run.path), cwd=tmp_path)
    while not proc.stdout.readline().startswith("gen    1/"):  # generation 1 is done, 2 under way
        assert proc.poll() is None, proc.stderr.read()
    time.sleep(0.5)
    proc.send_signal(signal.SIGTERM)
    time.sleep(0.3)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143, err
    assert len(run.rows()) == 1  # generation 2 was under way and was not finished
    assert run.last_checkpoint_generation() == 1  # issue 57: the last finished generation's, written first
    assert (f"SIGTERM: stopped during generation 2 of {GENERATIONS}; its last checkpoint is after "
            "generation 1") in err
    assert "Traceback" not in err


def test_a_sigterm_to_a_sweeps_process_group_checkpoints_its_running_run_and_the_sweep_resumes(
        tmp_path, repo_root):
    """A scheduler signals every process of a job: the sweep, its run's process and the run's rollout
    workers all get SIGTERM, and the sweep passes the stop on to the run as well. The run still ends
    its generation with a checkpoint (the sweep's ask is no second signal), the sweep exits 143 and
    `sgr sweep --resume` completes the run to the numbers of an uninterrupted run."""
    spec = tmp_path / "sweep.yaml"
    spec.write_text(yaml.safe_dump({
        "methods": ["sgr"], "tasks": ["Walker-v0"], "seeds": [2],
        "overrides": {"generations": GENERATIONS, "pop_size": 16, "episode_steps": 12, "workers": 1,
                      "checkpoint_every": 1000, "render_champion": False}}))
    cut = tmp_path / "cut"
    proc = start("sweep", "--config", str(spec), "--out", str(cut), "--quiet", "--parallel", "1",
                 cwd=tmp_path, start_new_session=True)  # its own process group, as a batch job's
    run = RunDir(cut / "runs" / "sgr-Walker-v0-s2")
    wait_for_rows(proc, run, 2)
    os.killpg(proc.pid, signal.SIGTERM)
    out, err = proc.communicate(timeout=180)
    assert proc.returncode == 143, out + err
    assert "interrupted by SIGTERM; continue with: sgr sweep --resume" in out
    n = len(run.rows())
    assert n < GENERATIONS
    assert run.last_checkpoint_generation() == n  # the stop's checkpoint, the generation ended
    log = (run.path / "log.txt").read_text()  # (the sweep's ask may come first: no second signal)
    assert "stopping after this generation, with a checkpoint" in log
    assert f"sgr: SIGTERM: stopped after generation {n} of {GENERATIONS}, with a checkpoint" in log

    assert main(["sweep", "--resume", str(cut), "--quiet"]) == 0
    assert main(["sweep", "--config", str(spec), "--out", str(tmp_path / "whole"), "--quiet"]) == 0
    whole = RunDir(tmp_path / "whole" / "runs" / "sgr-Walker-v0-s2")
    assert len(run.rows()) == GENERATIONS
    assert fitness_rows(run) == fitness_rows(whole)
    assert run.champion() == whole.champion()
