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
from collections.abc import Sequence
from typing import BinaryIO

import numpy as np

from evolve.rollout.episodes import rollout_policy
from evolve.rollout.robust import EpisodeNoise
from tasks.registry import load_spec_blob


def run_chunk(task: str, bodies: list[np.ndarray], items: Sequence, factory, episode_steps,
              noise: EpisodeNoise | None = None, spec: bytes | None = None) -> np.ndarray:
    """Episode returns of one chunk, simulated as one batch (`noise`: the chunk's perturbations);
    `spec` is a task registered in the parent's code (`tasks.registry.spec_blob`), registered here
    first."""
    load_spec_blob(spec)
    return rollout_policy(task, bodies, lambda env: factory(env, items), episode_steps, noise)


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
    # Ctrl-C reaches the whole process group: the pool's owner handles it and closes our input
    """The worker loop: one reply per job until end of input; a job's exception is sent back, not
    raised, so the worker lives on. The real stdout carries only frames (prints go to stderr)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
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
            except Exception as exc:  # sent back and raised in the parent
                reply = (False, exc)
        try:
            write_frame(replies, reply)
        except BrokenPipeError:  # the pool's owner is gone
            return
        except Exception:  # an exception that does not pickle
            write_frame(replies, (False, RuntimeError(f"{type(reply[1]).__name__}: {reply[1]}")))
