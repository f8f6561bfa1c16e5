"""A sweep's stop passed on to a run still starting is held, not lost: a run's process holds SIGUSR1
blocked from before its program starts (`hold_passed_on`, the sweeps' preexec), and its loop
(`stop_after_generation`) lets the pending stop in once its handler is set; after the loop the stop
is held again, so a late one is never SIGUSR1's default action (a kill)."""

from __future__ import annotations

import signal
import threading

import pytest

from evolve.runs.stops import PASSED_ON, hold_passed_on, stop_after_generation


def pass_on() -> None:
    """The sweep's stop, sent to this thread (pytest's process has other threads, which do not hold
    it; in a run's process every thread does, from before its program starts)."""
    signal.pthread_kill(threading.get_ident(), PASSED_ON)


@pytest.fixture
def held_here():
    """This thread's signal mask and PASSED_ON's handler as found, restored after the test (a
    stop left pending is discarded first: ignored while pending, Linux drops it)."""
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, [])
    handler = signal.getsignal(PASSED_ON)
    yield
    signal.signal(PASSED_ON, signal.SIG_IGN)  # drops a pending PASSED_ON
    signal.pthread_sigmask(signal.SIG_SETMASK, mask)
    signal.signal(PASSED_ON, handler)


def test_a_stop_passed_on_before_the_loop_lands_when_the_loop_begins(held_here):
    hold_passed_on()
    pass_on()  # the sweep stops while the run's program is still starting
    assert PASSED_ON in signal.sigpending()  # held, not delivered: the process lives
    with stop_after_generation() as stop:
        assert PASSED_ON not in signal.sigpending()
        assert stop.is_set() and stop.signum == PASSED_ON  # the loop stops after its first generation
        assert PASSED_ON not in signal.pthread_sigmask(signal.SIG_BLOCK, [])  # let in while the loop runs
    assert PASSED_ON in signal.pthread_sigmask(signal.SIG_BLOCK, [])  # held again after it
    pass_on()  # a late stop, after the loop: pending, not a kill
    assert PASSED_ON in signal.sigpending()


def test_a_loop_in_a_process_that_holds_nothing_leaves_the_mask_as_it_found_it(held_here):
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {PASSED_ON})
    with stop_after_generation() as stop:
        pass_on()
        assert stop.is_set()
    assert PASSED_ON not in signal.pthread_sigmask(signal.SIG_BLOCK, [])
