"""A real multi-node Ray cluster (`ray.cluster_utils.Cluster`: a head without CPUs and two worker
nodes, each a raylet with its own CPU and resource) loses machines, and the results do not change:
(a) a sweep on it gives the local backend's results; (b) a worker node removed while the sweep runs:
its run resumes on the other node from its checkpoints and equals the local sweep's; (c) `workers:
ray` within one run: a node removed mid-generation, its chunk is simulated again on the other node
and the run is unchanged; (c) a sweep given SIGTERM: each run ends the generation under way with a
checkpoint and the resumed sweep equals an uninterrupted one, and a second SIGTERM kills the runs at
once; (d) the whole cluster goes away: the sweep stops with one line naming the resume command.
Tests run in this order and share one cluster (the last one shuts it down)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
import yaml

ray = pytest.importorskip("ray")
from ray.cluster_utils import Cluster  # noqa: E402

from evolve.records.rundir import RunDir  # noqa: E402
from evolve.rollout.ray_cluster import RayRolloutPool  # noqa: E402
from evolve.runs.experiment import Experiment  # noqa: E402
from evolve.sweeps.ray_sweep import RayBackend  # noqa: E402
from evolve.sweeps.sweep import LocalBackend, Sweep, run_sweep  # noqa: E402

pytestmark = [pytest.mark.slow, pytest.mark.subprocess, pytest.mark.ray]

FITNESS = ["generation", "best", "mean", "median", "n_species", "n_valid", "n_invalid", "episodes"]
GENERATIONS = 8
SWEEP = {"methods": ["sgr", "nested"], "tasks": ["Walker-v0"], "seeds": 1,
         "overrides": {"robust": None, "final_selection": None,  # nominal
                       "generations": GENERATIONS, "pop_size": 8, "episode_steps": 10, "checkpoint_every": 1,
                       "render_champion": False,
                       "nested": {"pop_size": 4, "inner_pop_size": 4, "inner_generations": 1}}}
FAST_FAILURE_DETECTION = {"health_check_period_ms": 200, "health_check_failure_threshold": 5,
                          "health_check_initial_delay_ms": 0}


def _worker_node(cluster: Cluster, name: str):
    return cluster.add_node(num_cpus=1, resources={name: 1})


@pytest.fixture(scope="module")
def cluster():
    c = Cluster(initialize_head=True,
                head_node_args={"num_cpus": 0, "_system_config": FAST_FAILURE_DETECTION})
    _worker_node(c, "node_a")
    _worker_node(c, "node_b")
    c.wait_for_nodes()
    ray.init(address=c.address, log_to_driver=False)
    yield c
    if ray.is_initialized():
        ray.shutdown()
    c.shutdown()


def fitness(run_path) -> list[tuple]:
    return [tuple(r[k] for k in FITNESS) for r in RunDir(run_path).rows()]


def sweep_file(tmp_path: Path) -> Path:
    f = tmp_path / "sweep.yaml"
    f.write_text(yaml.safe_dump(SWEEP))
    return f


_LOCAL: dict = {}


def local_results(tmp_path_factory) -> dict:
    """The local backend's results of SWEEP (computed once)."""
    if not _LOCAL:
        tmp = tmp_path_factory.mktemp("local")
        sweep = Sweep.create(sweep_file(tmp), tmp / "sweep")
        assert run_sweep(sweep, LocalBackend(2), quiet=True) == 0
        _LOCAL.update({run.name: fitness(sweep.run_dir(run).path) for run in sweep.runs})
        assert all(len(rows) == GENERATIONS for rows in _LOCAL.values())
    return _LOCAL


def _ppid(pid: int) -> int:
    return int(Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[1])


def _running(pid: int) -> bool:
    """Whether process `pid` exists and is not a zombie."""
    try:
        return "zombie" not in Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False


def node_of(cluster: Cluster, pid: int):
    """The cluster node whose raylet started process `pid` (its ancestor)."""
    raylets = {p.process.pid: node for node in cluster.worker_nodes
               for p in node.all_processes["raylet"]}
    while pid > 1:
        if pid in raylets:
            return raylets[pid]
        pid = _ppid(pid)
    raise AssertionError("process not started by a worker node")


