"""sgr: the face users import. Re-exports the public API of the three layers below it (what the
`__all__` of `tsim`, `tasks` and `evolve` hold), so `import sgr` is enough for a notebook:

    import sgr
    env = sgr.BatchEnv("Walker-v0", [body])
    exp = sgr.Experiment.from_config({"method": "sgr", "task": "Walker-v0"}, out="runs/nb")

`sgr.evogym` is evogym 2.0's own API (EvoWorld, EvoSim, EvoViewer, EvoGymBase, utils, the bare gym
ids) on our simulator, so evogym code ports by changing `evogym` to `sgr.evogym` in its imports.
Nothing in tsim, tasks or evolve imports this package.

The names are resolved on first use (PEP 562), so `import sgr.evogym` does not pay for importing
`evolve` (NEAT and the run machinery) it does not use; `tasks` is imported at once, since importing
it registers the gymnasium ids `sgr/<task>` (as evogym's import registers its ids).
tests/sgr/test_sgr_package.py checks that the lists below are exactly the three packages' `__all__`.
"""

from __future__ import annotations

import importlib

import tasks  # noqa: F401  (registers the gymnasium ids: gym.make("sgr/Walker-v0") after import sgr)

_FROM = {
    "tsim": ["BatchSim", "Body", "Renderer", "SgrError", "World", "build_body", "check_robot", "has_actuator",
             "is_connected", "load_world", "sample_robot", "sample_robots", "world_from_dict",
             "world_from_matrix", "write_gif"],
    "tasks": ["TASKS", "BatchEnv", "Measure", "SgrEnv", "SgrVectorEnv", "TaskSpec", "obs_dim", "register",
              "task_spec", "task_world"],
    "evolve": ["METHODS", "Champion", "Experiment", "Problem", "RunDir", "config_from_dict", "load_champion",
               "load_config"],
}
_WHERE = {name: pkg for pkg, names in _FROM.items() for name in names}

__all__ = sorted(_WHERE)


def __getattr__(name: str):
    """The re-exported name, imported from its package on first use."""
    if name in _WHERE:
        value = getattr(importlib.import_module(_WHERE[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'sgr' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
