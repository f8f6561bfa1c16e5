"""Stops asked for by signals: Ctrl-C (SIGINT) at a terminal, SIGTERM from a cluster's scheduler
(Slurm, PBS, Kubernetes send it before SIGKILL) or from `kill`.

The first SIGINT or SIGTERM lets the generation under way end, writes a checkpoint and stops; a
second stops at once, after writing a checkpoint of the last finished generation when the newest
one is older (the generation under way is lost, nothing before it). A second signal less than
`SAME_REQUEST_S` after the first is the same request, not a second one: `timeout`, `kill -TERM
-PGID` and many schedulers signal the process and then its process group, so one stop arrives
twice within microseconds. (Python's signal handlers are not told who sent a signal; learning it
would mean blocking the signals in every thread, rollout workers included, for a thread of
`sigwaitinfo`: the time between the two is what tells them apart.) SIGUSR1 is how a sweep passes
a stop on to its runs: it asks the same as a first signal but never counts as one, so a run that
got the scheduler's SIGTERM itself (Slurm signals every process of a job) and its sweep's SIGUSR1
still finishes its generation. The exit code of a stop is 128 + the signal's number, the shell's
convention: 130 for SIGINT, 143 for SIGTERM.

A run's process started by a sweep holds SIGUSR1 blocked from before its program starts
(`hold_passed_on`, the sweep's preexec) until its loop has set the handler: a stop passed on while
the run is still starting waits, pending, and the run stops after its first generation, rather than
dying of SIGUSR1's default action or being lost.
"""

from __future__ import annotations

import signal
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager

STOPS = (signal.SIGINT, signal.SIGTERM)  # a second one stops at once
PASSED_ON = signal.SIGUSR1  # a sweep's stop, passed on to its runs: never a second signal
# A second SIGINT or SIGTERM sooner than this after the first is the same request: the copy sent to
# the process group arrives microseconds after the one sent to the process (tens of milliseconds on a
# machine whose CPUs are all busy), while a person's second Ctrl-C, or a second `kill`, comes
# later (the documented "again: stop now" is tested with signals 0.3 s apart).
SAME_REQUEST_S = 0.2


class Interrupted(KeyboardInterrupt):
    """A stop asked for by a signal; `signum` says which (a KeyboardInterrupt, so that code that
    handles Ctrl-C handles a SIGTERM alike)."""

    def __init__(self, signum: int = signal.SIGINT, at_once: bool = False):
        super().__init__(signal.Signals(signum).name)
        self.signum = int(signum)
        self.at_once = at_once  # a second signal: the generation under way was not finished


def exit_code(exc: BaseException) -> int:
    """128 + the number of the signal that stopped the process: 130 for Ctrl-C (a plain
    KeyboardInterrupt), 143 for SIGTERM."""
    return 128 + getattr(exc, "signum", int(signal.SIGINT))


class StopRequest:
    """Whether, and by which signal, the loop was asked to stop after the generation under way."""

    def __init__(self) -> None:
        self.signum: int | None = None  # the first signal that asked
        self.counted = False  # a SIGINT or SIGTERM came: the next one stops at once
        self.first_at = 0.0  # when it came (time.monotonic)
        self.at_once = False  # a second one came: stopping now (later ones change nothing)

    def is_set(self) -> bool:
        """Asked to stop after this generation."""
        return self.signum is not None


def _first_line(signum: int) -> str:
    if signum == signal.SIGINT:  # (the words the Ctrl-C path has always printed)
        return ("sgr: stopping after this generation, with a checkpoint (Ctrl-C again: stop now, "
                "at the last finished generation)")
    name = "asked by the sweep" if signum == PASSED_ON else signal.Signals(signum).name
    return (f"sgr: {name}: stopping after this generation, with a checkpoint (SIGTERM or Ctrl-C "
            "again: stop now, at the last finished generation)")


@contextmanager
def stop_after_generation() -> Iterator[StopRequest]:
    """While inside: the first SIGINT or SIGTERM (or a sweep's SIGUSR1) marks the request (the loop
    stops after its generation, with a checkpoint); another within `SAME_REQUEST_S` of it is the
    same request; a later SIGINT or SIGTERM raises `Interrupted(at_once=True)` at once, and the
    ones after it are ignored (the loop is writing its last checkpoint). Outside the main thread,
    where signal handlers cannot be set, the signals keep their handlers."""
    stop = StopRequest()
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return

    def handler(signum, frame):
        if signum != PASSED_ON:
            now = time.monotonic()
            if stop.at_once or stop.counted and now - stop.first_at < SAME_REQUEST_S:
                return  # stopping now already, or the same request sent twice (to the process group)
            if stop.counted:
                stop.at_once = True
                raise Interrupted(signum, at_once=True)
            stop.counted, stop.first_at = True, now
        if stop.signum is None:
            print(f"\n{_first_line(signum)}", file=sys.stderr, flush=True)
        if stop.signum in (None, PASSED_ON):  # the stop is the signal's, not the sweep's passing it on
            stop.signum = signum

    old = {s: signal.signal(s, handler) for s in (*STOPS, PASSED_ON)}
    held = PASSED_ON in signal.pthread_sigmask(signal.SIG_UNBLOCK, {PASSED_ON})  # a pending stop lands now
    try:
        yield stop
    finally:
        _outwait(stop.first_at if stop.counted else None)
        if held:  # held again before the default action is back: a late stop is never a kill
            signal.pthread_sigmask(signal.SIG_BLOCK, {PASSED_ON})
        for s, h in old.items():
            signal.signal(s, h)


def hold_passed_on() -> None:
    """Block the sweep's stop (SIGUSR1) in this thread, and in the program it executes, until a
    loop's `stop_after_generation` sets its handler and lets it in: a run's process gets this
    before its program starts (the sweeps' preexec), so a stop passed on while it starts is not
    lost."""
    signal.pthread_sigmask(signal.SIG_BLOCK, {PASSED_ON})


def _outwait(first_at: float | None) -> None:
    """Wait, with our handlers still set, until `SAME_REQUEST_S` has passed since the first stop
    (time.monotonic), so that its copy sent to the process group lands on them, not on the default
    handler, which would kill the process while it closes (exit -15, its last lines lost)."""
    if first_at is not None:
        left = first_at + SAME_REQUEST_S - time.monotonic()
        if left > 0:
            time.sleep(left)


@contextmanager
def sigterm_interrupts() -> Iterator[None]:
    """While inside: SIGTERM raises `Interrupted` as Ctrl-C raises KeyboardInterrupt (a process
    with nothing of its own to checkpoint, such as a sweep that then stops its runs); another
    within `SAME_REQUEST_S` of the first is the same request and changes nothing. Outside the
    main thread: nothing changes."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    first: list[float] = []  # when the first SIGTERM came

    def handler(signum, frame):
        now = time.monotonic()
        if first and now - first[0] < SAME_REQUEST_S:
            return  # the same request, sent to the process group as well
        first.append(now)
        raise Interrupted(signum)

    old = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        _outwait(first[0] if first else None)
        signal.signal(signal.SIGTERM, old)
