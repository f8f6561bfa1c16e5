"""A run folder's config.yaml and neat.ini read back and checked as a new run's config is.

A folder is data from a stranger: every reader of one (`sgr evolve --resume`, `select-champion`,
`decode`, `render`, `load_champion`) passes its config.yaml through `check_run_config` (the same
type and value checks `check_config` of evolve/runs/config.py makes of a new run's config, with the
same bounds) and, where it runs the search, its neat.ini through `check_run_neat_ini`, before it
uses a value. The checks of the values themselves (`check_values`) live here, once, for both.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Mapping
from pathlib import Path

from evolve.config import (
    ABSENT_BEFORE,
    COMMON,
    MAX_EPISODE_STEPS,
    MAX_POP,
    FinalSelection,
    RunConfig,
    not_for,
)
from evolve.methods import METHODS
from evolve.rollout.pool import workers_problem
from evolve.rollout.robust import Robust
from tasks.specs import TASKS, body_fit_problem, unknown_task
from tsim.backend import runtime
from tsim.errors import SgrError


def short_repr(value: object, most: int = 80) -> str:
    """`repr(value)` for an error line, cut at `most` characters (a YAML value may be huge)."""
    text = repr(value)
    return text if len(text) <= most else text[:most] + " ..."


def type_name(t: type | tuple[type, ...]) -> str:
    """A key's YAML type(s) as an error line says them: "int", "str or null"."""
    ts = t if isinstance(t, tuple) else (t,)
    return " or ".join("null" if x is type(None) else x.__name__ for x in ts)


def typed(key: str, val: object, typ: object, source: object) -> object:
    """A config key's YAML value checked against its type (an int is a float); SgrError naming
    the key otherwise, or for a float that is not finite."""
    if typ is float and isinstance(val, int) and not isinstance(val, bool):
        val = float(val)
    types = typ if isinstance(typ, tuple) else (typ,)
    ok = isinstance(val, typ) and not (isinstance(val, bool) and bool not in types)
    if not ok:
        raise SgrError(f"{source}: key {key!r} must be {type_name(typ)}, got {short_repr(val)}")
    if isinstance(val, float) and not math.isfinite(val):
        raise SgrError(f"{source}: key {key!r} must be a finite number, got {val!r}")
    return val


def check_imports(imports: list, source: object) -> None:
    """SgrError unless `imports` lists module names or .py files."""
    if not all(isinstance(m, str) for m in imports):
        raise SgrError(f"{source}: key 'imports' must be a list of module names or .py files, "
                       f"got {short_repr(imports)}")


def check_values(values: dict, method: str, source: object) -> tuple[Robust | None, FinalSelection | None]:
    """The checks of the common keys' values that a new run's config and a run folder's config.yaml
    share (`check_config` of evolve/runs/config.py, `check_run_config`): counts >= 1 and bounded,
    the body's shape, the episode length, workers, robust and final_selection;
    `values["episode_steps"]` is resolved to the task's length. Returns robust and final_selection
    parsed; SgrError naming the key."""
    problem = METHODS[method]
    for key in ("generations", "pop_size", "checkpoint_every"):
        if values[key] < 1:
            raise SgrError(f"{source}: key {key!r} must be >= 1, got {values[key]}")
    if values["pop_size"] > MAX_POP:
        raise SgrError(f"{source}: key 'pop_size' must be at most {MAX_POP:,}, got {values['pop_size']:,}")
    shape = values["robot_shape"]
    if len(shape) != 2 or not all(isinstance(v, int) and not isinstance(v, bool) and v > 0 for v in shape):
        raise SgrError(f"{source}: key 'robot_shape' must be [rows, cols] of positive ints, got {shape}")
    if (why := body_fit_problem(values["task"], (shape[0], shape[1]))) is not None:
        raise SgrError(f"{source}: key 'robot_shape' {list(shape)}: {why}")
    steps = values["episode_steps"]
    if isinstance(steps, str) and steps != "evogym" or isinstance(steps, int) and steps < 1:
        raise SgrError(f"{source}: key 'episode_steps' must be a positive int, 'evogym' or null, "
                       f"got {steps!r}")
    if isinstance(steps, int) and steps > MAX_EPISODE_STEPS:
        raise SgrError(f"{source}: key 'episode_steps' must be at most {MAX_EPISODE_STEPS:,}, got {steps:,}")
    # the run records the episode length it uses, not a rule for it
    values["episode_steps"] = TASKS[values["task"]].episode_length(steps)
    if (why := workers_problem(values["workers"])) is not None:
        raise SgrError(f"{source}: key 'workers' {why}")
    try:  # robust.py raises ValueError naming the key: the user's to fix
        robust = Robust.from_config(values["robust"], source)
    except SgrError:
        raise
    except ValueError as exc:
        raise SgrError(str(exc)) from None
    if robust is not None and robust.accumulate and problem.reevaluate_elites:
        raise SgrError(f"{source}: key 'robust.accumulate' is not for method {method!r}: its fitness "
                       "(the best of a search run for each body) is not a score to average")
    selection = FinalSelection.from_config(values["final_selection"], source)
    if selection is not None and problem.reevaluate_elites:
        raise SgrError(f"{source}: key 'final_selection' {not_for(method)}")
    return robust, selection