def lose(cluster: Cluster, node) -> None:
    """The machine goes: every process its raylet started (Ray workers, the runs they started) is
    SIGKILLed, then the node itself. (Removing only the raylet leaves its workers to notice later,
    and a run's process goes on meanwhile, which a lost machine's would not.)"""
    raylets = {p.process.pid for p in node.all_processes["raylet"]}
    doomed = []
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            pid = int(d.name)
            try:
                while pid > 1 and pid not in raylets:
                    pid = _ppid(pid)
            except (OSError, IndexError):
                continue
            if pid in raylets and int(d.name) not in raylets:
                doomed.append(int(d.name))
    for pid in doomed:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    cluster.remove_node(node, allow_graceful=False)


def test_a_the_clusters_nodes_are_separate_raylets_with_their_own_resources(cluster):
    nodes = [n for n in ray.nodes() if n["Alive"]]
    assert len(nodes) == 3
    assert sorted(n["Resources"].get("CPU", 0) for n in nodes) == [0, 1, 1]
    assert {"node_a", "node_b"} <= set(ray.cluster_resources())
    assert len({p.process.pid for n in cluster.worker_nodes for p in n.all_processes["raylet"]}) == 2


@pytest.mark.long  # (b) compares a sweep on the cluster with the local one too
def test_a_a_sweep_on_the_cluster_gives_the_local_backends_results(cluster, tmp_path, tmp_path_factory):
    backend = RayBackend(1)
    assert (backend.parallel, backend.cpus_per_run) == (2, 1)  # one run on each worker node
    sweep = Sweep.create(sweep_file(tmp_path), tmp_path / "sweep")
    assert run_sweep(sweep, backend, quiet=True) == 0
    results = {run.name: fitness(sweep.run_dir(run).path) for run in sweep.runs}
    assert results == local_results(tmp_path_factory)


def test_b_a_node_removed_while_the_sweep_runs_its_run_resumes_on_the_other_node(cluster, tmp_path,
                                                                                 tmp_path_factory):
    local = local_results(tmp_path_factory)
    sweep = Sweep.create(sweep_file(tmp_path), tmp_path / "sweep")
    backend = RayBackend(1)
    result: dict = {}
    t = threading.Thread(target=lambda: result.update(failed=run_sweep(sweep, backend, quiet=True)))
    t.start()
    victim, deadline = None, time.monotonic() + 180
    while victim is None:  # a run part-way, its process (the run's lock holder) on a node we remove
        assert time.monotonic() < deadline and t.is_alive(), "no run was caught part-way"
        for run in sweep.runs:
            rd = sweep.run_dir(run)
            if 2 <= len(rd.rows()) <= GENERATIONS - 3 and (rd.path / ".lock").is_file():
                pid = (rd.path / ".lock").read_text().strip()
                if pid.isdigit() and Path(f"/proc/{pid}").exists():
                    victim = run, rd, node_of(cluster, int(pid)), len(rd.rows())
                    break
        time.sleep(0.01)
    run, rd, node, _ = victim
    lose(cluster, node)
    rows_then = len(rd.rows())
    t.join(300)
    assert not t.is_alive() and result["failed"] == 0
    assert {r.name: fitness(sweep.run_dir(r).path) for r in sweep.runs} == local
    log = (rd.path / "log.txt").read_text()
    assert "the run's Ray task failed" in log
    starts = [int(line.rsplit(" ", 1)[1]) for line in log.splitlines() if line.startswith("resuming ")]
    assert starts[0] == 0 and len(starts) == 2 and 1 <= starts[1] <= rows_then, log  # from a checkpoint
    _worker_node(cluster, "node_c")  # two worker nodes again for the next test
    cluster.wait_for_nodes()


