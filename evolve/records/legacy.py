"""Pickles of an older sgr converted to today's data files: checkpoints (gen-XXXXX.pkl) to JSON
checkpoints, and the pickled spec of a script's task (task.pkl) to a task reference (task.json:
the task's name, the file its reward was defined in and that file's sha256; tasks/registry.py).

This is the one place where sgr unpickles a file, and it runs only when the user says that they
trust the folder (`sgr migrate DIR --trust-pickle`): a pickle can run any code when it
is loaded. Resuming never comes here; it refuses a run holding only pickles with the command above.
A converted checkpoint holds the same state, so the run resumes from it as it would have from the
pickle; each pickle is deleted once its JSON replacement is written.
"""

from __future__ import annotations

import io
import pickle
from pathlib import Path

from evolve.records.rundir import RunDir
from tsim.errors import SgrError
from tsim.files import CHECKPOINT_CAP, CONFIG_CAP, read_bytes

# modules renamed since checkpoints were first written: old checkpoints still load
MOVED_MODULES = {"evolve.genome": "evolve.search.genome"}


class _Unpickler(pickle.Unpickler):
    def find_class(self, module: str, name: str):
        return super().find_class(MOVED_MODULES.get(module, module), name)


def load_trusted_pickle(path: Path) -> dict:
    """An older sgr's checkpoint state. RUNS ANY CODE THE FILE HOLDS: only for folders the user
    trusts."""
    state = _Unpickler(io.BytesIO(read_bytes(path, CHECKPOINT_CAP))).load()
    if not isinstance(state, dict) or "generation" not in state:
        raise SgrError(f"{path}: not an sgr checkpoint")
    return state


def convert_task(run: RunDir) -> list[str]:
    """An older sgr's task.pkl made a task reference (task.json); the names of the files written.
    RUNS ANY CODE task.pkl HOLDS (only for folders the user trusts): the spec is unpickled and
    registered in this process (so that its checkpoints convert too), and its reference names
    the file its reward was defined in, when that file is still there (else none: the task is
    known only where a process registers it)."""
    from tasks.registry import OLD_TASK_FILE, TASK_FILE, code_file, register, task_reference
    from tasks.spec import TaskSpec
    from tasks.specs import TASKS

    old = run.path / OLD_TASK_FILE
    if not old.is_file():
        return []
    try:
        spec = pickle.loads(read_bytes(old, CONFIG_CAP))
    except Exception as exc:  # a damaged file, or code that no longer loads (a module gone)
        raise SgrError(f"{old}: cannot convert ({type(exc).__name__}: {exc})") from None
    if not isinstance(spec, TaskSpec):
        raise SgrError(f"{old}: not a task (a pickled {type(spec).__name__})")
    if spec.name not in TASKS:
        register(spec)
    run.save_task(task_reference(spec.name, source=code_file(spec)))
    old.unlink()
    return [TASK_FILE]


def run_dirs(path: Path) -> list[RunDir]:
    """The run directories of `path`: itself when it is a run, else those under a sweep's runs/."""
    path = Path(path)
    if (path / "config.yaml").is_file():
        return [RunDir(path)]
    if (path / "sweep.yaml").is_file():
        return [RunDir(p) for p in sorted((path / "runs").iterdir()) if (p / "config.yaml").is_file()]
    raise SgrError(f"{path} is neither a run directory (config.yaml) nor a sweep directory (sweep.yaml)")
