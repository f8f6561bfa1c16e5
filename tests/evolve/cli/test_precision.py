"""`--precision` on `sgr evolve`, `sgr bench` and `sgr validate`, and $SGR_PRECISION honoured by them:
the commands run (in subprocesses: a process's precision is fixed when Taichi starts) in the real
type asked for, and a run records it."""

import json
import os
import subprocess
import sys

import pytest
import yaml

pytestmark = [pytest.mark.slow, pytest.mark.subprocess]


def run_cli(*args, cwd, env=None) -> subprocess.CompletedProcess:
    base = {k: v for k, v in os.environ.items() if k not in ("SGR_ARCH", "SGR_PRECISION")}
    return subprocess.run([sys.executable, "-m", "evolve.cli", *args], cwd=cwd, capture_output=True,
                          text=True, env={**base, "SGR_THREADS": "1", **(env or {})}, timeout=300)


def test_bench_runs_in_the_precision_of_its_flag_or_of_sgr_precision(tmp_path):
    r = run_cli("bench", "--robots", "2", "--steps", "2", "--json", "--precision", "f32", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout.strip().splitlines()[-1])["precision"] == "f32"
    r = run_cli("bench", "--robots", "2", "--steps", "2", "--json", cwd=tmp_path,
                env={"SGR_PRECISION": "f32"})
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout.strip().splitlines()[-1])["precision"] == "f32"


def test_evolve_records_the_precision_it_ran_in(tmp_path, repo_root):
    cfg = {"method": "sgr", "task": "Walker-v0", "generations": 1, "pop_size": 4, "episode_steps": 2,
           "render_champion": False, "workers": 1, "robust": None, "final_selection": None,
           "neat_config": str(repo_root / "configs/neat/sgr.ini")}
    (tmp_path / "tiny.yaml").write_text(yaml.safe_dump(cfg))
    r = run_cli("evolve", "--config", "tiny.yaml", "--out", "run", "--precision", "f32", "--quiet",
                cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert yaml.safe_load((tmp_path / "run/config.yaml").read_text())["precision"] == "f32"


REPLAY = """
import json, sys
from tsim.backend import runtime
if sys.argv[2] == "f64-first":
    runtime.init(precision="f64")
from evolve.records.replay import load_champion, rescore_champion
try:
    champ = load_champion(sys.argv[1])
except ValueError as exc:
    print(json.dumps({"error": str(exc)}))
    raise SystemExit(0)
print(json.dumps({"fitness": champ.fitness, "rescored": rescore_champion(sys.argv[1]),
                  "rollout": champ.rollout(), "precision": runtime.precision()}))
"""


def test_an_f32_champion_replays_exactly_in_f32_and_is_refused_in_an_f64_process(tmp_path, repo_root):
    """The champion of an f32 run records its precision; a new process replays it in f32 to its
    recorded fitness (batched rescoring and gymnasium rollout alike), and a process already in f64
    gets one line saying why it cannot."""
    cfg = {"method": "sgr", "task": "Walker-v0", "generations": 1, "pop_size": 4, "episode_steps": 20,
           "render_champion": False, "workers": 1, "precision": "f32", "robust": None,
           "final_selection": None, "neat_config": str(repo_root / "configs/neat/sgr.ini")}
    (tmp_path / "f32.yaml").write_text(yaml.safe_dump(cfg))
    r = run_cli("evolve", "--config", "f32.yaml", "--out", "run", "--quiet", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert json.loads((tmp_path / "run/champion.json").read_text())["precision"] == "f32"
    env = {k: v for k, v in os.environ.items() if k not in ("SGR_ARCH", "SGR_PRECISION")}
    out = subprocess.run([sys.executable, "-c", REPLAY, str(tmp_path / "run"), "fresh"], env=env,
                         capture_output=True, text=True, timeout=300)
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got["precision"] == "f32"
    assert got["rescored"] == got["fitness"] and got["rollout"] == got["fitness"], got
    out = subprocess.run([sys.executable, "-c", REPLAY, str(tmp_path / "run"), "f64-first"], env=env,
                         capture_output=True, text=True, timeout=300)
    err = json.loads(out.stdout.strip().splitlines()[-1])["error"]
    assert "key 'precision': scored in f32" in err and "already runs in f64" in err