@pytest.mark.long  # shorter: rollout/test_ray_cluster.py's actor killed mid-generation
def test_c_workers_ray_a_node_removed_mid_generation_is_simulated_elsewhere_unchanged(
        cluster, tmp_path, shipped_config):
    cfg = shipped_config("sgr", generations=3, pop_size=8, episode_steps=10, render_champion=False)
    exp = Experiment.create(str(cfg), str(tmp_path / "local"), {"workers": 1}, quiet=True)
    exp.run_all()
    exp.close()
    exp = Experiment.create(str(cfg), str(tmp_path / "ray"), {"workers": "ray"}, quiet=True)
    pool = exp.pool
    seen: dict = {}
    try:
        assert isinstance(pool, RayRolloutPool)
        before = pool.pids()  # one actor on each worker node
        nodes = [node_of(cluster, pid) for pid in before]
        assert len(before) == 2 and nodes[0] is not nodes[1]
        run, calls, in_run = pool.run, [], threading.Event()

        def run_and_watch(*args, **kwargs):
            calls.append(1)
            if len(calls) == 1:  # generation 0: each actor now compiles the simulator (> 1 s)
                in_run.set()
            try:
                return run(*args, **kwargs)
            finally:
                if len(calls) == 1:
                    seen["returned"] = time.monotonic()

        def remove_a_node():
            if in_run.wait(300):
                time.sleep(0.3)
                lose(cluster, nodes[0])
                seen["removed"] = time.monotonic()

        pool.run = run_and_watch
        remover = threading.Thread(target=remove_a_node, daemon=True)
        remover.start()
        exp.run_all()
        remover.join(30)
        after = pool.pids()
    finally:
        exp.close()
    assert seen["removed"] < seen["returned"], "the node was removed after its chunk"
    assert after == [before[1]]  # no free CPU left for a new actor: the pool goes on with one
    assert fitness(tmp_path / "ray") == fitness(tmp_path / "local")
    _worker_node(cluster, "node_d")
    cluster.wait_for_nodes()


