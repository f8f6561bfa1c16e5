"""Ray: the runs of a sweep as tasks on a cluster (`sgr sweep --backend ray`), and the rollouts of
one run on a cluster's actors (`workers: ray`).

This module imports Ray only when one of them is used, so the package works without it.

Sweep backend (`RayBackend`): each run of a sweep is one Ray task that reserves `cpus_per_run`
CPUs on a node and advances the run there with `sgr evolve --resume RUN --workers cpus_per_run` in
a subprocess, exactly as the local backend does on this machine. The run directories must lie on a
filesystem that every node mounts at the same path: the driver creates them, the nodes write them.
A task that fails (its process exits with an error, its worker or node dies) ends with an exit
code, and `run_sweep` resumes the run from its own checkpoints, on whichever node has room.

Rollout pool (`RayRolloutPool`): one actor per CPU of the cluster, each a process with one Taichi
thread that compiles the simulator once and then simulates a chunk of every generation. The
chunks are `balanced_chunks` of the bodies, as with local workers, and the split does not change
the returns. An actor that dies (its process killed, its node lost) has its chunk simulated again
at once by a surviving actor, so the generation's returns are those it would have had; before the
next generation it is replaced by a new actor where the cluster has a free CPU (a killed process
frees its own), and otherwise the pool goes on with fewer actors. Ray does not restart our actors
itself: a restarted actor waits for a free CPU, and after a node loss there may be none, so a
generation would wait for ever.
"""

from __future__ import annotations

import importlib.util
import logging
import os
import random
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np

from evolve.own_modules import ROOT
from evolve.rollout.pool import BasePool
from tsim.backend import runtime
from tsim.errors import SgrError

INSTALL = 'pip install "sgr[ray]"'
ACTOR_RESTARTS = 3  # a chunk whose actor dies is re-run on another actor this many times
REPLACE_TIMEOUT_S = 60.0  # a replacement actor that has not started by then is given up


def require_ray(what: str) -> None:
    """ValueError (one line for `sgr: error:`) when Ray is not installed; does not import it."""
    if importlib.util.find_spec("ray") is None:
        raise SgrError(f"{what} needs Ray: {INSTALL}")


def connect(what: str, address: str | None = None, start: str | None = None):
    """The ray module, connected: to the Ray this process already joined, else to `address`, else
    as `start` says (None: Ray's default, the cluster in $RAY_ADDRESS or the one `ray start` ran on
    this machine, else a new local instance; "local": always a new local instance)."""
    require_ray(what)
    import ray

    if not ray.is_initialized():
        # Ray puts the driver's working folder on its workers' path, before sgr: made from sgr's own
        # folder, so that a tasks.py or evolve.py where the user works is not imported there
        here = os.getcwd()
        os.chdir(ROOT)
        try:
            ray.init(address=address or start, logging_level=logging.WARNING, log_to_driver=False)
        except ConnectionError as exc:  # e.g. no cluster at that address
            where = f"at {address}" if address else "here"
            raise SgrError(f"{what}: cannot join a Ray cluster {where}: "
                           f"{' '.join(str(exc).split())}") from None
        finally:
            os.chdir(here)
    return ray


# ---------------------------------------------------------------------------------- rollout pool
class _RolloutActor:
    """One process with one Taichi thread; the simulator's kernels compile on its first chunk."""

    def pid(self) -> int:
        return os.getpid()

    def run(self, job: tuple) -> np.ndarray:
        from evolve.rollout.worker import run_chunk

        return run_chunk(*job)


