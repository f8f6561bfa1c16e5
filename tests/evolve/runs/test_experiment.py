"""Runs: config errors name the key; a killed run resumes to the same numbers; run-dir contents."""

import json
from pathlib import Path

import pytest
import yaml

from evolve.cli import main
from evolve.records.replay import replay_champion
from evolve.records.rundir import RunDir
from evolve.runs.experiment import Experiment

TINY = {"method": "sgr", "task": "Walker-v0", "generations": 4, "pop_size": 8, "seed": 5,
        "episode_steps": 15, "checkpoint_every": 2, "render_champion": False, "robust": None,
        "final_selection": None, "workers": 1}  # one rollout process: no worker start-up in each test


def _write(tmp_path, repo_root, **changes):
    cfg = {**TINY, "neat_config": str(repo_root / "configs/neat/sgr.ini"), **changes}
    p = tmp_path / "cfg.yaml"
    p.write_text(yaml.safe_dump(cfg))
    return p


@pytest.mark.parametrize("changes, message", [
    ({"popsize": 3}, "unknown key 'popsize'"),
    ({"task": "Jumper-v9"}, "key 'task': unknown task 'Jumper-v9'"),
    ({"generations": "ten"}, "key 'generations' must be int"),
    ({"cppn_outputs": 3}, "key 'cppn_outputs' must be 1 or 2"),
    ({"max_weight": True}, "key 'max_weight' must be float"),
    ({"method": "cmaes"}, "key 'method' must be one of"),
    ({"workers": "many"}, "key 'workers' must be a positive int, 'auto' or 'ray'"),
    ({"layout": "per_cell"}, "unknown key 'layout' for method 'sgr'"),
    ({"workers": 0}, "key 'workers' must be a positive int, 'auto' or 'ray'"),
])
def test_config_errors_name_the_key(tmp_path, repo_root, capsys, changes, message):
    p = _write(tmp_path, repo_root, **changes)
    assert main(["evolve", "--config", str(p), "--out", str(tmp_path / "run"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
    assert not (tmp_path / "run" / "generations.csv").exists()


@pytest.mark.parametrize("changes, message", [
    ({"inner_keep_generations": 0}, "key 'inner_keep_generations' must be a positive int or null"),
    ({"inner_keep_generations": "forever"}, "key 'inner_keep_generations' must be int or null"),
    ({"inner_keep_generations": True}, "key 'inner_keep_generations' must be int or null"),
    ({"inner_pop_size": 0}, "key 'inner_pop_size' must be >= 1"),
    ({"inner_generations": 0}, "key 'inner_generations' must be >= 1"),
])
def test_nested_config_errors_name_the_key(tmp_path, repo_root, capsys, changes, message):
    neat = repo_root / "configs/neat"
    p = _write(tmp_path, repo_root, method="nested", neat_config=str(neat / "nested-body.ini"),
               controller_neat_config=str(neat / "nested-controller.ini"), **changes)
    assert main(["evolve", "--config", str(p), "--out", str(tmp_path / "run"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
    assert not (tmp_path / "run" / "generations.csv").exists()


@pytest.mark.slow
def test_killed_run_resumes_with_identical_fitness_columns(tmp_path, repo_root):
    p = _write(tmp_path, repo_root)
    full = Experiment.create(str(p), str(tmp_path / "full"), {}, quiet=True)
    full.run_all()

    crashed = Experiment.create(str(p), str(tmp_path / "crash"), {}, quiet=True)
    step = crashed.search.step
    calls = {"n": 0}

    def dying_step():
        calls["n"] += 1
        if calls["n"] == 4:  # killed while evaluating generation 3, after the gen-2 checkpoint
            raise KeyboardInterrupt
        return step()

    crashed.search.step = dying_step
    with pytest.raises(KeyboardInterrupt):
        crashed.run_all()
    crashed.close()  # what the process's end would do: release the run's lock
    assert len(RunDir(tmp_path / "crash").rows()) == 3  # generation 2 was logged after the checkpoint
    assert main(["evolve", "--resume", str(tmp_path / "crash"), "--quiet"]) == 0

    cols = ["generation", "best", "mean", "median", "n_species", "n_valid", "n_invalid", "episodes"]
    a = [[r[c] for c in cols] for r in RunDir(tmp_path / "full").rows()]
    b = [[r[c] for c in cols] for r in RunDir(tmp_path / "crash").rows()]
    assert len(a) == 4 and a == b
    ca = json.loads((tmp_path / "full" / "champion.json").read_text())
    cb = json.loads((tmp_path / "crash" / "champion.json").read_text())
    assert ca == cb and ca["controller"]["layers"][0]["activation"] == "tanh"
    assert len(ca["body"]) == 5 and ca["fitness"] == max(float(r[1]) for r in a)
    # the JSON champion alone (dense layers, no neat-python) reproduces its recorded fitness
    assert replay_champion(tmp_path / "full")[0] == pytest.approx(ca["fitness"], abs=1e-9)


@pytest.mark.slow
def test_a_run_directory_is_not_overwritten(tmp_path, repo_root, capsys):
    p = _write(tmp_path, repo_root, generations=1)
    out = str(tmp_path / "r")
    assert main(["evolve", "--config", str(p), "--out", out, "--quiet"]) == 0
    assert main(["evolve", "--config", str(p), "--out", out, "--quiet"]) == 2
    assert "already holds a run" in capsys.readouterr().err


def test_ctrl_c_stops_the_run_with_a_resume_hint(tmp_path, repo_root, capsys, monkeypatch):
    p = _write(tmp_path, repo_root)

    def interrupted(self):
        raise KeyboardInterrupt
    monkeypatch.setattr(Experiment, "run_all", interrupted)
    out = tmp_path / "run"
    assert main(["evolve", "--config", str(p), "--out", str(out), "--quiet"]) == 130
    err = capsys.readouterr().err
    assert f"sgr evolve --resume {out}" in err
    assert RunDir(out).latest_checkpoint() is not None  # generation 0's state is there to resume


@pytest.mark.slow
@pytest.mark.subprocess
def test_ctrl_c_writes_a_checkpoint_and_every_generation_number_agrees(tmp_path, repo_root):
    """A real SIGINT: the generation under way ends, a checkpoint of it is written (none was due:
    checkpoint_every is 1000) and the run stops with exit 130. The console, generations.csv,
    champion.json, the checkpoint and the stop message all count generations from 1 alike, and the
    resumed run starts after the interrupted generation."""
    import os
    import re
    import signal
    import subprocess
    import sys
    import time

    p = _write(tmp_path, repo_root, generations=1000, checkpoint_every=1000, workers=1)
    env = {k: v for k, v in os.environ.items() if k not in ("SGR_ARCH", "SGR_THREADS")}
    proc = subprocess.Popen([sys.executable, "-m", "evolve.cli", "evolve", "--config", str(p), "--out", "r"],
                            cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    run = RunDir(tmp_path / "r")
    deadline = time.monotonic() + 120
    while len(run.rows()) < 3:
        assert proc.poll() is None and time.monotonic() < deadline, proc.stderr.read()
        time.sleep(0.02)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    rows = run.rows()
    n = len(rows)
    assert [int(r["generation"]) for r in rows] == list(range(1, n + 1))
    console = [int(g) for g in re.findall(r"^gen +(\d+)/1000", out, re.M)]
    assert console == list(range(1, n + 1))
    assert f"stopped after generation {n} of 1000, with a checkpoint" in err
    assert (run.ckpt_dir / f"gen-{n:05d}.json.gz").is_file()  # written at the stop, not by the schedule
    champ = json.loads((run.path / "champion.json").read_text())
    first_best = next(int(r["generation"]) for r in rows if float(r["best"]) == champ["fitness"])
    assert champ["generation"] == first_best
    assert main(["evolve", "--resume", str(run.path), "--generations", str(n + 1), "--quiet"]) == 0
    assert [int(r["generation"]) for r in run.rows()] == list(range(1, n + 2))


def test_packaged_configs_resolve_by_name_from_any_folder(tmp_path, monkeypatch):
    """sgr/Climber-v2, quick and paper name the packaged files wherever one stands; a path that
    exists is still a path."""
    from evolve.runs.config import configs_dir, find_config

    monkeypatch.chdir(tmp_path)
    assert find_config("sgr/Climber-v2") == configs_dir() / "sgr" / "Climber-v2.yaml"
    assert find_config("direct/Walker-v0.yaml") == configs_dir() / "direct" / "Walker-v0.yaml"
    assert find_config("quick") == configs_dir() / "sgr" / "quick.yaml"
    assert find_config("paper", "sweep file") == configs_dir() / "sweeps" / "paper.yaml"
    (tmp_path / "sgr").mkdir()
    (tmp_path / "sgr" / "Climber-v2").write_text("method: sgr\n")
    assert find_config("sgr/Climber-v2") == Path("sgr/Climber-v2")


@pytest.mark.slow
def test_evolve_task_and_method_run_the_packaged_config_in_a_named_folder(tmp_path, monkeypatch, capsys,
                                                                            repo_root):
    monkeypatch.chdir(tmp_path)
    # 60-step episodes (the packaged length, 500, made the test 18 s, most of it the champion's GIF
    # and final selection; tests/evolve/runs/test_run_config.py holds the paper length resolved)
    assert main(["evolve", "--task", "Walker-v0", "--method", "direct", "--generations", "1", "--pop", "4",
                 "--workers", "1", "--episode-steps", "60", "--quiet"]) == 0
    (run,) = (tmp_path / "runs").iterdir()
    assert run.name.startswith("direct-Walker-v0-seed0-")
    raw = RunDir(run).config()
    packaged = yaml.safe_load((repo_root / "configs/direct/Walker-v0.yaml").read_text())
    assert raw["method"] == "direct" and raw["task"] == "Walker-v0" and raw["episode_steps"] == 60
    for key in ("robust", "final_selection", "body_distance_weight", "checkpoint_every"):  # as packaged
        assert raw[key] == packaged[key], key
    out = capsys.readouterr().out.splitlines()  # the first line names the backend (issue 45)
    assert out[0].startswith("backend: cpu (") and out[1] == f"run directory: {Path('runs') / run.name}"
