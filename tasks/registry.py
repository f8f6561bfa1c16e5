"""Your own tasks without editing sgr: `register(spec)` puts a `TaskSpec` beside sgr's own, so
`BatchEnv`, gymnasium's `sgr/<name>`, configs, sweeps and rollout workers all take it.

Rollout workers are other processes (`python -m evolve.rollout`, or Ray actors) that know only
sgr's tasks: a registered spec travels with each job through the pipe
(evolve/rollout/worker.py, `spec_blob`).

A run of a task registered in a script (no `imports:` to name it) keeps that spec in its folder,
as the same pickle (`TASK_FILE`), so that `sgr render`, `sgr report`, `sgr evolve --resume` and
`load_champion` work on it later, in another process. Loading it runs code, so it follows the rule
of `imports:`: only where the files are yours alone, or after `trust_imports()` (--trust-imports).
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import os
import pickle
import sys
from pathlib import Path

import gymnasium as gym

from tasks.spec import TaskSpec
from tasks.specs import BUILTIN, TASKS, forget_worlds
from tsim.errors import SgrError

_SGR = ("tasks", "tsim", "evolve")
_TRUST_ALL = False  # --trust-imports: import code named in any file, whoever wrote it
TASK_FILE = "task.pkl"  # in a run folder: the spec of a task registered in a script
HOW_TO_TRUST = "if you trust it, add --trust-imports (in Python: tasks.registry.trust_imports())"


def register(spec: TaskSpec, *, replace: bool = False) -> TaskSpec:
    """Make `spec` a task: `BatchEnv(spec.name, ...)`, `gymnasium.make("sgr/" + spec.name, body=m)`
    (TimeLimit at `paper_steps`), configs and sweeps (`task: <name>`) and rollout workers. A name
    that is registered already is an error unless `replace`; sgr's own tasks cannot be replaced.
    Returns the spec."""
    if not isinstance(spec, TaskSpec):
        raise TypeError(f"register takes a tasks.TaskSpec, got {type(spec).__name__}")
    if spec.name in BUILTIN:
        raise SgrError(f"task {spec.name!r} is one of sgr's own tasks; give yours another name")
    old = TASKS.get(spec.name)
    if old is not None and old is not spec and not replace:
        raise SgrError(f"task {spec.name!r} is registered already; register(spec, replace=True) "
                       "replaces it")
    TASKS[spec.name] = spec
    forget_worlds()
    env_id = f"sgr/{spec.name}"
    if env_id in gym.registry:
        del gym.registry[env_id]
    gym.register(env_id, entry_point="tasks.gym_env:SgrEnv", vector_entry_point="tasks.gym_env:SgrVectorEnv",
                 kwargs={"task": spec.name}, max_episode_steps=spec.paper_steps)
    return spec


def trust_imports(on: bool = True) -> None:
    """`--trust-imports`: import the code that run and sweep folders name whoever wrote them."""
    global _TRUST_ALL
    _TRUST_ALL = on


def imports_trusted() -> bool:
    """Whether `trust_imports()` was called in this process (a sweep passes it on to its runs)."""
    return _TRUST_ALL


def _yours(path: Path) -> bool:
    """Whether only you can have written `path`: you own it and neither group nor others may write
    it (git's rule for repositories, applied to the files that name code)."""
    st = path.stat()
    return st.st_uid == os.getuid() and not st.st_mode & 0o022


class TaskModuleError(RuntimeError):
    """A user's task module raised while it was imported. Not an SgrError: the `sgr` command shows
    the traceback of the user's own code (chained as its cause)."""


def import_tasks(ref: str, base: Path | None = None, *, named_in: Path | None = None) -> None:
    """Import the module that registers your tasks: a module name (`mytasks`) or a .py file
    (relative to `base`, default the current folder). Importing the same file twice runs it once.
    `named_in`: the file in a run or sweep folder that names `ref` (resuming, reporting); its code
    is imported only when that file and the .py are yours alone (`_yours`) or after
    `trust_imports()`, since a folder someone else could write must not run code. SgrError naming
    `ref` when it cannot or may not be imported; TaskModuleError when its code raises."""
    path = None
    if ref.endswith(".py"):
        path = Path(ref) if Path(ref).is_absolute() else (base or Path.cwd()) / ref
        path = path.resolve()
        if not path.is_file():
            raise SgrError(f"task module {ref!r}: file not found: {path}")
    if named_in is not None and not _TRUST_ALL:
        others = [p for p in (Path(named_in), path) if p is not None and not _yours(p)]
        if others:
            raise SgrError(f"{named_in} names code to import ({ref}) and {others[0]} could have been "
                           f"written by someone else: {HOW_TO_TRUST}")
    if path is not None:
        name = f"sgr_user_tasks_{path.stem}_{hashlib.sha1(str(path).encode()).hexdigest()[:10]}"
        if name in sys.modules:
            return
        loader = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(loader)
        sys.modules[name] = module  # cloudpickle and dataclasses look modules up by name
        try:
            loader.loader.exec_module(module)
        except Exception as exc:  # a bug in the user's code: its traceback is theirs to read
            del sys.modules[name]
            raise TaskModuleError(f"task module {path} raised {type(exc).__name__}: {exc}; "
                                  "its traceback is above") from exc
        return
    try:
        importlib.import_module(ref)
    except ImportError as exc:
        raise SgrError(f"task module {ref!r} cannot be imported ({exc}); give a module on the path "
                       "or a .py file") from None


def load_task_file(path: Path, named_in: Path) -> str:
    """Register the task a run folder keeps in `path` (`TASK_FILE`, written where the run began),
    unless a task of that name is registered already; returns its name. `named_in` is the run's
    config.yaml. The pickle is code: loaded only when both files are yours alone (`_yours`) or
    after `trust_imports()`; ValueError in one line, saying how to allow it, otherwise."""
    path = Path(path)
    if not _TRUST_ALL:
        others = [p for p in (Path(named_in), path) if not _yours(p)]
        if others:
            raise SgrError(f"{path} holds the code of the run's own task, and {others[0]} could have "
                             f"been written by someone else: {HOW_TO_TRUST}")
    try:
        spec = pickle.loads(path.read_bytes())
    except Exception as exc:  # a damaged file, or code that no longer loads (a module gone)
        raise SgrError(f"{path}: the run's task does not load ({type(exc).__name__}: {exc})") from None
    if not isinstance(spec, TaskSpec):
        raise SgrError(f"{path}: not a task (a pickled {type(spec).__name__})")
    if spec.name not in TASKS:
        register(spec)
    return spec.name
