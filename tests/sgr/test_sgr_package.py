"""`import sgr` gives the public API of the three layers (exactly what their `__all__` hold), and
`import sgr.evogym` does not import evolve."""

import subprocess
import sys

import pytest

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


@pytest.mark.slow
@pytest.mark.subprocess
def test_importing_sgr_evogym_leaves_evolve_alone():
    code = "import sys, sgr.evogym.envs; print('evolve' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_import_sgr_registers_the_sgr_gymnasium_ids():
    """After `import sgr` alone, gym.make("sgr/Walker-v0", ...) works (no NamespaceNotFound)."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    code = ("import gymnasium as gym, numpy as np, sgr\n"
            "env = gym.make('sgr/Walker-v0', body=np.full((5, 5), 3))\n"
            "print(env.spec.id, env.spec.max_episode_steps)")
    root = Path(__file__).resolve().parents[2]
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                       env={**os.environ, "PYTHONPATH": str(root)})
    assert r.returncode == 0 and r.stdout.split() == ["sgr/Walker-v0", "500"], r.stderr[-2000:]
