"""Episodes split over worker processes, each running one single-threaded Taichi.

Why processes and not Taichi's threads: a generation is 500 short kernel launches (one per env
step), and between launches the controllers and observations run in Python. With threads, every
launch ends in a barrier and the Python part runs on one core; measured on 2 vCPUs, 2 threads gave
1.5x and 2 processes (each with half the robots and its own step loop, no barrier between them)
gave 1.9x.

A batch is split into `workers` chunks balanced by voxel count; the split depends only on the
bodies, so a run's results do not depend on scheduling. Each chunk is simulated as its own batch.
The physics of a world does not depend on its batch; observations and controllers are padded to
the batch's widest robot, which tests show leaves the returns unchanged (see
tests/evolve/rollout/test_pool.py).
"""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
from collections.abc import Callable, Sequence
from contextlib import AbstractContextManager, nullcontext

import numpy as np

from evolve.own_modules import child_env, python_command
from evolve.rollout.episodes import BatchPolicy
from evolve.rollout.robust import EpisodeNoise
from evolve.rollout.worker import read_frame, run_chunk, spec_blob, write_frame
from tasks.behaviour import FEATURES
from tasks.env import BatchEnv
from tsim.backend import runtime
from tsim.errors import SgrError

# factory(env, items) -> batched policy for the robots of env; items[i] drives robot i. With
# workers > 1 it is pickled: a module-level function or a functools.partial of one.
PolicyFactory = Callable[[BatchEnv, Sequence], BatchPolicy]


MAX_WORKERS = 4096  # more rollout processes on one machine is a typo (or a planted value)


def workers_problem(workers: object) -> str | None:
    """What is wrong with a `workers` value (the config key, --workers, `RolloutPool`), or None: a
    positive int (at most MAX_WORKERS), 'auto' or 'ray'. The one place the rule is written."""
    if workers in ("auto", "ray") or type(workers) is int and 1 <= workers <= MAX_WORKERS:
        return None
    if type(workers) is int and workers > MAX_WORKERS:
        return f"must be at most {MAX_WORKERS:,} processes, got {workers:,}"
    return f"must be a positive int, 'auto' or 'ray', got {repr(workers)[:80]}"


def resolve_workers(workers: int | str) -> int:
    """'auto' -> the CPUs this process may use; an int is taken as is (>= 1)."""
    if workers == "auto":
        try:
            return max(1, len(os.sched_getaffinity(0)))
        except AttributeError:  # not on Linux
            return max(1, os.cpu_count() or 1)
    if workers == "ray" or workers_problem(workers) is not None:  # (Ray's actors: RayRolloutPool)
        raise SgrError(f"workers must be a positive int or 'auto', got {workers!r}")
    return workers


def balanced_chunks(costs: Sequence[float], n: int) -> list[list[int]]:
    """Split indices into at most n chunks of similar total cost (largest first onto the lightest
    chunk, ties to the lower chunk); each chunk lists its indices in ascending order."""
    n = max(1, min(n, len(costs)))
    loads = [0.0] * n
    chunks: list[list[int]] = [[] for _ in range(n)]
    for i in sorted(range(len(costs)), key=lambda i: (-costs[i], i)):
        c = min(range(n), key=lambda c: (loads[c], c))
        chunks[c].append(i)
        loads[c] += costs[i]
    return [sorted(c) for c in chunks if c]


def chunk_job(task: str, bodies: Sequence[np.ndarray], items: Sequence, factory: PolicyFactory,
              episode_steps: int | str | None, noise: EpisodeNoise | None, chunk: list[int],
              record: bool = False) -> tuple:
    """`run_chunk`'s arguments for the robots `chunk` of a batch (what a worker is sent); a task
    registered in this process's code travels with the job (`evolve.rollout.worker.spec_blob`)."""
    return (task, [bodies[i] for i in chunk], [items[i] for i in chunk], factory, episode_steps,
            None if noise is None else noise.take(chunk), spec_blob(task), record)


class WorkerDied(RuntimeError):
    """A rollout worker process died twice on the same chunk."""


