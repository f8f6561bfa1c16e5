"""sgr's own top-level modules (`tsim`, `tasks`, `evolve`), whatever the working folder holds.

Those names are common words: a project that uses invoke has a `tasks.py`, and `python -m` puts
the working folder first on `sys.path`, where that file would replace sgr's `tasks` in the process.
So every Python process sgr starts (rollout workers, a sweep's runs) is started by `python_command`:
with `-P` (Python 3.11's safe path: the working folder is not put on `sys.path`) and sgr's own
folder first on PYTHONPATH. That is the robust fix: no file in the working folder is ever
imported in a child, whatever it is called, and the child finds the same sgr as its parent.

In the process itself, `use_own_modules` (called where `evolve` is first imported) makes sure
`tsim` and `tasks` are sgr's even where something else of the same name comes first on the path
(another installed package, a folder on PYTHONPATH), and says so in one line: what and where.
Only the standard library is imported here, so it works before any other sgr module.
"""

from __future__ import annotations

import importlib.util
import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]  # the folder that holds tsim/, tasks/ and evolve/
OWN = ("tsim", "tasks", "evolve")


def own_file(name: str) -> Path:
    """The __init__.py of sgr's own top-level package `name`."""
    return ROOT / name / "__init__.py"


def _same(a: str | os.PathLike | None, b: Path) -> bool:
    try:
        return a is not None and Path(a).resolve() == b.resolve()
    except OSError:
        return False


def python_command(module: str, *args: str) -> list[str]:
    """argv of `python -m module args...` for a child process of sgr: with -P, so that the working
    folder is not put first on the child's sys.path (a tasks.py there would be imported instead of
    sgr's tasks); `child_env` supplies sgr's own folder."""
    return [sys.executable, "-P", "-m", module, *args]


def child_env(base: dict[str, str] | None = None, **extra: str) -> dict[str, str]:
    """The environment of a child process of sgr: `base` (default os.environ) with `extra`, and sgr's
    own folder first on PYTHONPATH, so the child imports the same sgr as this process."""
    env = {**(os.environ if base is None else base), **extra}
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH")) if p)
    return env


def use_own_modules() -> None:
    """Make `tsim` and `tasks` in this process sgr's own: one not imported yet that the path would
    find elsewhere first is loaded from sgr's folder, with one warning line saying what was
    passed over and where; ImportError (one line) when something else of that name is imported
    already, since sgr cannot run on it."""
    for name in ("tsim", "tasks"):
        ours = own_file(name)
        loaded = sys.modules.get(name)
        if loaded is not None:
            if not _same(getattr(loaded, "__file__", None), ours):
                what = getattr(loaded, "__file__", None) or repr(loaded)
                raise ImportError(f"the module {name!r} imported in this process is {what}, not sgr's "
                                  f"({ours.parent}): import sgr before it, or rename it")
            continue
        try:
            found = importlib.util.find_spec(name)
        except (ImportError, ValueError):
            found = None
        where = None if found is None else found.origin
        if _same(where, ours):
            continue
        if found is not None:
            print(f"sgr: warning: another {name!r} ({where or 'a namespace folder'}) comes before sgr's "
                  f"({ours.parent}) on the Python path; sgr uses its own, and `import {name}` in this "
                  "process gives sgr's", file=sys.stderr)
        spec = importlib.util.spec_from_file_location(name, ours,
                                                      submodule_search_locations=[str(ours.parent)])
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        try:
            spec.loader.exec_module(module)
        except BaseException:
            del sys.modules[name]
            raise
