"""Robust evaluation (evolve/rollout/robust.py): K perturbed episodes per genome in one batch.

What must hold: with K = 1 and no noise a run is today's run bit for bit; the noise of an episode
is a pure function of (run seed, tag, episode), so results do not depend on the batch, the worker
count or a SIGKILL and resume; champion.json says how the fitness was scored, and that record alone
scores it again exactly; the noise has the asked-for distribution.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

from evolve.nn.dense import DenseController
from evolve.records.replay import champion_gif, replay_champion, rescore_champion
from evolve.records.rundir import RunDir
from evolve.rollout.episodes import dense_policy
from evolve.rollout.pool import RolloutPool
from evolve.rollout.robust import EpisodeNoise, Perturbation, Robust, episode_keys, unit_uniform
from evolve.runs.experiment import Experiment
from tasks.env import BatchEnv, obs_dim
from tsim.body import build_body
from tsim.sampling import sample_robot

ROBUST = {"episodes": 3, "action_noise": "uniform", "action_scale": 1e-2, "offset": 0.01,
          "statistic": "q25"}
# the cheap design (#33): one fresh episode a generation, a survivor's scores averaged, the top raced
FAST = {"episodes": 1, "action_noise": "uniform", "action_scale": 1e-2, "offset": 0.0, "statistic": "mean",
        "reevaluate": True, "accumulate": True, "race": 4}
# the packaged configs' design (settle8), settling after 2 scores so that short runs show it
SETTLE = {"episodes": 1, "action_noise": "uniform", "action_scale": 1e-2, "offset": 0.0, "statistic": "mean",
          "reevaluate": True, "accumulate": True, "settle": 2}
COLUMNS = ["generation", "best", "mean", "median", "n_species", "n_valid", "n_invalid", "episodes"]
NESTED = {"pop_size": 6, "inner_pop_size": 6, "inner_generations": 1}


def config(method: str, **changes) -> dict:
    return {"method": method, "task": "Walker-v0", "generations": 3, "pop_size": 12, "seed": 5,
            "episode_steps": 30, "render_champion": False, "workers": 1, "robust": None,
            "final_selection": None, **(NESTED if method == "nested" else {}), **changes}


def run(tmp: Path, name: str, cfg: dict) -> RunDir:
    exp = Experiment.from_config(cfg, tmp / name, quiet=True)
    exp.run_all()
    exp.close()
    return exp.run


def rows(run_dir: RunDir) -> list[list[str]]:
    return [[r[c] for c in COLUMNS] for r in run_dir.rows()]


def test_one_episode_without_noise_is_the_nominal_run_bit_for_bit(tmp_path):
    nominal = run(tmp_path, "nominal", config("sgr"))
    one = run(tmp_path, "one", config("sgr", robust={"episodes": 1, "action_noise": "none"}))
    assert rows(one) == rows(nominal)
    a, b = nominal.champion(), one.champion()
    assert a["fitness"] == b["fitness"] and a["body"] == b["body"] and a["controller"] == b["controller"]
    assert b["evaluation"]["robust"]["episodes"] == 1 and a["evaluation"]["robust"] is None


@pytest.mark.slow
@pytest.mark.subprocess
# direct in `pytest -m long`: sgr and nested (a method with inner searches) stay; the rollout that
# adds the noise is the same for every method (test_episode_noise_follows_the_episode_...)
@pytest.mark.parametrize("method", ["sgr", pytest.param("direct", marks=pytest.mark.long), "nested"])
def test_robust_runs_do_not_depend_on_the_worker_count_and_their_champion_rescores_exactly(
        tmp_path, method):
    one = run(tmp_path, "w1", config(method, robust=ROBUST))
    two = run(tmp_path, "w2", config(method, robust=ROBUST, workers=2))
    assert rows(one) == rows(two)
    champ = one.champion()
    assert champ == two.champion()
    assert champ["evaluation"]["robust"] == {**ROBUST, "reevaluate": False}
    assert rescore_champion(one.path) == champ["fitness"]  # the K episodes again, from the JSON alone
    nominal = replay_champion(one.path)[0]
    assert nominal != champ["fitness"]  # scored under noise, not by the exact episode
    # each generation simulated K episodes per evaluated genome
    for r in one.rows():
        assert int(r["episodes"]) % ROBUST["episodes"] == 0 and int(r["episodes"]) > 0


@pytest.mark.slow
@pytest.mark.subprocess
# k3 and accumulate-race in `pytest -m long`: the packaged design (accumulate-settle) stays in the
# suite, and the worker-count tests below hold those two evaluations' runs exact
@pytest.mark.parametrize("robust", [pytest.param(ROBUST, marks=pytest.mark.long),
                                    pytest.param(FAST, marks=pytest.mark.long), SETTLE],
                         ids=["k3", "accumulate-race", "accumulate-settle"])
def test_a_sigkilled_robust_run_resumes_in_a_new_process_on_two_workers_to_the_same_run(tmp_path, robust):
    cfg = config("sgr", robust=robust, generations=8, pop_size=24, checkpoint_every=2)
    (tmp_path / "c.yaml").write_text(yaml.safe_dump({**cfg, "neat_config": None}))
    crashed = RunDir(tmp_path / "crashed")
    env = {**os.environ, "PYTHONHASHSEED": "random"}
    proc = subprocess.Popen([sys.executable, "-m", "evolve.cli", "evolve", "--config",
                             str(tmp_path / "c.yaml"), "--out", str(crashed.path), "--quiet"],
                            env=env, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while len(crashed.rows()) < 5:
        assert proc.poll() is None, proc.stderr.read()
        assert time.monotonic() < deadline
        time.sleep(0.002)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    resumed = subprocess.run([sys.executable, "-m", "evolve.cli", "evolve", "--resume", str(crashed.path),
                              "--workers", "2", "--quiet"], env=env, capture_output=True, text=True,
                             timeout=300)
    assert resumed.returncode == 0, resumed.stderr
    full = run(tmp_path, "full", cfg)
    assert len(crashed.rows()) == 8 and rows(crashed) == rows(full)
    assert crashed.champion() == full.champion()


@pytest.mark.slow
@pytest.mark.subprocess
def test_with_reevaluate_elites_are_simulated_again_with_fresh_noise_and_the_run_stays_exact(tmp_path):
    cfg = config("sgr", robust={**ROBUST, "reevaluate": True}, generations=4)
    once = run(tmp_path, "a", cfg)
    again = run(tmp_path, "b", {**cfg, "workers": 2})
    assert rows(once) == rows(again)
    keep = run(tmp_path, "keep", config("sgr", robust=ROBUST, generations=4))
    k = ROBUST["episodes"]
    for r, rk in zip(once.rows(), keep.rows(), strict=True):  # every valid genome, every generation
        assert int(r["episodes"]) == k * int(r["n_valid"])
        if int(r["generation"]) > 1:  # without: elites keep their score, fewer episodes
            assert int(rk["episodes"]) < k * int(rk["n_valid"])
    assert rescore_champion(once.path) == once.champion()["fitness"]


@pytest.mark.parametrize("method", ["sgr", pytest.param("direct", marks=pytest.mark.long)])  # as above
def test_accumulated_runs_do_not_depend_on_the_worker_count_and_their_champion_rescores_exactly(
        tmp_path, method):
    """One fresh episode per genome and generation, a survivor's fitness the mean of all its scores,
    the 4 best raced: the same run on 1 or 2 workers, and champion.json's list of evaluations alone
    gives its fitness again, bit for bit (the mean over generations, summed in order)."""
    cfg = config(method, robust=FAST, generations=5)
    one = run(tmp_path, "w1", cfg)
    two = run(tmp_path, "w2", {**cfg, "workers": 2})
    assert rows(one) == rows(two)
    champ = one.champion()
    assert champ == two.champion()
    tags = champ["evaluation"]["tags"]
    assert champ["evaluation"]["robust"] == FAST and "tag" not in champ["evaluation"]
    assert rescore_champion(one.path) == champ["fitness"]
    for r in one.rows():  # every valid genome once, plus the raced four
        assert int(r["episodes"]) == int(r["n_valid"]) + min(4, int(r["n_valid"]))
    assert any(t.endswith("/race") for t in tags)


def test_settled_runs_do_not_depend_on_the_worker_count_and_spend_fewer_episodes(tmp_path):
    """The packaged design (accumulate + settle): the same run on 1 or 2 workers, the champion's
    fitness rescored bit for bit from champion.json, and genomes with `settle` scores not simulated
    again (a later generation spends fewer episodes than it has valid genomes)."""
    cfg = config("sgr", robust=SETTLE, generations=6)
    one = run(tmp_path, "w1", cfg)
    two = run(tmp_path, "w2", {**cfg, "workers": 2})
    assert rows(one) == rows(two)
    champ = one.champion()
    assert champ == two.champion()
    assert rescore_champion(one.path) == champ["fitness"]
    assert len(champ["evaluation"]["tags"]) <= SETTLE["settle"]
    assert any(int(r["episodes"]) < int(r["n_valid"]) for r in one.rows()[2:])


def test_nested_neat_refuses_accumulated_fitness_in_one_line(tmp_path, capsys):
    from evolve.cli import main
    (tmp_path / "c.yaml").write_text(yaml.safe_dump(config("nested", robust=FAST)))
    assert main(["evolve", "--config", str(tmp_path / "c.yaml"), "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert "key 'robust.accumulate' is not for method 'nested'" in err and err.count("\n") == 1, err


@pytest.mark.slow
@pytest.mark.subprocess
def test_episode_noise_follows_the_episode_not_its_slot_in_the_batch_or_the_worker():
    rng = np.random.default_rng(1)
    bodies = [sample_robot((5, 5), rng) for _ in range(5)]
    ctrls = []
    for body in bodies:
        b = build_body(body)
        n_in = obs_dim("Walker-v0", b.n_points)
        k = int(np.ceil(np.sqrt(n_in)))
        ctrls.append(DenseController([rng.normal(0, 1, (k * k, 25)), rng.normal(0, 1, (25, 25))],
                                     [rng.normal(0, 0.5, 25), rng.normal(0, 0.5, 25)], ["tanh", "tanh"],
                                     n_in, np.asarray(b.actuator_flat, dtype=np.int64)))
    keys = episode_keys(7, [f"g/{i}" for i in range(5)], 0)
    noise = EpisodeNoise(Perturbation("gaussian", 1e-2, 0.02), keys, np.array([1, 1, 0, 1, 1], bool))
    order = [3, 0, 4, 1, 2]
    with RolloutPool(1) as one, RolloutPool(2) as two:
        base = one.run("Walker-v0", bodies, ctrls, dense_policy, 25, noise)
        split = two.run("Walker-v0", bodies, ctrls, dense_policy, 25, noise)
        shuffled = one.run("Walker-v0", [bodies[i] for i in order], [ctrls[i] for i in order],
                           dense_policy, 25, noise.take(order))
        nominal = one.run("Walker-v0", bodies, ctrls, dense_policy, 25)
    assert np.array_equal(base, split) and np.array_equal(base[order], shuffled)
    assert base[2] == nominal[2]  # its row is off: the exact episode
    assert np.all(base[[0, 1, 3, 4]] != nominal[[0, 1, 3, 4]])


def test_noise_has_the_asked_for_distribution_and_keys_are_independent():
    keys = episode_keys(0, [str(i) for i in range(4000)], 0)
    assert len(set(keys.tolist())) == 4000
    u = unit_uniform(keys, 0, 3, 25)
    assert u.min() >= 0 and u.max() < 1
    assert abs(u.mean() - 0.5) < 0.005 and abs(u.var() - 1 / 12) < 0.002  # 1e5 draws: ~1e-3 sd
    assert abs(np.corrcoef(u[:, 0], u[:, 1])[0, 1]) < 0.05
    assert abs(np.corrcoef(u.ravel(), unit_uniform(keys, 0, 4, 25).ravel())[0, 1]) < 0.02  # next step
    a = Perturbation("uniform", 0.5).actions(keys, 3, 25)
    assert np.abs(a).max() <= 0.5 and np.abs(a).max() > 0.49
    g = Perturbation("gaussian", 0.5).actions(keys, 3, 25)
    assert abs(g.mean()) < 0.01 and abs(g.std() - 0.5) < 0.01
    assert abs(np.mean(np.abs(g) < 0.5) - 0.6827) < 0.01  # one sd holds 68.27 % of a normal
    s = Perturbation("none", 0.0, 0.1).shifts(keys)
    assert np.abs(s).max() <= 0.1 and abs(s.mean()) < 0.005
    assert Perturbation("none", 0.5).actions(keys, 3, 25) is None
    # the same key, step and column always give the same number
    assert np.array_equal(unit_uniform(keys[5:9], 0, 3, 25), u[5:9])


@pytest.mark.parametrize("statistic, expected", [
    ("mean", [2.0, 5.0]), ("min", [1.0, -1.0]), ("median", [2.0, 7.0]), ("q25", [1.5, 3.0]),
    ("q0", [1.0, -1.0]), ("q100", [3.0, 9.0])])
def test_scores_are_the_statistic_over_the_episodes(statistic, expected):
    returns = np.array([[1.0, 9.0], [3.0, -1.0], [2.0, 7.0]])  # 3 episodes of 2 genomes
    r = Robust.from_config({"episodes": 3, "statistic": statistic})
    assert r.score(returns).tolist() == expected


@pytest.mark.parametrize("statistic", ["mean", "min", "median", "q25"])
def test_a_genome_scored_alone_gets_the_bits_of_its_column_in_a_batch(statistic):
    """A champion is scored again alone (`rescore_champion`); evolution scored it in a batch."""
    rng = np.random.default_rng(3)
    r = Robust.from_config({"episodes": 32, "statistic": statistic})
    for k in (4, 12, 32, 100):
        returns = rng.normal(5.0, 3.0, size=(k, 16))
        batch = r.score(returns)
        assert [r.score(returns[:, [i]])[0] for i in range(16)] == batch.tolist()


def test_a_robot_shift_moves_the_robot_alone():
    body = np.array([[3, 3, 3], [3, 0, 3], [3, 0, 3]])
    plain = BatchEnv("Carrier-v0", [body, body])
    shifted = BatchEnv("Carrier-v0", [body, body], robot_shift=[0.0, 0.03])
    n = plain.n_points[0]
    assert np.array_equal(plain.sim.state[0], shifted.sim.state[0])
    d = shifted.sim.state[1, :, 0] - plain.sim.state[1, :, 0]
    assert np.allclose(d[:n], 0.03, atol=1e-15) and np.all(d[n:] == 0.0)  # the package stays
    assert np.array_equal(shifted.sim.state[1, :, 1], plain.sim.state[1, :, 1])


@pytest.mark.parametrize("robust, message", [
    ({"episodes": 0}, "key 'robust.episodes' must be an int from 1 to 100,000"),
    ({"action_noise": "pink"}, "key 'robust.action_noise' must be one of none, uniform, gaussian"),
    ({"action_scale": -1}, "key 'robust.action_scale' must be a number >= 0"),
    ({"statistic": "q250"}, "key 'robust.statistic' must be one of mean, min, median, qNN"),
    ({"episode": 4}, "key 'robust': unknown key 'episode'"),
    ({"reevaluate": "yes"}, "key 'robust.reevaluate' must be true or false"),
    ({"accumulate": True}, "key 'robust.accumulate' needs reevaluate: true"),
    ({"reevaluate": True, "race": 3}, "key 'robust.race' needs accumulate: true"),
    ({"reevaluate": True, "settle": 3}, "key 'robust.settle' needs accumulate: true"),
    ({"reevaluate": True, "accumulate": True, "race": -1}, "key 'robust.race' must be an int >= 0"),
    ([4], "key 'robust' must be dict or null"),
])
def test_a_bad_robust_key_is_one_error_line_naming_it(tmp_path, capsys, robust, message):
    from evolve.cli import main

    (tmp_path / "c.yaml").write_text(yaml.safe_dump(config("sgr", robust=robust)))
    assert main(["evolve", "--config", str(tmp_path / "c.yaml"), "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("sgr: error:") and message in err and err.count("\n") == 1, err
    assert not (tmp_path / "r").exists()


def test_render_shows_the_nominal_episode_or_a_perturbed_replay(tmp_path):
    import imageio.v3 as iio

    rd = run(tmp_path, "r", config("sgr", robust=ROBUST, generations=1))
    a = iio.imread(champion_gif(rd.path, tmp_path / "a.gif", width=160, height=80))
    again = iio.imread(champion_gif(rd.path, tmp_path / "b.gif", width=160, height=80))
    moved = iio.imread(champion_gif(rd.path, tmp_path / "c.gif", width=160, height=80, replay=1,
                                    eps=0.3, offset=0.05))
    assert np.array_equal(a, again)
    assert a.shape[0] == moved.shape[0] and not np.array_equal(a, moved)
    assert json.loads((rd.path / "champion.json").read_text())["evaluation"]["tag"]
