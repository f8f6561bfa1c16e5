"""The Ray sweep backend: each run of a sweep is a Ray task that advances the run's directory (on a
filesystem every node shares) with `sgr evolve --resume` on whichever node has room.

A sweep stopped by Ctrl-C or SIGTERM stops its runs as the local backend does: it cancels their
tasks without force (Ray raises KeyboardInterrupt in each task), each task passes the stop on to
its run's process (SIGUSR1, evolve/runs/stops.py) and waits while the run ends its generation with a
checkpoint. A second Ctrl-C or SIGTERM while the sweep waits cancels with force: the tasks' workers
are killed, and the runs' processes with them, each keeping its last checkpoint.

Ray's cancel is best effort: in tests/evolve/sweeps/test_ray_nodes.py a run went on to its end
after the sweep's stop, a few times in some dozens (its task, it seems, began as the cancel came,
which lost it). So the sweep also marks the stop in a file of its folder (`.stop-<token>`, on the
filesystem the nodes share, made and removed by this sweep's process), which each task looks for
before it starts its run and while it waits.

A node that is lost takes its runs' processes with it; their tasks fail, and `run_sweep` resumes
each run from its own checkpoints on a node that is left. A cluster that goes away altogether (its
head unreachable, or no node with a CPU left) for CLUSTER_LOST_S stops the sweep with one line that
names the resume command; every run keeps its last checkpoint.
"""

from __future__ import annotations

import contextlib
import os
import secrets
import socket
import subprocess
import time
from pathlib import Path

from evolve.own_modules import child_env, python_command
from evolve.rollout.ray_cluster import connect
from evolve.runs.stops import PASSED_ON
from evolve.sweeps.sweep import BackendLost, open_log, run_process_setup, trust_flag
from tsim.errors import SgrError

CLUSTER_LOST_S = 10.0  # the cluster unusable this long: the sweep stops
HEALTH_EVERY_S = 1.0
WAIT_TURN_S = 0.2  # a run's task looks for a cancel this often


STOPPED = 128 + PASSED_ON  # a run's exit code when its sweep stopped it (evolve/runs/stops.py)


def _run_on_node(run_path: str, workers: int, flags: tuple[str, ...] = (),
                 stop_file: str | None = None) -> int:
    """A Ray task: advance one run to its end in a subprocess on this node; its exit code. Cancelled
    without force, or finding `stop_file` (the sweep stops), it lets the run end its generation with
    a checkpoint first; finding it before the run started, it starts nothing (STOPPED)."""
    if stop_file is not None and os.path.lexists(stop_file):
        return STOPPED
    env = child_env()  # -P (python_command) and sgr's folder first: no file of the working folder is imported
    proc = None
    try:
        log = open_log(Path(run_path) / "log.txt")  # never through a link (SgrError: the task fails)
        try:
            # the run dies with this worker (a task cancelled with force, a sweep killed): no run goes on
            # alone; a stop passed on while it starts waits for its loop (run_process_setup)
            proc = subprocess.Popen(python_command("evolve.cli", "evolve", "--resume", run_path,
                                                   "--workers", str(workers), "--quiet", *flags),
                                    stdout=log, stderr=subprocess.STDOUT, env=env,
                                    preexec_fn=run_process_setup)
        finally:
            os.close(log)
        return _wait(proc, stop_file)
    except KeyboardInterrupt:  # ray.cancel(force=False): the sweep stops
        if proc is None:
            raise
        proc.send_signal(PASSED_ON)  # as LocalBackend.stop: the run ends its generation, checkpoints, exits
        while True:  # however long its generation takes; a force cancel kills this worker, and the run
            try:
                return proc.wait()
            except KeyboardInterrupt:
                continue


def _wait(proc: subprocess.Popen, stop_file: str | None = None) -> int:
    """proc's exit code. Ray's KeyboardInterrupt (a cancel) reaches only Python code, not a process
    blocked in waitpid: wait in short turns, in each of which `stop_file`, once it exists, passes
    the sweep's stop on to the run (once)."""
    passed = False
    while True:
        try:
            return proc.wait(timeout=WAIT_TURN_S)
        except subprocess.TimeoutExpired:
            if not passed and stop_file is not None and os.path.lexists(stop_file):
                proc.send_signal(PASSED_ON)
                passed = True


