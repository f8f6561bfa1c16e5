"""Your own tasks without editing sgr: `register(spec)` puts a `TaskSpec` beside sgr's own, so
`BatchEnv`, gymnasium's `sgr/<name>`, configs, sweeps and rollout workers all take it.

Rollout workers are other processes (`python -m evolve.rollout`, or Ray actors) that know only
sgr's tasks: a registered spec travels with each job as a cloudpickle (`spec_blob`), which carries
functions defined in your script or in your own modules by value, and the worker registers it
(`load_spec_blob`) before it simulates.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import pickle
import sys
import sysconfig
from pathlib import Path

import cloudpickle
import gymnasium as gym

from tasks.spec import TaskSpec
from tasks.specs import BUILTIN, TASKS, task_world

_BLOBS: dict[str, tuple[TaskSpec, bytes]] = {}  # name -> (spec, its pickle), made once per spec
_SGR = ("tasks", "tsim", "evolve")


def register(spec: TaskSpec, *, replace: bool = False) -> TaskSpec:
    """Make `spec` a task: `BatchEnv(spec.name, ...)`, `gymnasium.make("sgr/" + spec.name, body=m)`
    (TimeLimit at `paper_steps`), configs and sweeps (`task: <name>`) and rollout workers. A name
    that is registered already is an error unless `replace`; sgr's own tasks cannot be replaced.
    Returns the spec."""
    if not isinstance(spec, TaskSpec):
        raise TypeError(f"register takes a tasks.TaskSpec, got {type(spec).__name__}")
    if spec.name in BUILTIN:
        raise ValueError(f"task {spec.name!r} is one of sgr's own tasks; give yours another name")
    old = TASKS.get(spec.name)
    if old is not None and old is not spec and not replace:
        raise ValueError(f"task {spec.name!r} is registered already; register(spec, replace=True) "
                         "replaces it")
    TASKS[spec.name] = spec
    task_world.cache_clear()
    _BLOBS.pop(spec.name, None)
    env_id = f"sgr/{spec.name}"
    if env_id in gym.registry:
        del gym.registry[env_id]
    gym.register(env_id, entry_point="tasks.gym_env:SgrEnv", vector_entry_point="tasks.gym_env:SgrVectorEnv",
                 kwargs={"task": spec.name}, max_episode_steps=spec.paper_steps)
    return spec


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


def import_tasks(ref: str, base: Path | None = None) -> None:
    """Import the module that registers your tasks: a module name (`mytasks`) or a .py file
    (relative to `base`, default the current folder). Importing the same file twice runs it once.
    ValueError naming `ref` when it cannot be imported."""
    if ref.endswith(".py"):
        path = Path(ref) if Path(ref).is_absolute() else (base or Path.cwd()) / ref
        path = path.resolve()
        if not path.is_file():
            raise ValueError(f"task module {ref!r}: file not found: {path}")
        name = f"sgr_user_tasks_{path.stem}_{hashlib.sha1(str(path).encode()).hexdigest()[:10]}"
        if name in sys.modules:
            return
        loader = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(loader)
        sys.modules[name] = module  # cloudpickle and dataclasses look modules up by name
        try:
            loader.loader.exec_module(module)
        except Exception as exc:
            del sys.modules[name]
            raise ValueError(f"task module {ref!r}: {type(exc).__name__}: {exc}") from None
        return
    try:
        importlib.import_module(ref)
    except ImportError as exc:
        raise ValueError(f"task module {ref!r} cannot be imported ({exc}); give a module on the path "
                         "or a .py file") from None
