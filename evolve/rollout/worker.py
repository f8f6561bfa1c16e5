"""A rollout worker process of `RolloutPool`: reads jobs on stdin, writes (ok, returns or
exception) replies on stdout, each a pickle framed by its 8-byte length; exits at end of input.

Run as `python -m evolve.rollout` (evolve/rollout/__main__.py) by the pool, never by hand.
"""

from __future__ import annotations

import os
import pickle
import signal
import struct
import sys
import sysconfig
import traceback
from collections.abc import Sequence
from pathlib import Path
from typing import BinaryIO

import cloudpickle
import numpy as np

from evolve.rollout.episodes import rollout_policy
from evolve.rollout.robust import EpisodeNoise
from tasks.registry import register
from tasks.specs import BUILTIN, TASKS
from tsim.errors import SgrError


def run_chunk(task: str, bodies: list[np.ndarray], items: Sequence, factory, episode_steps,
              noise: EpisodeNoise | None = None, spec: bytes | None = None,
              record: bool = False) -> np.ndarray:
    """Episode returns of one chunk, simulated as one batch (`noise`: the chunk's perturbations);
    `spec` is a task registered in the parent's code (`spec_blob`), registered here
    first. `record`: each row the return and its behaviour features (`rollout_policy`)."""
    load_spec_blob(spec)
    return rollout_policy(task, bodies, lambda env: factory(env, items), episode_steps, noise, record=record)


_SGR = ("tasks", "tsim", "evolve")
_BLOBS: dict[str, tuple[object, bytes]] = {}  # name -> (spec, its pickle), made once per spec


def _own_module(module: object) -> bool:
    """Whether a module is the user's own code: not sgr's, not the standard library's and not an
    installed package's (those import the same way in a worker; the user's may not be on its path)."""
    name = getattr(module, "__name__", "")
    f = getattr(module, "__file__", None)
    if not f or name == "__main__" or name.split(".")[0] in _SGR:
        return False
    f = Path(f).resolve()
    installed = {sysconfig.get_paths()[k] for k in ("stdlib", "platstdlib", "purelib", "platlib")}
    return not any(f.is_relative_to(Path(p).resolve()) for p in installed)




def spec_blob(name: str) -> bytes | None:
    """The pickled spec of a registered task, for a worker process; None for sgr's own tasks (every
    process knows them). Functions of the user's own modules are pickled by value."""
    if name in BUILTIN or name not in TASKS:
        return None
    spec = TASKS[name]
    cached = _BLOBS.get(name)
    if cached is not None and cached[0] is spec:
        return cached[1]
    fns = [spec.reward, spec.termination, spec.state, spec.placement, *(b.fn for b in spec.observation)]
    for mod in {sys.modules.get(getattr(f, "__module__", None) or "") for f in fns if f is not None}:
        if mod is not None and _own_module(mod):
            cloudpickle.register_pickle_by_value(mod)
    blob = cloudpickle.dumps(spec, protocol=pickle.HIGHEST_PROTOCOL)
    _BLOBS[name] = (spec, blob)
    return blob


_LOADED: dict[str, bytes] = {}


def load_spec_blob(blob: bytes | None) -> None:
    """In a worker: register the spec `spec_blob` made (once per distinct blob)."""
    if blob is None:
        return
    spec = pickle.loads(blob)
    if _LOADED.get(spec.name) != blob:
        register(spec, replace=True)
        _LOADED[spec.name] = blob


def write_frame(stream: BinaryIO, obj) -> None:
    """Pickle `obj` and write it as one frame (8-byte little-endian length, then the bytes),
    flushed."""
    data = pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL)
    stream.write(struct.pack("<Q", len(data)) + data)
    stream.flush()


def read_frame(stream: BinaryIO) -> bytes:
    """One frame's pickle bytes; EOFError at a clean end of input."""
    head = stream.read(8)
    if len(head) < 8:
        raise EOFError("end of input")
    (n,) = struct.unpack("<Q", head)
    data = stream.read(n)
    if len(data) < n:
        raise EOFError("truncated frame")
    return data


def main() -> None:
    """The worker loop: one reply per job until end of input; a job's exception is sent back, not
    raised, so the worker lives on. The real stdout carries only frames (prints go to stderr)."""
    # Ctrl-C reaches the whole process group, a scheduler's SIGTERM every process of the job: the
    # pool's owner handles them (its generation ends, with a checkpoint) and closes our input
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, signal.SIG_IGN)
    # the protocol owns the real stdout; anything printed (e.g. by a library) goes to stderr
    replies = os.fdopen(os.dup(sys.stdout.fileno()), "wb")
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())
    jobs = sys.stdin.buffer
    while True:
        try:
            data = read_frame(jobs)
        except EOFError:
            return
        try:
            job = pickle.loads(data)
        except Exception as exc:
            reply = (False, RuntimeError(f"a rollout worker could not load its job ({exc}); policy "
                                         "factories and items must be importable, picklable objects"))
        else:
            try:
                reply = (True, run_chunk(*job))
            except Exception as exc:  # sent back and raised in the parent, with where it was raised here
                if not isinstance(exc, SgrError):  # (a traceback does not pickle; a note does)
                    exc.add_note(f"raised in rollout worker process {os.getpid()}:\n"
                                 + "".join(traceback.format_tb(exc.__traceback__)).rstrip())
                reply = (False, exc)
        try:
            write_frame(replies, reply)
        except BrokenPipeError:  # the pool's owner is gone
            return
        except Exception:  # an exception that does not pickle
            write_frame(replies, (False, RuntimeError(f"{type(reply[1]).__name__}: {reply[1]}")))
