"""`import sgr` gives the public API of the three layers (what their `__all__` hold)."""

import evolve
import sgr
import tasks
import tsim


def test_sgr_reexports_every_public_name_of_tsim_tasks_and_evolve():
    for pkg in (tsim, tasks, evolve):
        for name in pkg.__all__:
            assert getattr(sgr, name) is getattr(pkg, name), f"sgr.{name} is not {pkg.__name__}.{name}"
    assert set(sgr.__all__) == set(tsim.__all__) | set(tasks.__all__) | set(evolve.__all__)