class RayBackend:
    """Runs as Ray tasks: `parallel` runs at once on each node, each with the node's CPUs / parallel
    (of the smallest node) rollout workers; `address` joins a running cluster ("auto": the one
    `ray start` made on this machine), without it a local Ray instance starts."""

    def __init__(self, parallel: int = 1, address: str | None = None):
        ray = connect("--backend ray", address, start="local")
        self.resume_args = " --backend ray" + (f" --address {address}" if address else "")
        self._gcs = ray.get_runtime_context().gcs_address  # host:port of the cluster's head
        self._checked = time.monotonic()
        self._unwell_since: float | None = None
        nodes = [n["Resources"].get("CPU", 0) for n in ray.nodes() if n["Alive"]]
        nodes = [int(c) for c in nodes if c >= 1] or [1]
        self.cpus_per_run = max(1, min(nodes) // parallel)
        self.parallel = sum(max(1, c // self.cpus_per_run) for c in nodes)
        # no retries by Ray: a failed task ends with an exit code and run_sweep resumes the run (its
        # retries counted the same with either backend, and every failure said in the sweep's output)
        self._task = ray.remote(_run_on_node).options(num_cpus=self.cpus_per_run, max_retries=0)
        self.procs: dict = {}  # SweepRun -> ObjectRef of its task
        self._logs: dict = {}  # SweepRun -> its log.txt
        self._stop_file: Path | None = None  # the sweep folder's stop mark for this process's tasks

    def start(self, sweep, run) -> None:
        """Submit `run` (already prepared) as one Ray task and return at once; `poll` reports its
        end."""
        self._wait_for_cluster()  # a task submitted to a cluster that is gone could wait for ever
        path = sweep.run_dir(run).path.resolve()  # the same path on every node
        self._logs[run] = path / "log.txt"
        if self._stop_file is None:  # a name no earlier sweep process used: a mark left by one is never read
            self._stop_file = sweep.path.resolve() / f".stop-{secrets.token_hex(8)}"
        self.procs[run] = self._task.remote(str(path), self.cpus_per_run, tuple(trust_flag(sweep)),
                                            str(self._stop_file))

    def poll(self) -> dict:
        """Runs that ended since the last call, with their exit codes (-1: the task failed; why is
        appended to the run's log.txt)."""
        import ray

        if not self.procs:
            return {}
        self._check_cluster()
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

    def _check_cluster(self) -> None:
        """BackendLost once the head has been unreachable, or no live node has had a CPU, for
        CLUSTER_LOST_S (checked every HEALTH_EVERY_S); the head is probed by a plain TCP connection
        first, as Ray's own calls would wait for it."""
        now = time.monotonic()
        if now - self._checked < HEALTH_EVERY_S:
            return
        self._checked = now
        problem = self._cluster_problem()
        if problem is None:
            self._unwell_since = None
            return
        if self._unwell_since is None:
            self._unwell_since = now
        if now - self._unwell_since >= CLUSTER_LOST_S:
            raise BackendLost(f"the Ray cluster is gone ({problem} for {CLUSTER_LOST_S:.0f} s)")

    def _wait_for_cluster(self) -> None:
        """Return once the cluster is usable; BackendLost when it has not been for CLUSTER_LOST_S."""
        while (problem := self._cluster_problem()) is not None:
            now = time.monotonic()
            self._unwell_since = self._unwell_since or now
            if now - self._unwell_since >= CLUSTER_LOST_S:
                raise BackendLost(f"the Ray cluster is gone ({problem} for {CLUSTER_LOST_S:.0f} s)")
            time.sleep(HEALTH_EVERY_S)
        self._unwell_since = None

    def _cluster_problem(self) -> str | None:
        import ray

        host, _, port = self._gcs.rpartition(":")
        try:
            socket.create_connection((host, int(port)), timeout=2.0).close()
        except OSError:
            return f"its head at {self._gcs} does not answer"
        if not any(n["Alive"] and n["Resources"].get("CPU", 0) >= 1 for n in ray.nodes()):
            return "no node with a CPU is left"
        return None

    def _log(self, run, exc: Exception) -> None:
        what = " ".join(str(exc).split())[:2000]
        try:
            fd = open_log(self._logs[run])  # never through a link
        except (OSError, SgrError):
            return
        with os.fdopen(fd, "a") as f:
            f.write(f"\nsgr sweep: the run's Ray task failed: {type(exc).__name__}: {what}\n")

    def stop(self) -> None:
        """Ask every running run to stop and wait, as LocalBackend.stop: each task is cancelled
        without force and passes the stop on to its run, which ends its generation and writes a
        checkpoint. A second Ctrl-C or SIGTERM while waiting cancels with force: the tasks' workers
        are killed, and each run's process with its worker, each run keeping its last checkpoint.
        Nothing to do once the cluster is lost; lost while waiting, the wait ends."""
        import ray

        refs = list(self.procs.values())
        self.procs = {}
        if self._unwell_since is not None or not refs:
            return
        marked = self._mark_stop()
        for ref in refs:
            ray.cancel(ref, force=False)
        try:
            # the cluster watched meanwhile; a signal comes in the sleep, not in Ray's wait, which would
            # turn the handler's `Interrupted` (SIGTERM: exit 143) into a plain KeyboardInterrupt
            while refs:
                _, refs = ray.wait(refs, num_returns=len(refs), timeout=0)
                self._check_cluster()
                if refs:
                    time.sleep(WAIT_TURN_S)
        except BackendLost:
            return
        except KeyboardInterrupt:
            for ref in refs:
                ray.cancel(ref, force=True)
            ray.wait(refs, num_returns=len(refs), timeout=30)
            raise
        finally:
            if marked:
                with contextlib.suppress(OSError):
                    os.unlink(self._stop_file)

    def _mark_stop(self) -> bool:
        """Make the stop mark the tasks look for (a new empty file, never through a link); whether
        it was made (if not, Ray's cancel alone passes the stop on)."""
        try:  # (set by `start`: a sweep with tasks to stop has started one)
            os.close(os.open(self._stop_file, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW
                             | os.O_CLOEXEC, 0o644))
        except OSError:
            return False
        return True
