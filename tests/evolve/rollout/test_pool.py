"""Rollouts split over worker processes give the same returns as one in-process batch."""

from __future__ import annotations

import numpy as np
import pytest

from evolve.nn.dense import DenseController
from evolve.rollout.episodes import dense_policy
from evolve.rollout.pool import RolloutPool, balanced_chunks, resolve_workers
from tasks.env import obs_dim
from tsim.body import build_body
from tsim.sampling import sample_robot


def _random_dense(body: np.ndarray, rng: np.random.Generator) -> DenseController:
    b = build_body(body)
    n_in = obs_dim("Walker-v0", b.n_points)
    k = int(np.ceil(np.sqrt(n_in)))
    return DenseController([rng.normal(0, 1, (k * k, 25)), rng.normal(0, 1, (25, 25))],
                           [rng.normal(0, 0.5, 25), rng.normal(0, 0.5, 25)], ["tanh", "tanh"],
                           n_in, np.asarray(b.actuator_flat, dtype=np.int64))


def _local_policy():
    """A factory that pickles here but that worker processes cannot import (its module exists only
    in this process)."""
    import sys
    import types

    mod = types.ModuleType("sgr_module_of_this_process_only")

    def policy(env, items):
        return dense_policy(env, items)

    policy.__module__, policy.__qualname__, mod.policy = mod.__name__, "policy", policy
    sys.modules[mod.__name__] = mod
    return policy


def test_chunks_cover_every_robot_once_and_balance_the_voxel_load():
    rng = np.random.default_rng(3)
    costs = list(rng.integers(3, 26, size=37).astype(float))
    for n in (1, 2, 3, 8, 50):
        chunks = balanced_chunks(costs, n)
        assert len(chunks) == min(n, len(costs))
        assert sorted(i for c in chunks for i in c) == list(range(len(costs)))
        assert all(c == sorted(c) for c in chunks)
        loads = [sum(costs[i] for i in c) for c in chunks]
        assert max(loads) - min(loads) <= max(costs)
        assert balanced_chunks(costs, n) == chunks  # depends on the costs only


@pytest.mark.slow
@pytest.mark.subprocess
def test_two_worker_processes_return_exactly_the_in_process_returns():
    rng = np.random.default_rng(0)
    bodies = [sample_robot((5, 5), rng) for _ in range(7)]
    ctrls = [_random_dense(b, rng) for b in bodies]
    local = RolloutPool(1).run("Walker-v0", bodies, ctrls, dense_policy, 40)
    with RolloutPool(2) as pool:
        split = pool.run("Walker-v0", bodies, ctrls, dense_policy, 40)
        again = pool.run("Walker-v0", bodies[:3], ctrls[:3], dense_policy, 40)  # workers persist
    assert np.array_equal(split, local)
    assert np.array_equal(again, local[:3])
    assert np.any(local != 0.0)


@pytest.mark.slow
@pytest.mark.subprocess
def test_errors_in_a_worker_are_raised_in_the_caller_and_the_pool_survives():
    rng = np.random.default_rng(1)
    bodies = [sample_robot((5, 5), rng) for _ in range(4)]
    ctrls = [_random_dense(b, rng) for b in bodies]
    broken = [b.copy() for b in bodies]
    broken[3][:] = 0  # no voxels: the worker's BatchEnv refuses it
    with RolloutPool(2) as pool:
        with pytest.raises(ValueError, match="bad body matrix: all voxels are empty"):
            pool.run("Walker-v0", broken, ctrls, dense_policy, 5)
        with pytest.raises(RuntimeError, match="could not load its job"):
            pool.run("Walker-v0", bodies, ctrls, _local_policy(), 5)
        assert pool.run("Walker-v0", bodies, ctrls, dense_policy, 5).shape == (4,)


@pytest.mark.slow
@pytest.mark.subprocess
def test_a_worker_killed_mid_generation_is_started_again_with_the_same_results(capsys):
    import os
    import signal
    import threading
    import time

    rng = np.random.default_rng(2)
    bodies = [sample_robot((5, 5), rng) for _ in range(6)]
    ctrls = [_random_dense(b, rng) for b in bodies]
    local = RolloutPool(1).run("Walker-v0", bodies, ctrls, dense_policy, 60)
    with RolloutPool(2) as pool:
        killed = []

        def kill_first_worker():  # SIGKILL by PID while the generation is under way
            while not pool._procs:
                time.sleep(0.001)
            killed.append(pool._procs[0].pid)
            os.kill(killed[0], signal.SIGKILL)

        t = threading.Thread(target=kill_first_worker)
        t.start()
        split = pool.run("Walker-v0", bodies, ctrls, dense_policy, 60)
        t.join()
        assert pool._procs[0].pid != killed[0]
    assert np.array_equal(split, local)
    err = capsys.readouterr().err
    assert f"rollout worker process {killed[0]} died (exit code -9); starting it again" in err


def test_worker_counts_are_checked():
    assert resolve_workers("auto") >= 1
    assert resolve_workers(3) == 3
    for bad in (0, -2, "many", 1.5, True):
        with pytest.raises(ValueError, match="workers must be a positive int or 'auto'"):
            resolve_workers(bad)


@pytest.mark.slow
@pytest.mark.subprocess
@pytest.mark.parametrize("method", ["sgr", "direct", "nested"])
def test_runs_give_the_same_results_with_one_or_two_worker_processes(tmp_path, shipped_config, method):
    from evolve.runs.experiment import Experiment

    nested = {"inner_pop_size": 4, "inner_generations": 1} if method == "nested" else {}
    p = shipped_config(method, generations=2, pop_size=8, episode_steps=30, render_champion=False,
                       **nested)
    rows = {}
    for workers in (1, 2):
        exp = Experiment.create(str(p), str(tmp_path / f"w{workers}"), {"workers": workers}, quiet=True)
        try:
            exp.run_all()
        finally:
            exp.close()
        rows[workers] = [(r["best"], r["mean"], r["median"], r["n_valid"]) for r in exp.run.rows()]
    assert rows[1] == rows[2]
    assert len(rows[1]) == 2


@pytest.mark.slow
@pytest.mark.subprocess
def test_an_experiment_left_open_at_exit_stops_its_workers_without_a_traceback(tmp_path):
    """At interpreter exit `RolloutPool.__del__` ran after subprocess's globals were gone and printed
    'Exception ignored ... TypeError: catching classes that do not inherit from BaseException'."""
    import subprocess
    import sys

    script = ("from evolve import Experiment\n"
              "cfg = {'method': 'sgr', 'task': 'Walker-v0', 'generations': 1, 'pop_size': 4,\n"
              "       'episode_steps': 5, 'workers': 2, 'render_champion': False}\n"
              f"exp = Experiment.from_config(cfg, {str(tmp_path / 'r')!r}, quiet=True)\n"
              "exp.run_all()\n")
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    assert "Exception ignored" not in run.stderr and "Traceback" not in run.stderr, run.stderr[-2000:]
