"""A stop sent twice at once is one stop; a second stop later stops at once, yet loses only the
generation under way.

`timeout`, `kill -TERM -PGID` and many schedulers signal the process and then its process group, so
sgr gets the same SIGTERM twice within microseconds: that is one request (the generation under way
ends, with a checkpoint), and the resumed run equals the uninterrupted one. A second SIGTERM that
comes later (past `stops.SAME_REQUEST_S`) stops at once, after writing the checkpoint of the last
finished generation (none was due: `checkpoint_every` is larger than the run), from which the run
resumes exactly. Real signals throughout: `timeout` (coreutils) around `python -m evolve.cli evolve`,
and the test process signalling itself from inside a generation."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from evolve.records.rundir import RunDir
from evolve.runs import stops
from evolve.runs.experiment import Experiment
from evolve.runs.stops import Interrupted

pytestmark = [pytest.mark.slow, pytest.mark.subprocess]

LATER = getattr(stops, "SAME_REQUEST_S", 0.2) + 0.3  # a second signal past the window

FITNESS_COLUMNS = ["generation", "best", "mean", "median", "n_species", "n_valid", "n_invalid", "episodes"]
GENERATIONS = 4
CONFIG = {"method": "sgr", "task": "Walker-v0", "generations": GENERATIONS, "pop_size": 8, "seed": 5,
          "episode_steps": 20, "workers": 1, "render_champion": False, "robust": None,
          "final_selection": None, "checkpoint_every": 1000}  # no checkpoint is due before the end


def fitness_rows(run: RunDir) -> list[list[str]]:
    return [[r[c] for c in FITNESS_COLUMNS] for r in run.rows()]


@pytest.fixture(scope="module")
def whole(tmp_path_factory) -> RunDir:
    """The run nobody stopped (in this process)."""
    folder = tmp_path_factory.mktemp("whole") / "run"
    with Experiment.from_config(CONFIG, folder, quiet=True) as exp:
        exp.run_all()
    return RunDir(folder)


def signals_in_generation(exp: Experiment, generation: int, gap: float) -> None:
    """Make the evaluation of `generation` (counted from 1) send this process SIGTERM twice, `gap`
    seconds apart, once the generation's genomes are bred and decoded (its state half changed)."""
    real = exp.search.evaluate

    def evaluate(phenotypes, tags):
        if exp.search.generation + 1 == generation:
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(gap)
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(0.05)  # (the handler runs at the next bytecode)
        return real(phenotypes, tags)

    exp.search.evaluate = evaluate


def test_sigterm_twice_at_once_is_one_stop_the_generation_ends_with_a_checkpoint(tmp_path, whole):
    """Two SIGTERMs at once (as `timeout` sends them) during generation 2: generation 2 ends, its
    checkpoint is written, the stop is not "at once"; the resumed run equals the uninterrupted one.
    (Before: the second one stopped at once, at the checkpoint of generation 0.)"""
    folder = tmp_path / "run"
    with Experiment.from_config(CONFIG, folder, quiet=True) as exp:
        signals_in_generation(exp, 2, 0.0)
        with pytest.raises(Interrupted) as stopped:
            exp.run_all()
    assert not stopped.value.at_once and stopped.value.signum == signal.SIGTERM
    run = RunDir(folder)
    assert len(run.rows()) == 2 and run.last_checkpoint_generation() == 2
    with Experiment.resume(folder, quiet=True) as exp:
        exp.run_all()
    assert fitness_rows(run) == fitness_rows(whole)
    assert run.champion() == whole.champion()


def test_a_second_sigterm_past_the_window_stops_at_once_with_a_checkpoint_of_the_last_finished_generation(
        tmp_path, whole):
    """SIGTERM, then SIGTERM again past stops.SAME_REQUEST_S, in the middle of generation 3 (its genomes
    bred, their evaluation begun): the run stops at once, generation 3 unfinished, and the checkpoint
    of generation 2, which the schedule skipped, is written first: its generation is the rows'
    count. The resumed run equals the uninterrupted one. (Before: the last checkpoint was
    generation 0's: two finished generations lost.)"""
    folder = tmp_path / "run"
    with Experiment.from_config(CONFIG, folder, quiet=True) as exp:
        signals_in_generation(exp, 3, LATER)
        with pytest.raises(Interrupted) as stopped:
            exp.run_all()
    assert stopped.value.at_once
    run = RunDir(folder)
    assert len(run.rows()) == 2
    assert run.last_checkpoint_generation() == len(run.rows())
    with Experiment.resume(folder, quiet=True) as exp:
        assert exp.search.generation == 2
        exp.run_all()
    assert fitness_rows(run) == fitness_rows(whole)
    assert run.champion() == whole.champion()