class BasePool:
    """What every rollout pool shares: `run` (check, split into balanced chunks, gather the returns
    in input order). A pool says how many chunks it takes at once (`_width`) and simulates jobs
    (`_run_jobs`); a width of 1 with `_runs_here` simulates in this process, without a job."""

    _runs_here = False  # whether a width of 1 means "in this process" (local pools)

    def run(self, task: str, bodies: Sequence[np.ndarray], items: Sequence, factory: PolicyFactory,
            episode_steps: int | str | None = None, noise: EpisodeNoise | None = None,
            record: bool = False) -> np.ndarray:
        """Episode return of each body driven by its item (`factory(env, items)` builds the policy),
        in input order, each episode perturbed by its row of `noise` (if any); an exception raised
        where a chunk was simulated is raised here. `record`: (n, 1 + len(FEATURES)), each return
        then its behaviour features (tasks/behaviour.py)."""
        if len(bodies) != len(items):
            raise ValueError(f"{len(bodies)} bodies but {len(items)} policy items")
        if len(bodies) == 0:
            return np.zeros(0)
        with self._session():
            width = self._width()
            if width == 1 and self._runs_here:
                return run_chunk(task, list(bodies), list(items), factory, episode_steps, noise, None, record)
            chunks = balanced_chunks([float(np.count_nonzero(b)) for b in bodies], width)
            jobs = [chunk_job(task, bodies, items, factory, episode_steps, noise, c, record) for c in chunks]
            out = np.zeros((len(bodies), 1 + len(FEATURES)) if record else len(bodies))
            for c, returns in zip(chunks, self._run_jobs(jobs), strict=True):
                out[c] = returns
            return out

    def _session(self) -> AbstractContextManager:
        """What surrounds one `run` (nothing here; Ray keeps Python's `random` as it was)."""
        return nullcontext()

    def _width(self) -> int:
        """How many chunks a batch is split into."""
        raise NotImplementedError

    def _run_jobs(self, jobs: list[tuple]) -> list[np.ndarray]:
        """The returns of each job (`chunk_job`), in order."""
        raise NotImplementedError

    def close(self) -> None:
        """Let go of what the pool started."""

    def __enter__(self) -> BasePool:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class RolloutPool(BasePool):
    """Episode returns of (body, policy item) pairs, in this process (workers=1) or split over
    persistent worker processes (`python -m evolve.rollout`), started on first use; WorkerDied
    when a worker dies twice on a chunk.

    Workers are plain subprocesses fed pickles over pipes rather than a multiprocessing pool: a
    spawned multiprocessing child re-imports the caller's main module, which breaks scripts and
    notebooks that lack an `if __name__ == "__main__"` guard.
    """

    _runs_here = True

    def __init__(self, workers: int | str = 1):
        self.workers = resolve_workers(workers)
        self._procs: list[subprocess.Popen] = []

    def _width(self) -> int:
        return self.workers

    def _run_jobs(self, jobs: list[tuple]) -> list[np.ndarray]:
        for proc, job in zip(self._start(len(jobs)), jobs, strict=True):
            self._send(proc, job)
        out: list = []
        failure = None
        for i, job in enumerate(jobs):  # every reply, even after a failure
            ok, value = self._reply(i, job)
            out.append(value if ok else None)
            if not ok and failure is None:
                failure = value
        if failure is not None:
            raise failure
        return out

    def _reply(self, i: int, job: tuple) -> tuple[bool, object]:
        """Worker i's reply to `job` (already sent). A worker that died (killed by the OOM killer,
        say) is started again and given its job once more: a chunk's returns depend on the job
        alone, so the generation's results are the same."""
        for attempt in range(2):
            proc = self._procs[i]
            try:
                return pickle.loads(read_frame(proc.stdout))
            except (EOFError, OSError, pickle.UnpicklingError):
                if attempt == 1:
                    raise self._died(proc) from None
                print(f"sgr: warning: rollout worker process {proc.pid} died (exit code {proc.wait()}); "
                      "starting it again", file=sys.stderr)
                proc.stdout.close()
                self._procs[i] = self._spawn()
                self._send(self._procs[i], job)
        raise AssertionError("unreachable")

    def _start(self, n: int) -> list[subprocess.Popen]:
        """The first n workers, starting those not running yet."""
        while len(self._procs) < n:
            self._procs.append(self._spawn())
        return self._procs[:n]

    def _spawn(self) -> subprocess.Popen:
        # -P and sgr's folder first: a tasks.py in the working folder is never imported there
        # one Taichi thread per worker process, simulating in this process's precision (passed to it)
        env = child_env(SGR_THREADS="1", SGR_PRECISION=runtime.precision())
        return subprocess.Popen(python_command("evolve.rollout"), stdin=subprocess.PIPE,
                                stdout=subprocess.PIPE, env=env)

    def _send(self, proc: subprocess.Popen, job: tuple) -> None:
        try:
            write_frame(proc.stdin, job)
        except BrokenPipeError:  # a dead worker: reading its reply finds out and starts it again
            pass

    def _died(self, proc: subprocess.Popen) -> WorkerDied:
        """Stop the pool and describe the worker that died (its traceback went to stderr)."""
        self.close()
        return WorkerDied(f"rollout worker process {proc.pid} died (exit code {proc.poll()}); "
                            "its error is above; set workers: 1 to run in this process")

    def close(self) -> None:
        """Stop the workers: end of input makes each one exit."""
        for proc in self._procs:
            try:
                proc.stdin.close()
            except OSError:
                pass
        for proc in self._procs:
            try:
                proc.wait(timeout=5)  # idle workers exit at once; a busy one is killed
            except self._timeout:
                proc.kill()
                proc.wait()
            proc.stdout.close()
        self._procs = []

    # held by the class: at interpreter exit `__del__` may run after the module's globals are gone
    _timeout = subprocess.TimeoutExpired

    def __del__(self) -> None:
        """An Experiment left open at exit: its workers are stopped, with no traceback printed."""
        if getattr(self, "_procs", None):  # (none when __init__ refused its workers)
            try:
                self.close()
            except Exception:  # noqa: BLE001, S110 - at exit the modules close needs may be gone;
                pass  # the workers then read the end of their input when this process ends, and exit
