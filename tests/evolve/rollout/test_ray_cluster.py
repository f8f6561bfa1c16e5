"""Ray on one local instance (2 CPUs) for the module: the sweep backend's sizing and failed tasks, and
one run's rollouts on Ray actors, which give exactly the results of local processes, also when an
actor is killed mid-generation. Losing whole nodes: tests/evolve/sweeps/test_ray_nodes.py."""

from __future__ import annotations

import os
import signal
import threading
import time

import pytest
import yaml

ray = pytest.importorskip("ray")

from evolve.rollout.ray_cluster import RayRolloutPool  # noqa: E402
from evolve.runs.experiment import Experiment  # noqa: E402
from evolve.sweeps.ray_sweep import RayBackend  # noqa: E402
from evolve.sweeps.sweep import Sweep  # noqa: E402

pytestmark = [pytest.mark.slow, pytest.mark.subprocess, pytest.mark.ray]

FITNESS = ["generation", "best", "mean", "median", "n_species", "n_valid", "n_invalid", "episodes"]


@pytest.fixture(scope="module", autouse=True)
def local_ray():
    ray.init(address="local", num_cpus=2, include_dashboard=False, log_to_driver=False)
    yield
    if ray.is_initialized():
        ray.shutdown()


def fitness(run_path) -> list[tuple]:
    from evolve.records.rundir import RunDir

    rows = RunDir(run_path).rows()
    return [tuple(r[k] for k in FITNESS) for r in rows]


# ---------------------------------------------------------------------------------- sweep backend
# (a sweep's results on Ray against the local backend's: tests/evolve/sweeps/test_ray_nodes.py, on a
# real multi-node cluster)
def test_ray_backend_sizes_runs_by_the_nodes_cpus_and_reports_failed_tasks(tmp_path):
    one = RayBackend(1)
    assert (one.parallel, one.cpus_per_run) == (1, 2)
    two = RayBackend(2)
    assert (two.parallel, two.cpus_per_run) == (2, 1)
    sweep = Sweep.create(_write(tmp_path / "s.yaml", {"methods": ["sgr"], "tasks": ["Walker-v0"],
                                                       "seeds": 1}), tmp_path / "sw")
    run = sweep.runs[0]
    sweep.run_dir(run).path.mkdir(parents=True)  # no config: `sgr evolve --resume` fails
    two.start(sweep, run)
    ended = {}
    for _ in range(600):
        ended = two.poll()
        if ended:
            break
        time.sleep(0.1)
    assert ended[run] != 0 and not two.procs
    assert "not a run directory" in (sweep.run_dir(run).path / "log.txt").read_text()


def _write(path, data):
    path.write_text(yaml.safe_dump(data))
    return path


# ---------------------------------------------------------------------------------- rollout pool
def _config(shipped_config, method: str):
    nested = {"pop_size": 4, "inner_pop_size": 4, "inner_generations": 1} if method == "nested" else {}
    return shipped_config(method, **{"generations": 3, "pop_size": 8, "episode_steps": 10,
                                     "render_champion": False, **nested})


def _run(config, out, workers, during=None) -> list[tuple]:
    exp = Experiment.create(str(config), str(out), {"workers": workers}, quiet=True)
    try:
        if during:
            during(exp)
        exp.run_all()
    finally:
        exp.close()
    return fitness(out)


_LOCAL: dict[str, list[tuple]] = {}


def _local(tmp_path, shipped_config, method):
    if method not in _LOCAL:
        _LOCAL[method] = _run(_config(shipped_config, method), tmp_path / f"{method}-w1", 1)
    return _LOCAL[method]


# direct and nested in `pytest -m long`: Ray's actors run the rollout jobs the local pool runs,
# whatever the method; tests/evolve/rollout/test_pool.py holds every method's runs equal on one
# or two worker processes
@pytest.mark.parametrize("method", ["sgr", pytest.param("direct", marks=pytest.mark.long),
                                    pytest.param("nested", marks=pytest.mark.long)])
def test_workers_ray_gives_the_results_of_one_local_worker(tmp_path, shipped_config, method):
    on_ray = _run(_config(shipped_config, method), tmp_path / "ray", "ray")
    assert on_ray == _local(tmp_path, shipped_config, method)
    assert len(on_ray) == 3


def test_an_actor_killed_mid_generation_is_replaced_and_the_run_unchanged(tmp_path, shipped_config):
    exp = Experiment.create(str(_config(shipped_config, "sgr")), str(tmp_path / "ray"),
                            {"workers": "ray"}, quiet=True)
    pool = exp.pool
    try:
        assert isinstance(pool, RayRolloutPool)
        before = pool.pids()  # starts the actors
        assert len(before) == 2
        run, calls, in_run, seen = pool.run, [], threading.Event(), {}

        def run_and_watch(*args, **kwargs):
            calls.append(1)
            if len(calls) == 1:  # generation 0: each actor now compiles the simulator (> 1 s)
                in_run.set()
            try:
                return run(*args, **kwargs)
            finally:
                if len(calls) == 1:
                    seen["returned"] = time.monotonic()

        def kill_one_actor():
            if in_run.wait(300):
                time.sleep(0.2)
                os.kill(before[0], signal.SIGKILL)
                seen["killed"] = time.monotonic()

        pool.run = run_and_watch
        killer = threading.Thread(target=kill_one_actor, daemon=True)
        killer.start()
        exp.run_all()
        killer.join(5)
        after = pool.pids()
    finally:
        exp.close()
    assert seen["killed"] < seen["returned"], "the actor was killed after its chunk"
    assert after[0] != before[0] and after[1] == before[1]  # replaced; the other one kept
    assert fitness(tmp_path / "ray") == _local(tmp_path, shipped_config, "sgr")


def test_workers_ray_starts_ray_when_none_runs_and_stops_it_after(tmp_path, shipped_config, monkeypatch):
    """`sgr evolve --workers ray` outside a cluster: the pool starts a local Ray in the middle of
    generation 0, which must not change the run (Ray's start-up draws from Python's `random`)."""
    ray.shutdown()  # the module's Ray: the last test of the module
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    rows = _run(_config(shipped_config, "sgr"), tmp_path / "ray", "ray")
    assert not ray.is_initialized()
    assert rows == _local(tmp_path, shipped_config, "sgr")
