"""Experiment configs: YAML files (or dicts) checked against a schema, with errors that name the key.

The schema is the common keys below plus the method's own (`Problem.config_keys`). Paths inside a
config (neat_config, ...) are relative to the YAML file; left out, they are the method's packaged
defaults in configs/neat/. A relative one that is not beside the YAML file is taken from the
packaged configs as if the file sat among them (a copied packaged config keeps working), saying so
on stderr. `load_config` returns a `RunConfig`: frozen and typed, every key
present (defaults filled from the schema, the one place they live), checked once, `episode_steps`
resolved to the number of steps a run uses and `robust`/`final_selection` parsed once into their
dataclasses. It reads as a mapping of the config's keys to their YAML values, which is what a
run directory stores (config.yaml), with the run's precision; `arch` is the one asked for when
the config was checked, not written to config.yaml (segments.json records where each part of a run
ran: evolve/records/segments.py). `RunConfig.of` reads a run folder's config.yaml back, older ones
(keys missing, `episode_steps` null) included. Left out, `robust` and `final_selection` are the
honest evaluation that `sgr evolve` runs by default (evolve/config.py, `HONEST_ROBUST`);
null is the paper's nominal one.

`imports` lists modules (names, or .py files relative to the config) that register tasks of your own
(`tasks.register`); they are imported before the task is looked up, by every process of the run.
"""

from __future__ import annotations

import sys
from pathlib import Path

from evolve.config import COMMON, RunConfig, default
from evolve.methods import METHODS
from evolve.records.files import read_yaml
from evolve.records.run_config import (  # the checks a run folder's config.yaml shares (short_repr: sweeps)
    check_imports,
    check_run_config,
    check_run_neat_ini,
    check_values,
    read_run_config,
    short_repr,
    typed,
)
from tasks.registry import import_tasks
from tasks.specs import TASKS, closest, unknown_task
from tsim.backend import runtime
from tsim.errors import SgrError

__all__ = ["check_config", "check_run_config", "check_run_neat_ini", "config_from_dict", "configs_dir",
           "find_config", "load_config", "packaged_config", "read_run_config", "short_repr"]

REPO_CONFIGS = Path(__file__).resolve().parents[2] / "configs"


def configs_dir() -> Path:
    """The configs shipped with sgr: the repository's configs/ in a checkout or an editable
    install, the package's configs folder (mapped there at build time, see pyproject.toml) in an
    installed one."""
    if REPO_CONFIGS.is_dir():
        return REPO_CONFIGS
    return Path(__file__).resolve().parents[1] / "configs"


def check_config(raw: dict, source: str = "config", named_in: Path | None = None) -> RunConfig:
    """Fill defaults and validate, once; raises SgrError naming the offending key. Keys `arch` and
    `precision` (a run folder's config.yaml used as a config) are replaced by this run's.
    `named_in`: the file of a run or sweep folder the config was read back from (`--from RUN`, a
    sweep's runs on --resume): its `imports:` are imported only after --trust-imports, and not at
    all when the task is registered already (tasks/registry.py); a config the user names imports
    them."""
    if not isinstance(raw, dict):
        raise SgrError(f"{source}: a config must be a mapping of keys to values")
    method = raw.get("method")
    if isinstance(method, str) and method not in METHODS and isinstance(raw.get("imports"), list):
        check_imports(raw["imports"], source)  # a method of the user's: its module registers it
        for ref in raw["imports"]:
            try:
                import_tasks(ref, named_in=named_in)
            except ValueError as exc:
                raise SgrError(f"{source}: key 'imports': {exc}") from None
    if not isinstance(method, str) or method not in METHODS:
        raise SgrError(f"{source}: key 'method' must be one of {', '.join(METHODS)}, got {method!r}"
                       f"{closest(method, METHODS)}")
    problem = METHODS[method]
    schema = {**COMMON, **problem.config_keys}
    raw = {k: v for k, v in raw.items() if k != "arch"}  # recorded, not chosen
    # the simulator's real type, f64 (evogym's bits) or f32; null: $SGR_PRECISION, else f64
    asked_precision = raw.pop("precision", None)
    for key in raw:
        if key not in schema:
            raise SgrError(f"{source}: unknown key {key!r} for method {method!r}; "
                           f"known keys: {', '.join(sorted(schema))}")
    values = {}
    for key, (typ, fallback) in schema.items():
        if key not in raw:
            if key == "task":
                raise SgrError(f"{source}: missing required key {key!r}")
            values[key] = default(key, problem.reevaluate_elites) if key in COMMON else fallback
            continue
        values[key] = typed(key, raw[key], typ, source)
    imports = values["imports"]
    check_imports(imports, source)
    for ref in imports if named_in is None or values["task"] not in TASKS else ():  # the user's tasks
        try:
            import_tasks(ref, named_in=named_in)
        except ValueError as exc:
            raise SgrError(f"{source}: key 'imports': {exc}") from None
    if values["task"] not in TASKS:
        raise SgrError(f"{source}: key 'task': {unknown_task(values['task'])}")
    robust, selection = check_values(values, method, source)
    try:  # the run records the precision it simulates in; a resumed run keeps it
        precision = runtime.requested_precision(asked_precision)
    except ValueError as exc:
        raise SgrError(f"{source}: key 'precision': {exc}") from None
    for key, name in problem.default_files.items():
        if values[key] is None:
            values[key] = str(configs_dir() / "neat" / name)
        if not Path(values[key]).is_file():
            raise SgrError(f"{source}: key {key!r}: file not found: {values[key]}")
    from tsim.backend.runtime import requested_arch

    cfg = RunConfig.build(values, problem.config_keys, arch=requested_arch(), precision=precision,
                          robust=robust, selection=selection)
    if cfg.start_from is not None:
        from evolve.runs.continuation import check_start_from

        cfg = cfg.replace(start_from=check_start_from(cfg, source))
    problem.validate(cfg, source)
    return cfg


