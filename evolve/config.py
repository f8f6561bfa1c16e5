"""Experiment configs: YAML files checked against a schema, with errors that name the key.

Paths inside a config (neat_config) are relative to the YAML file. `load_config` returns a plain
dict with every key present (defaults filled), which is what a run directory stores.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from tasks.specs import TASKS

METHODS = ("sgr", "direct", "nested")

# key: (type or tuple of types, default). None default = required.
COMMON: dict[str, tuple[Any, Any]] = {
    "method": (str, None),
    "task": (str, None),
    "generations": (int, 250),
    "pop_size": (int, 128),
    "seed": (int, 0),
    "robot_shape": (list, [5, 5]),
    "episode_steps": ((int, str, type(None)), None),
    "neat_config": (str, None),
    "checkpoint_every": (int, 5),
    "render_champion": (bool, True),
    "workers": ((int, str), "auto"),
}
PER_METHOD: dict[str, dict[str, tuple[Any, Any]]] = {
    "sgr": {"cppn_outputs": (int, 1), "weight_threshold": (float, 0.2), "max_weight": (float, 1.0),
            "body_distance_weight": (float, 0.1)},
    "direct": {"body_distance_weight": (float, 0.0), "layout": (str, "per_output")},
    "nested": {"inner_pop_size": (int, 12), "inner_generations": (int, 2),
               "inner_keep_generations": ((int, type(None)), 20), "controller_neat_config": (str, None)},
}
REQUIRED_FOR = {"nested": ("controller_neat_config",)}


def _type_name(t) -> str:
    ts = t if isinstance(t, tuple) else (t,)
    return " or ".join("null" if x is type(None) else x.__name__ for x in ts)


def check_config(raw: dict, source: str = "config") -> dict:
    """Fill defaults and validate; raises ValueError naming the offending key."""
    if not isinstance(raw, dict):
        raise ValueError(f"{source}: a config must be a mapping of keys to values")
    method = raw.get("method")
    if method not in METHODS:
        raise ValueError(f"{source}: key 'method' must be one of {', '.join(METHODS)}, got {method!r}")
    schema = {**COMMON, **PER_METHOD[method]}
    for key in raw:
        if key not in schema:
            raise ValueError(f"{source}: unknown key {key!r} for method {method!r}; "
                             f"known keys: {', '.join(sorted(schema))}")
    cfg = {}
    for key, (typ, default) in schema.items():
        if key not in raw:
            if default is None and (key in ("method", "task", "neat_config")
                                    or key in REQUIRED_FOR.get(method, ())):
                raise ValueError(f"{source}: missing required key {key!r}")
            cfg[key] = default
            continue
        val = raw[key]
        if typ is float and isinstance(val, int) and not isinstance(val, bool):
            val = float(val)
        types = typ if isinstance(typ, tuple) else (typ,)
        ok = isinstance(val, typ) and not (isinstance(val, bool) and bool not in types)
        if not ok:
            raise ValueError(f"{source}: key {key!r} must be {_type_name(typ)}, got {val!r}")
        cfg[key] = val
    if cfg["task"] not in TASKS:
        raise ValueError(f"{source}: key 'task': unknown task {cfg['task']!r}; known tasks: "
                         f"{', '.join(TASKS)}")
    for key in ("generations", "pop_size", "checkpoint_every"):
        if cfg[key] < 1:
            raise ValueError(f"{source}: key {key!r} must be >= 1, got {cfg[key]}")
    shape = cfg["robot_shape"]
    if len(shape) != 2 or not all(isinstance(v, int) and v > 0 for v in shape):
        raise ValueError(f"{source}: key 'robot_shape' must be [rows, cols] of positive ints, got {shape}")
    steps = cfg["episode_steps"]
    if isinstance(steps, str) and steps != "evogym" or isinstance(steps, int) and steps < 1:
        raise ValueError(f"{source}: key 'episode_steps' must be a positive int, 'evogym' or null, "
                         f"got {steps!r}")
    w = cfg["workers"]
    if isinstance(w, str) and w not in ("auto", "ray") or isinstance(w, int) and w < 1:
        raise ValueError(f"{source}: key 'workers' must be a positive int, 'auto' or 'ray', got {w!r}")
    if method == "direct" and cfg["layout"] not in ("per_output", "per_cell"):
        raise ValueError(f"{source}: key 'layout' must be 'per_output' or 'per_cell', got {cfg['layout']!r}")
    if method == "nested":
        for key in ("inner_pop_size", "inner_generations"):
            if cfg[key] < 1:
                raise ValueError(f"{source}: key {key!r} must be >= 1, got {cfg[key]}")
        keep = cfg["inner_keep_generations"]
        if keep is not None and keep < 1:
            raise ValueError(f"{source}: key 'inner_keep_generations' must be a positive int or null "
                             f"(never forget), got {keep}")
    if method == "sgr" and cfg["cppn_outputs"] not in (1, 2):
        raise ValueError(f"{source}: key 'cppn_outputs' must be 1 or 2, got {cfg['cppn_outputs']}")
    return cfg


def yaml_problem(exc: yaml.YAMLError) -> str:
    """One line for a YAML syntax error: what and where (PyYAML's own message spans several)."""
    mark = getattr(exc, "problem_mark", None)
    what = getattr(exc, "problem", None) or str(exc).splitlines()[0]
    return f"{what} at line {mark.line + 1}, column {mark.column + 1}" if mark else what


def load_config(path: str | Path, overrides: dict | None = None) -> dict:
    """Read, override (CLI flags), resolve relative paths and validate a YAML config."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"config file not found: {path}")
    try:
        raw = yaml.safe_load(path.read_text()) or {}
    except UnicodeDecodeError:
        raise ValueError(f"{path}: not a text file") from None
    except yaml.YAMLError as exc:
        raise ValueError(f"{path}: not valid YAML: {yaml_problem(exc)}") from None
    if not isinstance(raw, dict):
        raise ValueError(f"{path}: a config must be a mapping of keys to values, got a {type(raw).__name__}")
    raw = {**raw, **{k: v for k, v in (overrides or {}).items() if v is not None}}
    for key in ("neat_config", "controller_neat_config"):
        if isinstance(raw.get(key), str) and not Path(raw[key]).is_absolute():
            raw[key] = str((path.parent / raw[key]).resolve())
    cfg = check_config(raw, str(path))
    for key in ("neat_config", "controller_neat_config"):
        if cfg.get(key) and not Path(cfg[key]).is_file():
            raise ValueError(f"{path}: key {key!r}: file not found: {cfg[key]}")
    return cfg