def check_run_config(raw: Mapping, source: Path | str, *, load_task: Callable[[dict], None] | None = None,
                     running: bool = False) -> RunConfig:
    """A run folder's config.yaml (`raw`, as read) checked as a new run's config is, then read back
    (`RunConfig.of`): every key present of its type, the counts >= 1 and bounded, the body, the
    episode length, workers, robust, final_selection and precision as `check_config` has them. A
    key an older sgr did not write may be missing (it takes the meaning it had then), and keys
    this sgr does not know are kept unread. The folder is a stranger's: nothing it names is
    imported here; `load_task` (RunDir.load_task) registers its task once the keys it reads have
    their types. `running`: the run is to be resumed or evaluated, so the method's own checks
    (`Problem.validate`, which may read the files it names) run too.

    Raises:
        SgrError: one line naming `source` and the key.
    """
    method = raw.get("method")
    if isinstance(method, str) and method not in METHODS and load_task is not None:
        load_task(dict(raw), method=True)  # a method of the user's: its imports, when trusted
    if not isinstance(method, str) or method not in METHODS:
        raise SgrError(f"{source}: key 'method' must be one of {', '.join(METHODS)}, got "
                       f"{short_repr(method)}")
    problem = METHODS[method]
    schema = {**COMMON, **problem.config_keys}
    if "task" not in raw:
        raise SgrError(f"{source}: missing required key 'task'")
    values = {k: typed(k, raw[k], typ, source) for k, (typ, _) in schema.items() if k in raw}
    check_imports(values.get("imports") or [], source)
    precision = raw.get("precision")
    if precision is not None and precision not in runtime.PRECISIONS:
        raise SgrError(f"{source}: key 'precision' must be one of {', '.join(runtime.PRECISIONS)}, got "
                       f"{short_repr(precision)}")
    if load_task is not None:
        load_task(dict(raw))
    if values["task"] not in TASKS:
        raise SgrError(f"{source}: key 'task': {unknown_task(values['task'])}")
    filled = {k: values[k] if k in values else ABSENT_BEFORE.get(k, fallback)
              for k, (_, fallback) in COMMON.items()}
    check_values(filled, method, source)
    cfg = RunConfig.of(raw)
    if running:
        problem.validate(cfg.with_own({k: problem.absent_before.get(k, d)
                                      for k, (_, d) in problem.config_keys.items()}), source)
    return cfg


def read_run_config(run, running: bool = False) -> tuple[dict, RunConfig]:
    """A run folder's config.yaml as written and as a checked `RunConfig` (`check_run_config`:
    its task registered, every value checked as a new run's), and its neat.ini checked too when
    `running` (`check_run_neat_ini`): what every reader of a folder (resume, select-champion,
    decode, render, load_champion) goes through before it uses a value. `run`: a RunDir.

    Raises:
        SgrError: one line naming the file and the key.
    """
    if running:  # it will write into the folder: a link in it is refused before anything is read
        run.refuse_links()
    raw = run.config()
    cfg = check_run_config(raw, run.path / "config.yaml", load_task=run.load_task, running=running)
    if running and METHODS[cfg.method].uses_neat:
        check_run_neat_ini(run.path / "neat.ini", cfg)
    return raw, cfg


def check_run_neat_ini(path: Path, cfg: RunConfig) -> None:
    """A run folder's neat.ini checked as a new run's INI is (`load_neat_config`: its sizes in
    bounds), and its pop_size the run's config's, as sgr writes it (evolve/search/neat_ini.py).

    Raises:
        SgrError: one line naming the file and the key.
    """
    from evolve.search.neat_ini import load_neat_config
    from tsim.files import read_head

    if os.path.lexists(path):
        read_head(path, 0)  # a FIFO, a device or a link: one line naming what it is (tsim/files.py)
    if not path.is_file():
        raise SgrError(f"{path}: not there, or not a file: a run keeps the neat-python config it uses")
    neat_config = load_neat_config(path)
    if neat_config.pop_size != cfg.pop_size:
        raise SgrError(f"{path}: key 'pop_size' is {neat_config.pop_size:,}, its run's config.yaml says "
                       f"{cfg.pop_size:,} (sgr writes them alike)")
