"""Your own tasks without editing sgr: `register(spec)` puts a `TaskSpec` beside sgr's own, so
`BatchEnv`, gymnasium's `sgr/<name>`, configs, sweeps and rollout workers all take it.

Rollout workers are other processes (`python -m evolve.rollout`, or Ray actors) that know only
sgr's tasks: a registered spec travels with each job through the pipe
(evolve/rollout/worker.py, `spec_blob`), between the processes of one run, never through a file.

Nothing in a run or sweep folder runs code by being read (docs/RELIABILITY.md "Trust"). A run of
a task registered in a script (no `imports:` to name it) keeps a *reference* to it (`TASK_FILE`,
JSON): the task's name, the file that registered it and that file's sha256. Later, in another
process, the task is known when that process registered it itself (it imported the user's
script or module before `load_champion`, say), or, after `trust_imports()` (`--trust-imports`),
by importing that file again, only if its digest still matches. The `imports:` a run's or
sweep's config names follow the same rule (`import_tasks(named_in=...)`): imported only after
`trust_imports()`, and not at all when the tasks are registered already. Code the user names
in the command itself (`sgr evolve --config my.yaml`, a script's `Experiment.from_config`) is
imported as they asked. An older sgr's `task.pkl` (`OLD_TASK_FILE`) is never unpickled on
reading: `sgr migrate DIR --trust-pickle` turns it into a reference.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.machinery
import importlib.util
import json
import sys
from pathlib import Path

import gymnasium as gym

from tasks.spec import TaskSpec
from tasks.specs import BUILTIN, TASKS, forget_worlds
from tsim.errors import SgrError
from tsim.files import CONFIG_CAP, read_bytes, read_text

_SGR = ("tasks", "tsim", "evolve")
_TRUST_ALL = False  # --trust-imports: import the code that run and sweep folders name
TASK_FILE = "task.json"  # in a run folder: the reference to a task registered in a script
OLD_TASK_FILE = "task.pkl"  # an older sgr's: that task's pickled spec, never loaded on reading
TASK_FORMAT, TASK_VERSION = "sgr-task-reference", 1
HOW_TO_TRUST = "if you trust it, add --trust-imports (in Python: tasks.registry.trust_imports())"
_SOURCES: dict[str, Path | None] = {}  # task name -> the file whose code registered it
_NAMED: tuple[Path, ...] = ()  # --import FILE: script files the user names, trusted alone
MAX_SCRIPT_BYTES = 16 << 20  # a task script larger than this is no script (read no further)


def register(spec: TaskSpec, *, replace: bool = False) -> TaskSpec:
    """Make `spec` a task, known wherever sgr's own tasks are.

    That is `BatchEnv(spec.name, ...)`, `gymnasium.make("sgr/" + spec.name, body=m)` (TimeLimit at
    `paper_steps`), configs and sweeps (`task: <name>`) and rollout workers. The file of the code
    that called it is remembered: a run of the task refers to it (`task_reference`).

    Args:
        spec: The task.
        replace: Replace a task of the same name registered already (sgr's own tasks cannot be
            replaced).

    Returns:
        The spec.

    Raises:
        TypeError: When `spec` is not a `TaskSpec`.
        SgrError: When the name is one of sgr's own tasks, or is registered already and `replace`
            is False.
    """
    if not isinstance(spec, TaskSpec):
        raise TypeError(f"register takes a tasks.TaskSpec, got {type(spec).__name__}")
    if spec.name in BUILTIN:
        raise SgrError(f"task {spec.name!r} is one of sgr's own tasks; give yours another name")
    old = TASKS.get(spec.name)
    if old is not None and old is not spec and not replace:
        raise SgrError(f"task {spec.name!r} is registered already; register(spec, replace=True) "
                       "replaces it")
    TASKS[spec.name] = spec
    _SOURCES[spec.name] = _caller_file() or code_file(spec)
    forget_worlds()
    env_id = f"sgr/{spec.name}"
    if env_id in gym.registry:
        del gym.registry[env_id]
    from tasks.gym_env import register_id

    register_id(env_id, entry_point="tasks.gym_env:SgrEnv", vector_entry_point="tasks.gym_env:SgrVectorEnv",
                kwargs={"task": spec.name}, max_episode_steps=spec.paper_steps)
    return spec


def _caller_file() -> Path | None:
    """The .py file of the nearest caller outside sgr (the user's script or module), if it is one."""
    frame = sys._getframe(1)
    while frame is not None and frame.f_globals.get("__name__", "").split(".")[0] in _SGR:
        frame = frame.f_back
    f = frame.f_globals.get("__file__") if frame is not None else None
    return Path(f).resolve() if isinstance(f, str) and f.endswith(".py") and Path(f).is_file() else None


def code_file(spec: TaskSpec) -> Path | None:
    """The .py file the spec's reward was defined in, when it is one (a pickled function keeps it)."""
    f = getattr(getattr(spec.reward, "__code__", None), "co_filename", None)
    ok = isinstance(f, str) and f.endswith(".py") and Path(f).is_absolute() and Path(f).is_file()
    return Path(f).resolve() if ok else None


def trust_imports(on: bool = True) -> None:
    """`--trust-imports`: import the code that run and sweep folders name (their `imports:`, the
    file that registered a script's task)."""
    global _TRUST_ALL
    _TRUST_ALL = on


def name_imports(files: list[str | Path] | tuple = ()) -> tuple[Path, ...]:
    """`--import FILE`: trust these script files (and no other) to register the task a run
    folder's task.json refers to, each imported only while its sha256 is the one recorded. Returns
    the files named before (to restore them); SgrError when one is not a file."""
    global _NAMED
    paths = []
    for f in files:
        path = Path(f).expanduser()
        if not path.is_file():
            raise SgrError(f"--import {f}: {'not a regular file' if path.exists() else 'file not found'}")
        paths.append(path.resolve())
    was, _NAMED = _NAMED, tuple(paths)
    return was


def imports_trusted() -> bool:
    """Whether `trust_imports()` was called in this process (a sweep passes it on to its runs)."""
    return _TRUST_ALL


class TaskModuleError(RuntimeError):
    """A user's task module raised while it was imported. Not an SgrError: the `sgr` command shows
    the traceback of the user's own code (chained as its cause)."""


def import_tasks(ref: str, base: Path | None = None, *, named_in: Path | None = None) -> None:
    """Import the module that registers your tasks: a module name (`mytasks`) or a .py file
    (relative to `base`, default the current folder). Importing the same file twice runs it once.
    `named_in`: the file in a run or sweep folder that names `ref` (resuming, reporting); a folder
    is data, so its code is imported only after `trust_imports()` (the caller skips this when the
    tasks are registered already). SgrError naming `ref` when it cannot or may not be imported;
    TaskModuleError when its code raises."""
    if named_in is not None and not _TRUST_ALL:
        raise SgrError(f"{named_in} names code to import ({ref}), which sgr does not run for reading a "
                       f"folder: {HOW_TO_TRUST}, or register its tasks in your process first")
    if ref.endswith(".py"):
        path = Path(ref) if Path(ref).is_absolute() else (base or Path.cwd()) / ref
        path = path.resolve()
        if not path.is_file():
            raise SgrError(f"task module {ref!r}: file not found: {path}")
        _exec_file(path, path.read_bytes())
        return
    try:
        importlib.import_module(ref)
    except ImportError as exc:
        raise SgrError(f"task module {ref!r} cannot be imported ({exc}); give a module on the path "
                       "or a .py file") from None


class _BytesLoader(importlib.machinery.SourceFileLoader):
    """A .py file's loader that compiles the bytes given (those whose digest was checked), never a
    cached .pyc."""

    def __init__(self, name: str, path: str, data: bytes):
        super().__init__(name, path)
        self._data = data

    def get_code(self, fullname: str):
        return self.source_to_code(self._data, self.path)


def _exec_file(path: Path, data: bytes) -> None:
    """Run `data`, the text of the .py file `path`, as a module of its own (once per file)."""
    name = f"sgr_user_tasks_{path.stem}_{hashlib.sha1(str(path).encode()).hexdigest()[:10]}"
    if name in sys.modules:
        return
    loader = _BytesLoader(name, str(path), data)
    module = importlib.util.module_from_spec(importlib.util.spec_from_loader(name, loader))
    sys.modules[name] = module  # cloudpickle and dataclasses look modules up by name
    try:
        loader.exec_module(module)
    except Exception as exc:  # a bug in the user's code: its traceback is theirs to read
        del sys.modules[name]
        raise TaskModuleError(f"task module {path} raised {type(exc).__name__}: {exc}; "
                              "its traceback is above") from exc


def task_reference(name: str, source: Path | None = None) -> dict:
    """What a run folder keeps of a task registered in a script (`TASK_FILE`): its name, the file
    whose code registered it (or `source`): its file name ("file", looked up beside the run folder
    and inside it, where a copy of the run finds it) and its absolute path where the run was made
    ("source", a hint), and that file's sha256 (all null when there is no file: a task registered
    in a notebook is known only where it is registered again)."""
    source = source or _SOURCES.get(name)
    ref = {"format": TASK_FORMAT, "version": TASK_VERSION, "task": name, "file": None, "source": None,
           "sha256": None}
    if source is not None and source.is_file():
        ref.update(file=source.name, source=str(source),
                   sha256=hashlib.sha256(source.read_bytes()).hexdigest())
    return ref


def _script_bytes(path: Path) -> bytes | None:
    """The bytes of `path` when it is a regular file of at most MAX_SCRIPT_BYTES (links followed),
    else None: a FIFO or a device found where a script is looked for is never read (a read would
    block or never end)."""
    try:
        return read_bytes(path, MAX_SCRIPT_BYTES, follow=True)
    except (OSError, SgrError):  # not there, not a regular file, or too large
        return None


def _script_name(ref: dict) -> str | None:
    """The script's file name a reference gives ("file"; an older sgr's reference: its source's
    name), when it is a plain .py file name (no folder: it is looked up beside the run only)."""
    name = ref.get("file")
    if name is None and isinstance(ref.get("source"), str):
        name = Path(ref["source"]).name  # an older sgr's reference: the absolute path only
    if (isinstance(name, str) and name.endswith(".py") and name == Path(name).name
            and "\0" not in name and name not in (".", "..")):
        return name
    return None


def load_task_reference(path: Path) -> str:
    """The task a run folder refers to (`TASK_FILE`, JSON, read as data), registered in this process
    unless it is already; returns its name. Its script is imported only after `trust_imports()`
    (looked up by its file name in the run folder and beside it, then at its recorded path), or when
    the user named it (`name_imports`, --import FILE), and only while its sha256 is the one
    recorded; otherwise SgrError in one line naming the file and what to do."""
    path = Path(path)
    try:
        ref = json.loads(read_text(path, CONFIG_CAP))  # a regular file, not a link, of a few MiB at most
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
        raise SgrError(f"{path}: not a task reference ({' '.join(str(exc).split())[:200]})") from None
    if not (isinstance(ref, dict) and ref.get("format") == TASK_FORMAT and isinstance(ref.get("task"), str)):
        raise SgrError(f"{path}: not a task reference (no format {TASK_FORMAT!r} and task name)")
    name, source, digest = ref["task"], ref.get("source"), ref.get("sha256")
    if name in TASKS:  # registered by this process itself
        return name
    file = _script_name(ref)
    if file is None or not isinstance(digest, str):
        raise SgrError(f"{path}: task {name!r} was registered by code with no file (a notebook?): register "
                       "it in your process first")
    shown = f"{file} ({source} where the run was made)" if isinstance(source, str) else file
    named = [f for f in _NAMED if _script_bytes(f) is not None]
    if named:  # --import FILE: the user's own copy, trusted alone
        for f in named:
            data = _script_bytes(f)
            if data is not None and hashlib.sha256(data).hexdigest() == digest:
                return _import_script(path, name, f, data)
        raise SgrError(f"{path}: --import {', '.join(str(f) for f in named)}: not the script the run was "
                       f"made with ({shown}: its sha256 differs from the one recorded), so it is not "
                       "imported: register the task in your process first (import it) to use it as it is now")
    if not _TRUST_ALL:
        raise SgrError(f"{path}: task {name!r} is registered by {shown}, which sgr does not run for reading "
                       f"a folder: import it in your process first, or, if you trust it, add --trust-imports "
                       f"with {file} beside the run folder, or --import YOUR_COPY_OF_{file} (in Python: "
                       "tasks.registry.trust_imports())")
    run = path.parent
    places = [run / file, run.parent / file]
    if isinstance(source, str) and Path(source).is_absolute():
        places.append(Path(source))
    found = []
    for f in places:
        data = _script_bytes(f)
        if data is None:
            continue
        if hashlib.sha256(data).hexdigest() == digest:
            return _import_script(path, name, f, data)
        found.append(str(f))
    if found:
        raise SgrError(f"{path}: {', '.join(found)} has changed since the run was made (its sha256 differs "
                       "from the one recorded), so it is not imported: register the task in your process "
                       "first (import it) to use it as it is now")
    raise SgrError(f"{path}: task {name!r} is registered by {shown}, which is not there (nor {file} beside "
                   f"the run folder or in it): copy it beside the run folder, name your copy with --import "
                   "FILE, or register the task in your process first (import your copy of it)")


def _import_script(ref_file: Path, name: str, script: Path, data: bytes) -> str:
    """Import `data`, the text of `script` whose digest was checked; returns `name`, SgrError
    naming `ref_file` when the script did not register that task."""
    _exec_file(script.resolve(), data)
    if name not in TASKS:
        raise SgrError(f"{ref_file}: {script} was imported but did not register task {name!r}")
    return name
