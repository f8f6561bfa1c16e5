"""tsim.backend.runtime: Taichi's CPU worker threads are pinned one per CPU when they are as many as the
CPUs (the one-process case), and left alone otherwise."""

import json
import os
import subprocess
import sys

import pytest

pytestmark = [pytest.mark.slow, pytest.mark.subprocess]

PROBE = """
import json, os
from tsim.backend import runtime
runtime.init()
me = os.getpid()
tids = {int(t) for t in os.listdir(f"/proc/{me}/task")}
print(json.dumps({"pinned": {str(t): c for t, c in runtime.PINNED.items()},
                  "affinity": {str(t): sorted(os.sched_getaffinity(t)) for t in runtime.PINNED},
                  "threads_of_process": [t in tids for t in runtime.PINNED]}))
"""


def _probe(**env: str) -> dict:
    base = {k: v for k, v in os.environ.items() if k not in ("SGR_THREADS", "SGR_PIN", "SGR_ARCH")}
    out = subprocess.run([sys.executable, "-c", PROBE], env={**base, **env}, capture_output=True,
                         text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


CPUS = sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else []
needs_cpus = pytest.mark.skipif(len(CPUS) < 2 or not os.path.isdir("/proc/self/task"),
                                reason="needs Linux and at least 2 CPUs")


@needs_cpus
def test_workers_pinned_one_per_cpu_when_as_many_as_cpus():
    # in every process: one worker per CPU (a plain busy loop missed a worker in a third of
    # processes; eight of them, CPU times summed, still left a CI process unpinned)
    for _ in range(6):
        got = _probe(SGR_THREADS=str(len(CPUS)))
        assert sorted(got["pinned"].values()) == CPUS  # each CPU gets one worker
        assert all(got["threads_of_process"])
        assert {t: [c] for t, c in got["pinned"].items()} == got["affinity"]


@needs_cpus
def test_nothing_pinned_with_fewer_threads_or_sgr_pin_0():
    assert _probe(SGR_THREADS="1")["pinned"] == {}
    assert _probe(SGR_THREADS=str(len(CPUS)), SGR_PIN="0")["pinned"] == {}
