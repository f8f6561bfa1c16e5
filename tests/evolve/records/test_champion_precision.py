"""Reading a champion never changes the process: its precision is an argument handed to the
simulator its replays build, not an environment variable set behind the caller's back (issue 46).
A champion of the other precision than the process's default is loaded and replayed in a fresh
process, which ends with the environment it started with and the replays' returns as recorded."""

import json
import os
import shutil
import subprocess
import sys

import pytest
import yaml

from evolve.records.replay import load_champion
from tsim.backend import runtime
from tsim.errors import SgrError

REPLAY = """
import json, os, sys
before = dict(os.environ)
from tsim.backend import runtime
from evolve.records.replay import judge, load_champion, replay_champion, rescore_champion
champ = load_champion(sys.argv[1])
after_load = dict(os.environ) == before
rescored = rescore_champion(sys.argv[1])
rollout = champ.rollout()
returns = replay_champion(sys.argv[1], 2, 1e-3).tolist()
judge(sys.argv[1], 2)
print(json.dumps({"fitness": champ.fitness, "rescored": rescored, "rollout": rollout, "returns": returns,
                  "precision": runtime.precision(), "after_load": after_load,
                  "changed": sorted(k for k in {**before, **os.environ}
                                    if before.get(k) != os.environ.get(k))}))
"""


@pytest.mark.slow
@pytest.mark.subprocess
def test_loading_and_replaying_an_f32_champion_leaves_the_environment_as_it_was(tmp_path, repo_root):
    cfg = {"method": "sgr", "task": "Walker-v0", "generations": 1, "pop_size": 4, "episode_steps": 20,
           "render_champion": False, "workers": 1, "precision": "f32", "robust": None,
           "final_selection": None, "neat_config": str(repo_root / "configs/neat/sgr.ini")}
    (tmp_path / "f32.yaml").write_text(yaml.safe_dump(cfg))
    env = {k: v for k, v in os.environ.items() if k not in ("SGR_ARCH", "SGR_PRECISION")}
    r = subprocess.run([sys.executable, "-m", "evolve.cli", "evolve", "--config", "f32.yaml", "--out", "run",
                        "--quiet"], cwd=tmp_path, env={**env, "SGR_THREADS": "1"}, capture_output=True,
                       text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    out = subprocess.run([sys.executable, "-c", REPLAY, str(tmp_path / "run")], env=env,
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got["after_load"] and got["changed"] == [], got["changed"]  # no SGR_PRECISION set
    assert "SGR_PRECISION" not in env
    assert got["precision"] == "f32"  # the replays simulated in the champion's precision ...
    # ... to the recorded fitness: the batched rescoring, gymnasium's episode and replay 0 alike
    assert got["rescored"] == got["fitness"] == got["rollout"] == got["returns"][0], got


def test_a_process_in_the_other_precision_refuses_the_champion_and_sets_nothing(tmp_path, repo_root):
    """This (test) process simulates in f64: an f32 champion is refused in one line naming the key,
    and reading it set no environment variable."""
    runtime.init()  # started (f64, the tests' default) as any process that has simulated
    if runtime.precision() != "f64":
        pytest.skip("the tests run in f32 here")
    run = tmp_path / "run"
    shutil.copytree(repo_root / "tests/data/champions/sgr-Walker-v0-paper-s0", run)
    record = json.loads((run / "champion.json").read_text())
    (run / "champion.json").write_text(json.dumps({**record, "precision": "f32"}))
    before = dict(os.environ)
    with pytest.raises(SgrError, match="key 'precision': scored in f32, to be replayed in it: Taichi already "
                                       "runs in f64"):
        load_champion(run)
    assert dict(os.environ) == before
    (run / "champion.json").write_text(json.dumps({**record, "precision": "f16"}))
    with pytest.raises(SgrError, match="key 'precision': unknown precision 'f16'"):
        load_champion(run)
    assert dict(os.environ) == before
