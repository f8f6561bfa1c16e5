"""A ga-ppo run is a run like the others (evolve/methods/ga_ppo.py): its champion replays its
recorded fitness from champion.json alone, survivors are not trained again, it keeps no neat.ini,
and killed with SIGKILL and resumed it is the run it would have been; a bad `ppo` key, or torch
missing, is one line."""

from __future__ import annotations

import gzip
import json
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from evolve.records.replay import load_champion, rescore_champion
from evolve.records.rundir import RunDir
from evolve.runs.checkpoint import load_checkpoint
from evolve.runs.experiment import Experiment
from tests.evolve.cli.test_errors import in_process, one_error, run_cli
from tests.evolve.runs.test_resume import kill_when, sgr

pytest.importorskip("torch", reason="method ga-ppo needs torch: pip install 'sgr[rl]'")

ROOT = Path(__file__).resolve().parents[3]
# honest evaluation (noise, accumulated scores) of 4 bodies trained 256 steps each; no final selection
TINY = {"method": "ga-ppo", "task": "Walker-v0", "generations": 3, "pop_size": 4, "seed": 2,
        "episode_steps": 30, "workers": 1, "render_champion": False, "final_selection": None,
        "robust": {"episodes": 1, "action_noise": "uniform", "action_scale": 0.001, "reevaluate": True,
                   "accumulate": True, "settle": 3},
        "ppo": {"timesteps": 256, "n_envs": 2, "n_steps": 32, "batch_size": 32, "n_epochs": 2}}
COLUMNS = ["generation", "best", "mean", "median", "n_valid", "episodes", "body_diversity"]


def rows(run: RunDir) -> list[list[str]]:
    return [[r[c] for c in COLUMNS] for r in run.rows()]


@pytest.fixture(scope="module")
def tiny(tmp_path_factory) -> RunDir:
    folder = tmp_path_factory.mktemp("gappo") / "run"
    with Experiment.from_config(TINY, folder, quiet=True) as exp:
        exp.run_all()
    return RunDir(folder)


def test_a_run_trains_new_bodies_only_and_keeps_no_neat_ini(tiny):
    """4 bodies trained in generation 1, then only the mutants (pop 4, 2 survivors each time)."""
    assert [int(r["n_valid"]) for r in tiny.rows()] == [4, 2, 2]
    assert not (tiny.path / "neat.ini").exists()
    champ = tiny.champion()
    assert champ["method"] == "ga-ppo" and champ["controller"]["format"] == "sgr-mlp-controller-1"
    assert champ["training"]["timesteps"] == 256 and champ["training"]["ppo"]["n_envs"] == 2


def test_the_champion_replays_its_recorded_fitness_to_the_bit(tiny):
    champ = tiny.champion()
    assert rescore_champion(tiny.path) == champ["fitness"]
    loaded = load_champion(tiny.path)
    assert loaded.body.tolist() == champ["body"] and loaded.fitness == champ["fitness"]
    assert champ["headline"]["episodes"] == 20  # no final selection: 20 replays under the run's noise


def checkpoint(path: Path) -> dict:
    with gzip.open(path, "rt") as f:
        return json.load(f)


@pytest.mark.slow
@pytest.mark.subprocess
def test_a_sigkilled_run_resumes_in_a_new_process_to_the_same_run(tmp_path):
    """Killed after generation 2 or later, resumed from its newest checkpoint by a new process: the
    rows, the champion (its trained weights) and the last checkpoint are the uninterrupted run's."""
    raw = {**TINY, "generations": 5, "checkpoint_every": 1}
    cfg = tmp_path / "ga.yaml"
    cfg.write_text(yaml.safe_dump(raw))
    crashed = RunDir(tmp_path / "crashed")
    proc = sgr("evolve", "--config", str(cfg), "--out", str(crashed.path), "--quiet")
    kill_when(proc, crashed, 2)
    with Experiment.create(str(cfg), str(tmp_path / "full"), {}, quiet=True) as full:  # the reference
        full.run_all()
    resume_from = load_checkpoint(crashed)["generation"]
    assert 1 <= resume_from < 5
    resumed = sgr("evolve", "--resume", str(crashed.path), "--quiet")
    _, err = resumed.communicate(timeout=300)
    assert resumed.returncode == 0, err
    ref = RunDir(tmp_path / "full")
    assert rows(crashed) == rows(ref) and len(crashed.rows()) == 5
    mine, theirs = crashed.champion(), ref.champion()
    assert mine["controller"] == theirs["controller"] and mine["fitness"] == theirs["fitness"]
    assert checkpoint(crashed.checkpoints()[0]) == checkpoint(ref.checkpoints()[0])


def test_a_bad_ppo_key_is_one_line(tmp_path):
    cfg = tmp_path / "bad.yaml"
    cfg.write_text(yaml.safe_dump({**TINY, "ppo": {"timestep": 100}}))
    rc, err = run_cli("evolve", "--config", str(cfg), "--out", str(tmp_path / "run"), cwd=tmp_path)
    one_error(rc, err, "key 'ppo': unknown key 'timestep'; known keys: timesteps")
    assert not (tmp_path / "run").exists()


@pytest.mark.slow
@pytest.mark.subprocess
def test_without_torch_the_method_says_what_to_install(tmp_path):
    code = ("import sys\nsys.modules['torch'] = None\nfrom evolve.cli import main\n"
            "sys.exit(main(['evolve', '--method', 'ga-ppo', '--task', 'Walker-v0', '--out', 'run']))\n")
    r = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True,
                       timeout=300,
                       env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin", "HOME": str(tmp_path)})
    one_error(r.returncode, r.stderr, "method 'ga-ppo' trains with PPO and needs torch",
              "pip install 'sgr[rl]'")


def test_sgr_decode_refuses_a_ga_ppo_run_in_one_line(tiny, capsys):
    """Its champion has no genome to draw a body at another size."""
    line = in_process(capsys, "decode", str(tiny.path), "--shape", "7x7")
    assert "a ga-ppo run's champion is a body and a controller trained for it" in line