def _ray_sweep_past_a_generation(cluster, tmp_path: Path, episode_steps: int):
    """A `--backend ray` sweep of two alike 6-generation runs (episodes of `episode_steps`, no
    checkpoint due) started on the cluster and waited for until a run has ended a generation: its
    spec, folder, process, the runs' RunDirs and their row counts then."""
    spec = tmp_path / "sweep.yaml"
    spec.write_text(yaml.safe_dump({**SWEEP, "methods": ["sgr"], "seeds": 2, "overrides": {
        **SWEEP["overrides"], "generations": 6, "episode_steps": episode_steps, "checkpoint_every": 1000}}))
    out = tmp_path / "sweep"
    proc = subprocess.Popen([sys.executable, "-m", "evolve.cli", "sweep", "--config", str(spec), "--out",
                             str(out), "--backend", "ray", "--address", cluster.address, "--quiet"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    runs = [RunDir(out / "runs" / f"sgr-Walker-v0-s{seed}") for seed in (0, 1)]
    deadline = time.monotonic() + 180
    while not any((r.path / "generations.csv").is_file() and len(r.rows()) >= 1 for r in runs):
        assert time.monotonic() < deadline and proc.poll() is None, proc.communicate()
        time.sleep(0.01)
    before = [len(r.rows()) if (r.path / "generations.csv").is_file() else 0 for r in runs]
    return spec, out, proc, runs, before


@pytest.mark.long  # shorter: sweeps/test_sweep.py's Ray task stop, runs/test_stops.py's sweep stop
def test_c_a_sigterm_to_a_ray_sweep_lets_each_run_checkpoint_its_generation_and_the_sweep_resumes(
        cluster, tmp_path):
    """SIGTERM to a `--backend ray` sweep (on the cluster, one run on each worker node) once a run
    has ended a generation: each run's task passes the stop on, so a run ends the generation under
    way and writes its checkpoint there (none is due: checkpoint_every 1000; a killed task would
    leave generation 0's), the sweep exits 143 with the resume command, and the resumed sweep equals
    an uninterrupted local one. (The other run may not have begun its generations yet, its
    simulator still compiling, or even its program starting: it then ends with nothing lost.)"""
    # two alike runs, generations of about a second, no checkpoint due
    spec, out, proc, runs, before = _ray_sweep_past_a_generation(cluster, tmp_path, episode_steps=1000)
    proc.send_signal(signal.SIGTERM)
    stdout, err = proc.communicate(timeout=180)
    assert proc.returncode == 143, stdout + err
    assert "interrupted by SIGTERM; continue with: sgr sweep --resume" in stdout
    for run, rows in zip(runs, before, strict=True):
        n = len(run.rows()) if (run.path / "generations.csv").is_file() else 0
        assert rows <= n < 6, run.path.name
        assert run.last_checkpoint_generation() == n, run.path.name  # the stop's: the generation ended
        if rows:
            log = (run.path / "log.txt").read_text()
            assert "asked by the sweep: stopping after this generation, with a checkpoint" in log
            assert f"stopped after generation {n} of 6, with a checkpoint" in log
        pid = (run.path / ".lock").read_text().strip() if (run.path / ".lock").is_file() else ""
        assert not pid or not Path(f"/proc/{pid}").exists()  # the run's process ended, waited for
    assert max(before) >= 1

    assert run_sweep(Sweep.open(out), RayBackend(1), quiet=True) == 0
    whole = Sweep.create(spec, tmp_path / "whole")
    assert run_sweep(whole, LocalBackend(2), quiet=True) == 0
    for run in runs:
        assert fitness(run.path) == fitness(whole.path / "runs" / run.path.name), run.path.name
        assert len(fitness(run.path)) == 6


@pytest.mark.long
def test_c_a_second_sigterm_to_a_ray_sweep_kills_its_runs_at_once_at_their_last_checkpoint(cluster, tmp_path):
    """SIGTERM, then SIGTERM again 0.3 s later, early in a generation of seconds: the sweep cancels
    its tasks with force, so the runs' processes die with their workers without ending the
    generation (no row, no checkpoint for it: the last is generation 0's, or the last finished
    generation's where a run's process had the stop passed on first), and the sweep exits 143."""
    # generations of seconds (long episodes)
    spec, out, proc, runs, before = _ray_sweep_past_a_generation(cluster, tmp_path, episode_steps=4000)
    proc.send_signal(signal.SIGTERM)
    time.sleep(0.3)
    proc.send_signal(signal.SIGTERM)
    stdout, err = proc.communicate(timeout=60)
    assert proc.returncode == 143, stdout + err
    assert "interrupted by SIGTERM; continue with: sgr sweep --resume" in stdout
    for run, rows in zip(runs, before, strict=True):
        if rows:
            assert len(run.rows()) == rows, run.path.name  # the generation under way did not end
            # killed outright: generation 0's; or its process had the stop passed on first and,
            # stopping at once, wrote its last finished generation's checkpoint (docs/RELIABILITY.md)
            assert run.last_checkpoint_generation() in (0, rows), run.path.name
        pid = (run.path / ".lock").read_text().strip() if (run.path / ".lock").is_file() else ""
        deadline = time.monotonic() + 10
        while pid and _running(int(pid)):
            assert time.monotonic() < deadline, f"{run.path.name}: its process outlived the sweep"
            time.sleep(0.05)


@pytest.mark.long
def test_d_a_sweep_whose_cluster_goes_away_stops_with_one_line_naming_the_resume_command(cluster, tmp_path):
    ray.shutdown()  # this process leaves the cluster before it goes
    out, address = tmp_path / "sweep", cluster.address
    proc = subprocess.Popen([sys.executable, "-m", "evolve.cli", "sweep", "--config",
                             str(sweep_file(tmp_path)), "--out", str(out), "--backend", "ray",
                             "--address", address, "--quiet"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 180
    while not any(len(RunDir(d).rows()) >= 1 for d in (out / "runs").glob("*")):
        assert time.monotonic() < deadline and proc.poll() is None, proc.communicate()
        time.sleep(0.05)
    cluster.shutdown()
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 2, err
    ours = err.splitlines()
    assert len(ours) == 1 and ours[0].startswith("sgr: error: the Ray cluster is gone"), err
    resume = f"sgr sweep --resume {out} --backend ray --address {address}"
    assert ours[0].endswith(f"continue with: {resume}"), err
    assert all(RunDir(d).has_checkpoint() for d in (out / "runs").glob("*"))