LONG = {**CONFIG, "episode_steps": 150, "generations": 5}  # generations long enough to stop one


@pytest.fixture(scope="module")
def long_config(tmp_path_factory) -> tuple[Path, RunDir]:
    """LONG's config file, and the run of it nobody stopped (in this process)."""
    import yaml

    folder = tmp_path_factory.mktemp("long")
    cfg = folder / "cfg.yaml"
    cfg.write_text(yaml.safe_dump(LONG))
    with Experiment.create(str(cfg), folder / "whole", {}, quiet=True) as exp:
        exp.run_all()
    return cfg, RunDir(folder / "whole")


@pytest.mark.parametrize("sender", ["timeout", "killpg twice"])
def test_timeout_s_term_mid_run_then_resume_equals_the_uninterrupted_run(tmp_path, long_config, sender):
    """`timeout -s TERM N sgr evolve ...` (coreutils), its time made to be up once generations.csv
    has 2 rows by sending it SIGALRM (its own timer's signal): it sends SIGTERM to sgr and then to
    its process group, as at N seconds. Or the test does the same itself: SIGTERM to the process
    group twice, 50 ms apart (so that sgr surely sees two). sgr ends the generation under way with
    a checkpoint (exit 143, "stopped after generation n", n >= 2), and `sgr evolve --resume` gives
    the uninterrupted run's fitness columns and champion."""
    if sender == "timeout" and shutil.which("timeout") is None:
        pytest.skip("needs coreutils' timeout")
    cfg, whole_run = long_config
    folder = tmp_path / "run"
    env = {k: v for k, v in os.environ.items() if k not in ("SGR_ARCH", "SGR_THREADS")}
    sgr = [sys.executable, "-m", "evolve.cli", "evolve", "--config", str(cfg), "--out", str(folder),
           "--quiet"]
    if sender == "timeout":
        proc = subprocess.Popen(["timeout", "--preserve-status", "-s", "TERM", "600", *sgr], cwd=tmp_path,
                                env=env, text=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    else:
        proc = subprocess.Popen(sgr, cwd=tmp_path, env=env, text=True, stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, start_new_session=True)  # a job's process group
    run = RunDir(folder)
    deadline = time.monotonic() + 180
    while not ((folder / "generations.csv").is_file() and len(run.rows()) >= 2):
        assert proc.poll() is None, f"the run ended before the signal: {proc.stderr.read()}"
        assert time.monotonic() < deadline
        time.sleep(0.01)
    if sender == "timeout":
        os.kill(proc.pid, signal.SIGALRM)  # timeout's time is up
    else:
        os.killpg(proc.pid, signal.SIGTERM)
        time.sleep(0.05)
        os.killpg(proc.pid, signal.SIGTERM)
    _, err = proc.communicate(timeout=180)
    assert proc.returncode == 143, err
    n = len(run.rows())
    assert 2 <= n < LONG["generations"], err
    assert run.last_checkpoint_generation() == n, err
    assert f"SIGTERM: stopped after generation {n} of {LONG['generations']}, with a checkpoint" in err, err
    r = subprocess.run([sys.executable, "-m", "evolve.cli", "evolve", "--resume", str(folder), "--quiet"],
                       cwd=tmp_path, env=env, capture_output=True, text=True, timeout=180)
    assert r.returncode == 0, r.stderr
    assert fitness_rows(run) == fitness_rows(whole_run)
    assert run.champion() == whole_run.champion()


def test_the_stop_message_of_a_second_signal_names_the_checkpoint_it_wrote(tmp_path, capsys):
    """`sgr evolve` stopped at once during generation 2 says so, and that its checkpoint is after
    generation 1 (the one it wrote), with the command that resumes it."""
    from evolve.cli.evolve_cmd import run_experiment

    exp = Experiment.from_config({**CONFIG, "generations": 2}, tmp_path / "run", quiet=True)
    signals_in_generation(exp, 2, LATER)
    assert run_experiment(exp) == 143
    err = capsys.readouterr().err
    assert (f"SIGTERM: stopped during generation 2 of 2; its last checkpoint is after generation 1; "
            f"continue with: sgr evolve --resume {tmp_path / 'run'}") in err, err
    assert RunDir(tmp_path / "run").last_checkpoint_generation() == 1
    assert not Path(tmp_path / "run" / "fitness.png").exists()
