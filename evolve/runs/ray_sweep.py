"""The Ray sweep backend: each run of a sweep is a Ray task that advances the run's directory (on a
filesystem every node shares) with `sgr evolve --resume` on whichever node has room."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from evolve.rollout.ray_cluster import connect
from evolve.runs.sweep import die_with_parent


def _run_on_node(run_path: str, workers: int) -> int:
    """A Ray task: advance one run to its end in a subprocess on this node; its exit code."""
    root = str(Path(__file__).resolve().parents[2])
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in (root, os.environ.get("PYTHONPATH")) if p)}
    with open(Path(run_path) / "log.txt", "ab") as log:
        # the run dies with this worker (a cancelled task, a sweep that stopped): no run goes on alone
        proc = subprocess.Popen([sys.executable, "-m", "evolve.cli", "evolve", "--resume", run_path,
                                 "--workers", str(workers), "--quiet"],
                                stdout=log, stderr=subprocess.STDOUT, env=env, preexec_fn=die_with_parent)
    return proc.wait()


class RayBackend:
    """Runs as Ray tasks: `parallel` runs at once on each node, each with the node's CPUs / parallel
    (of the smallest node) rollout workers; `address` joins a running cluster ("auto": the one
    `ray start` made on this machine), without it a local Ray instance starts."""

    def __init__(self, parallel: int = 1, address: str | None = None):
        ray = connect("--backend ray", address, start="local")
        nodes = [n["Resources"].get("CPU", 0) for n in ray.nodes() if n["Alive"]]
        nodes = [int(c) for c in nodes if c >= 1] or [1]
        self.cpus_per_run = max(1, min(nodes) // parallel)
        self.parallel = sum(max(1, c // self.cpus_per_run) for c in nodes)
        # no retries by Ray: a failed task ends with an exit code and run_sweep resumes the run (its
        # retries counted the same with either backend, and every failure said in the sweep's output)
        self._task = ray.remote(_run_on_node).options(num_cpus=self.cpus_per_run, max_retries=0)
        self.procs: dict = {}  # SweepRun -> ObjectRef of its task
        self._logs: dict = {}  # SweepRun -> its log.txt

    def start(self, sweep, run) -> None:
        """Submit `run` (already prepared) as one Ray task and return at once; `poll` reports its
        end."""
        path = sweep.run_dir(run).path.resolve()  # the same path on every node
        self._logs[run] = path / "log.txt"
        self.procs[run] = self._task.remote(str(path), self.cpus_per_run)

    def poll(self) -> dict:
        """Runs that ended since the last call, with their exit codes (-1: the task failed; why is
        appended to the run's log.txt)."""
        import ray

        if not self.procs:
            return {}
        refs = {ref: run for run, ref in self.procs.items()}
        ready, _ = ray.wait(list(refs), num_returns=len(refs), timeout=0)
        ended = {}
        for ref in ready:
            run = refs[ref]
            try:
                ended[run] = int(ray.get(ref))
            except Exception as exc:  # the worker or its node died, the task was cancelled
                ended[run] = -1
                self._log(run, exc)
            del self.procs[run]
        return ended

    def _log(self, run, exc: Exception) -> None:
        what = " ".join(str(exc).split())[:2000]
        try:
            with open(self._logs[run], "a") as f:
                f.write(f"\nsgr sweep: the run's Ray task failed: {type(exc).__name__}: {what}\n")
        except OSError:
            pass

    def stop(self) -> None:
        """Cancel the running tasks: their workers are killed, and each run's process with its
        worker; every run keeps its last checkpoint."""
        import ray

        for ref in self.procs.values():
            ray.cancel(ref, force=True)
        if self.procs:
            ray.wait(list(self.procs.values()), num_returns=len(self.procs), timeout=30)
        self.procs = {}
