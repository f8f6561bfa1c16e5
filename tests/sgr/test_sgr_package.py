"""`import sgr` gives the public API of the three layers (exactly what their `__all__` hold), and
`import sgr.evogym` does not import evolve."""

import subprocess
import sys

import evolve
import sgr
import tasks
import tsim


def test_sgr_reexports_every_public_name_of_tsim_tasks_and_evolve():
    for pkg in (tsim, tasks, evolve):
        for name in pkg.__all__:
            assert getattr(sgr, name) is getattr(pkg, name), f"sgr.{name} is not {pkg.__name__}.{name}"
    assert set(sgr.__all__) == set(tsim.__all__) | set(tasks.__all__) | set(evolve.__all__)
    ns = {}
    exec("from sgr import *", ns)
    assert ns["BatchEnv"] is tasks.BatchEnv and ns["Experiment"] is evolve.Experiment


def test_importing_sgr_evogym_leaves_evolve_alone():
    code = "import sys, sgr.evogym.envs; print('evolve' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