class RayRolloutPool(BasePool):
    """Episode returns of (body, policy item) pairs, split over Ray actors (`workers: ray`): one per
    CPU of the cluster (or `actors`), started on first use. `run` is `BasePool.run`; Python's
    `random` state is left as it was."""

    def __init__(self, actors: int | None = None):
        require_ray("workers: ray")
        self.n_actors = actors
        self._actors: list = []
        self._live: list[int] = []  # the actors a run's chunks go to (set by _width)
        self._started_ray = False

    @contextmanager
    def _session(self) -> Iterator[None]:
        """Ray draws from Python's `random` (e.g. when it starts), which neat-python evolves with: the
        caller's random state is left as it was, as local workers leave it."""
        state = random.getstate()
        try:
            yield
        finally:
            random.setstate(state)

    def _width(self) -> int:
        """The live actors (started, and dead ones replaced where there is room); RuntimeError when
        none is left."""
        ray = self._start()
        self._replace_dead(ray)
        self._live = [i for i, a in enumerate(self._actors) if a is not None]
        if not self._live:
            raise RuntimeError("no Ray rollout actor is left and the cluster has no free CPU for a new "
                               "one; set workers: 1 or N to run on this machine")
        return len(self._live)

    def _run_jobs(self, jobs: list[tuple]) -> list[np.ndarray]:
        """Each job on one live actor; an actor's exception is raised here; a job whose actor died is
        run again on another one, RuntimeError when an actor died more than ACTOR_RESTARTS times."""
        import ray

        pending = {self._actors[i].run.remote(job): (k, i)
                   for k, (i, job) in enumerate(zip(self._live, jobs, strict=False))}
        tries = [0] * len(jobs)
        out: list = [None] * len(jobs)
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1)
            k, i = pending.pop(ready[0])
            try:
                out[k] = ray.get(ready[0])
            except ray.exceptions.RayTaskError as exc:  # raised in an actor: raise it here as it was
                raise exc.cause from None
            except ray.exceptions.RayActorError as exc:  # the process or its node died: run it elsewhere
                self._actors[i] = None
                tries[k] += 1
                live = [j for j, a in enumerate(self._actors) if a is not None]
                if tries[k] > ACTOR_RESTARTS or not live:
                    why = "no rollout actor is left" if not live else f"its actor died {tries[k]} times"
                    raise RuntimeError(f"a chunk of Ray rollouts could not be simulated: {why} ("
                                       f"{' '.join(str(exc).split())[:300]}); set workers: 1 or N to "
                                       "run on this machine") from None
                j = live[k % len(live)]
                pending[self._actors[j].run.remote(jobs[k])] = (k, j)
        return out

    def _new_actor(self, ray):
        # one Taichi thread per actor; actors simulate where and in the precision this process does
        env = {"SGR_THREADS": "1", "SGR_PRECISION": runtime.precision()}
        if os.environ.get("SGR_ARCH"):
            env["SGR_ARCH"] = os.environ["SGR_ARCH"]
        # the environment is set before the actor's process starts: Taichi reads it at its start
        cls = ray.remote(_RolloutActor).options(num_cpus=1, max_restarts=0, max_task_retries=0,
                                                runtime_env={"env_vars": env})
        return cls.remote()

    def _start(self):
        """Ray (joined, or started by this pool) and the actors, created on first use."""
        import ray

        if not ray.is_initialized():
            connect("workers: ray")
            self._started_ray = True
        if not self._actors:
            n = self.n_actors or max(1, int(ray.cluster_resources().get("CPU", 1)))
            self._actors = [self._new_actor(ray) for _ in range(n)]
        return ray

    def _replace_dead(self, ray) -> None:
        """A new actor in each dead one's place while the cluster has a free CPU for it; one that
        does not start within REPLACE_TIMEOUT_S is given up (the pool goes on without it)."""
        for i, actor in enumerate(self._actors):
            if actor is not None or ray.available_resources().get("CPU", 0) < 1:
                continue
            new = self._new_actor(ray)
            try:
                ray.get(new.pid.remote(), timeout=REPLACE_TIMEOUT_S)
            except (ray.exceptions.GetTimeoutError, ray.exceptions.RayActorError):
                ray.kill(new, no_restart=True)
                continue
            self._actors[i] = new

    def pids(self) -> list[int]:
        """The process ids of the actors (starting them, and replacing dead ones where there is
        room)."""
        state = random.getstate()
        try:
            ray = self._start()
            self._replace_dead(ray)
            return ray.get([a.pid.remote() for a in self._actors if a is not None])
        finally:
            random.setstate(state)

    def close(self) -> None:
        """Stop the actors; shut Ray down if this pool started it."""
        if not self._actors and not self._started_ray:
            return
        import ray

        for actor in self._actors:
            if actor is not None:
                ray.kill(actor, no_restart=True)
        self._actors = []
        if self._started_ray:
            ray.shutdown()
            self._started_ray = False

    def __del__(self) -> None:
        if self._actors:
            try:
                self.close()
            except Exception:
                pass