def load_config(path: str | Path, overrides: dict | None = None, named_in: Path | None = None) -> RunConfig:
    """Read, override, resolve and validate a YAML config.

    Relative paths in it are taken from the config's folder.

    Args:
        path: The YAML config.
        overrides: Values set over its keys (CLI flags, a sweep's overrides): every key as given,
            None setting null.
        named_in: The file of a run or sweep folder the config was read back from (`check_config`).

    Returns:
        The resolved config.

    Raises:
        SgrError: The config is not valid; the message names the file and the key.
    """
    path = Path(path)
    raw = read_yaml(path, "config file") or {}
    if not isinstance(raw, dict):
        raise SgrError(f"{path}: a config must be a mapping of keys to values, got a {type(raw).__name__}")
    return config_from_dict({**raw, **(overrides or {})}, str(path), path.parent, named_in)


def config_from_dict(raw: dict, source: str = "config", base: Path | None = None,
                     named_in: Path | None = None) -> RunConfig:
    """The resolved config of a dict (what a YAML file holds), defaults filled and validated.

    Args:
        raw: The config's keys and values.
        source: What the config is called in error messages.
        base: The folder relative file paths are taken from; None: the current folder.
        named_in: The file of a run or sweep folder the config was read back from (`check_config`).

    Returns:
        The resolved config.

    Raises:
        SgrError: The config is not valid; the message names `source` and the key.
    """
    if not isinstance(raw, dict):
        raise SgrError(f"{source}: a config must be a mapping of keys to values, "
                       f"got a {type(raw).__name__}")
    method = raw.get("method")
    problem = METHODS.get(method) if isinstance(method, str) else None  # else check_config says why
    raw = dict(raw)
    for key in problem.default_files if problem else ():
        if isinstance(raw.get(key), str) and not Path(raw[key]).is_absolute():
            raw[key] = _beside_or_packaged(raw[key], key, raw["method"], source, base or Path.cwd())
    start = raw.get("start_from")
    if isinstance(start, dict) and isinstance(start.get("run"), str) and not Path(start["run"]).is_absolute():
        raw["start_from"] = {**start, "run": str(((base or Path.cwd()) / start["run"]).resolve())}
    if isinstance(raw.get("imports"), list):  # .py files relative to the config, like neat_config
        raw["imports"] = [str(((base or Path.cwd()) / m).resolve())
                          if isinstance(m, str) and m.endswith(".py") and not Path(m).is_absolute() else m
                          for m in raw["imports"]]
    return check_config(raw, source, named_in)


def _beside_or_packaged(ref: str, key: str, method: str, source: str, base: Path) -> str:
    """The absolute path of a config's relative file `ref` (neat_config, ...): beside the config
    when it is there, else the packaged file it names, as if the config sat beside the packaged
    configs of its method (a packaged config copied elsewhere keeps working), saying so in one
    line; else the path beside the config, which check_config reports as missing."""
    beside = (base / ref).resolve()
    if beside.exists():
        return str(beside)
    for packaged in ((configs_dir() / method / ref).resolve(), configs_dir() / "neat" / Path(ref).name):
        if packaged.is_file():
            print(f"sgr: note: {source}: {key} {ref} is not beside it ({beside}); using sgr's packaged "
                  f"{packaged}", file=sys.stderr)
            return str(packaged)
    return str(beside)


def packaged_config(name: str) -> Path | None:
    """A config shipped with sgr by name: "sgr/Climber-v2" (a method's config of a task), "quick",
    or a sweep, "paper" (configs/sweeps/paper.yaml); None when there is none of that name."""
    base = configs_dir()
    name = name.removesuffix(".yaml")
    for f in (base / f"{name}.yaml", base / "sgr" / f"{name}.yaml", base / "sweeps" / f"{name}.yaml"):
        if f.is_file():
            return f
    return None


def find_config(ref: str, what: str = "config") -> Path:
    """A config path as given when that file exists, else the packaged config of that name
    (`packaged_config`), so names work from any folder; ValueError saying which it is not."""
    if Path(ref).is_file():
        return Path(ref)
    found = packaged_config(ref)
    if found is not None:
        return found
    if Path(ref).exists():
        raise SgrError(f"{what} {ref} is not a file")
    names = [str(f.relative_to(configs_dir()).with_suffix("")) for f in sorted(configs_dir().glob("*/*.yaml"))
             if f.parent.name != "neat"]
    raise SgrError(f"{what} {ref} does not exist, nor is it the name of a packaged config"
                   f"{closest(ref.removesuffix('.yaml'), names) or ' (e.g. sgr/Climber-v2, quick, paper)'}")
