"""Which runs a report or a plot may average: run folders found at any depth below the folders
given (with what was skipped and why), grouped by the settings that make their results comparable.

Runs are one group when they differ in their seed alone. The settings (`SETTINGS`): method, task,
body shape, population, generations, episode length, evaluation (nominal or the `robust` settings),
final selection, precision, arch and origin (`start_from`). Runs that differ in any of them are
never averaged together unless the caller pools that setting (`sgr report --pool pop,precision`;
`--pool all`: every one but method and task, the old (method, task) grouping). A group's label is
its method as plots have always named it ("sgr", "sgr robust 10x10"), and where two groups of one
task would share it, the settings that tell them apart ("sgr (pop 64)", "sgr (pop 128)").
Reading a folder never runs code: config.yaml is read with yaml's safe loader (`load_yaml`).
"""

from __future__ import annotations

import os
from collections import defaultdict
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from evolve.records.files import load_yaml
from tsim.backend import DEFAULT_PRECISION
from tsim.errors import SgrError
from tsim.files import CONFIG_CAP, read_text

UNKNOWN = "unknown"
# every setting that makes two runs' results incomparable; method and task are never pooled
SETTINGS = ("method", "task", "shape", "pop", "generations", "steps", "evaluation", "selection",
            "precision", "arch", "start")
POOLABLE = SETTINGS[2:]


@dataclass(frozen=True)
class Skipped:
    """A path given or found that is not a run, and why."""
    path: Path
    why: str

    def line(self) -> str:
        """One line for the console and report.md."""
        return f"{self.path}: {self.why}"


@dataclass
class Group:
    """Runs that differ in their seed alone (or in pooled settings): `settings` maps each of
    SETTINGS to its value (pooled ones: every value among the runs, joined by " / ")."""
    label: str
    task: str
    settings: dict[str, str]
    runs: list[Path] = field(default_factory=list)
    classic: str = ""  # the label without the settings that tell groups of one task apart

    def others(self) -> tuple[str, ...]:
        """Every setting but the method: groups equal in these compare methods."""
        return tuple(self.settings[k] for k in SETTINGS if k != "method")


def parse_pool(text: str | Sequence[str] | None) -> tuple[str, ...]:
    """The settings `--pool` names ("pop,precision", "all"); SgrError for any other."""
    if not text:
        return ()
    names = [n.strip() for part in ([text] if isinstance(text, str) else text) for n in part.split(",")]
    if "all" in names:
        return POOLABLE
    for n in names:
        if n in ("method", "task"):
            raise SgrError(f"--pool {n}: runs of different {n}s are never averaged together")
        if n not in POOLABLE:
            raise SgrError(f"--pool {n!r}: not a setting; use any of {', '.join(POOLABLE)}, or all")
    return tuple(k for k in POOLABLE if k in names)


def find_runs(paths: str | Path | Sequence[str | Path], need_config: bool = True
              ) -> tuple[list[Path], list[Skipped]]:
    """The run folders at any depth below `paths` (each may be a run itself) and what was passed
    over: files given, folders holding part of a run, folders with no run below. A run folder has
    generations.csv and (with `need_config`) a config.yaml that reads as a mapping; nothing below
    a run is searched, nor hidden folders. SgrError for a path that does not exist."""
    if isinstance(paths, str | Path):
        paths = [paths]
    runs: list[Path] = []
    skipped: list[Skipped] = []
    seen: set[Path] = set()
    for p in map(Path, paths):
        if not p.exists():
            raise SgrError(f"not a folder: {p}")
        if not p.is_dir():
            skipped.append(Skipped(p, "a file, not a run folder"))
            continue
        _walk(p, runs, skipped, seen, need_config)
    return runs, skipped


def _walk(folder: Path, runs: list[Path], skipped: list[Skipped], seen: set[Path], need_config: bool) -> None:
    real = folder.resolve()
    if real in seen:  # given twice, or a link back up the tree
        return
    seen.add(real)
    why = _not_a_run(folder, need_config)
    if why is None:
        runs.append(folder)
        return
    if why:  # part of a run: never searched below
        skipped.append(Skipped(folder, why))
        return
    try:
        subs = sorted(d for d in folder.iterdir() if not d.name.startswith(".") and d.is_dir())
    except OSError as exc:
        skipped.append(Skipped(folder, f"cannot be read ({exc.strerror})"))
        return
    before = len(runs) + len(skipped)
    for d in subs:
        _walk(d, runs, skipped, seen, need_config)
    if len(runs) + len(skipped) == before:
        skipped.append(Skipped(folder, "no run folder in it (none with config.yaml and generations.csv)"
                               if need_config else "no generations.csv in it or below it"))


def _not_a_run(folder: Path, need_config: bool) -> str | None:
    """None for a run folder; why a folder holding some of a run's files is not one; "" for a
    folder holding none of them (searched below)."""
    # (a FIFO, a device or a link counts as there: reading it says what it is, in one line)
    has = {n for n in ("config.yaml", "generations.csv", "champion.json") if os.path.lexists(folder / n)
           and not (folder / n).is_dir()}
    if "generations.csv" in has:
        if "config.yaml" not in has:
            return "generations.csv but no config.yaml" if need_config else None
        try:
            raw = load_yaml(read_text(folder / "config.yaml", CONFIG_CAP))
        except (yaml.YAMLError, UnicodeDecodeError):
            return "config.yaml is not valid YAML"
        return None if isinstance(raw, dict) else "config.yaml is not a mapping of settings"
    if "config.yaml" in has:
        return "config.yaml but no generations.csv (a run that never started?)"
    if "champion.json" in has:
        return "a champion.json alone (sgr decode's output?), not a run"
    return ""


def read_config(run_dir: Path) -> dict:
    """A run's config.yaml as a dict ({} without one or when it is not a mapping)."""
    f = Path(run_dir) / "config.yaml"
    if not os.path.lexists(f):
        return {}
    try:
        raw = load_yaml(read_text(f, CONFIG_CAP))
    except UnicodeDecodeError:
        raise SgrError(f"{f}: not a text file") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        raise SgrError(f"{f}: not valid YAML{f' (line {mark.line + 1})' if mark else ''}") from None
    return raw if isinstance(raw, dict) else {}


def episode_length(raw: dict, task: str) -> int | None:
    """The episode length a run used: its config's (runs record it), or for a config that left it
    out (null: the paper's, "evogym": evogym's) the task's; None for a task not registered here."""
    from tasks.specs import TASKS

    steps = raw.get("episode_steps")
    if isinstance(steps, int):
        return steps
    spec = TASKS.get(task)
    return None if spec is None else spec.episode_length(steps)


def run_settings(run_dir: Path, raw: dict | None = None) -> dict[str, str]:
    """The value of each of SETTINGS for a run, as text; a run without config.yaml (plots take
    those) has its method from its parent folder's name and "?" for the rest."""
    raw = read_config(run_dir) if raw is None else raw
    method = str(raw.get("method") or (Path(run_dir).resolve().parent.name or UNKNOWN))
    if raw.get("layout") not in (None, "per_output"):  # the direct baseline's variant is its own method
        method = f"{method} ({raw['layout']})"
    if raw.get("body_decoder") not in (None, "substrate"):  # and so is sgr with another body decoder
        method = f"{method} ({raw['body_decoder']})"
    if isinstance(raw.get("qd"), dict):  # and a map over other descriptors, or with other parents
        method = _map_variant(method, raw["qd"])
    task = str(raw.get("task") or UNKNOWN)
    if not raw:
        return {"method": method, "task": task, **{k: "?" for k in POOLABLE}}
    shape = raw.get("robot_shape") or [5, 5]
    try:
        steps = episode_length(raw, task)
    except (TypeError, ValueError):
        steps = None
    start = raw.get("start_from")
    return {"method": method, "task": task,
            "shape": "x".join(map(str, shape)) if isinstance(shape, list) else str(shape),
            "pop": str(raw.get("pop_size", 128)), "generations": str(raw.get("generations", 250)),
            "steps": "?" if steps is None else str(steps),
            "evaluation": _evaluation(raw.get("robust")), "selection": _selection(raw.get("final_selection")),
            "precision": str(raw.get("precision") or DEFAULT_PRECISION), "arch": _arches(run_dir),
            "start": f"from g{start.get('generation', '?')}" if isinstance(start, dict) else "fresh"}


def _map_variant(method: str, qd: dict) -> str:
    """A map-elites run's method as a report names it: its descriptors where they are not the
    default body ones, its parent choice where it is not uniform ("map-elites (gait_frequency x
    contact, curiosity, exploit 0.5)"): maps over other descriptors or bred otherwise are other
    methods, never averaged with each other (config.yaml read as data: any odd value is shown)."""
    from evolve.methods.map_elites import DEFAULT_DESCRIPTORS

    names = qd.get("descriptors")
    parts = []
    if names is not None and names != list(DEFAULT_DESCRIPTORS):
        parts.append(" x ".join(map(str, names)) if isinstance(names, list) else str(names))
    if qd.get("selection") not in (None, "uniform"):
        parts.append(str(qd["selection"]))
    if qd.get("exploit") not in (None, 0):  # (0.0 == 0)
        parts.append(f"exploit {qd['exploit']}")
    return f"{method} ({', '.join(parts)})" if parts else method


def _arches(run_dir: Path) -> str:
    """The arch(s) the run ran on, in the order of its segments (segments.json: "cuda, then cpu" for
    a run resumed elsewhere; an older run's config.yaml `arch`, which `segments` reads as its
    first); "not recorded" otherwise."""
    from evolve.records.segments import segments

    arches = list(dict.fromkeys(str(s.get("arch")) for s in segments(run_dir)))
    return ", then ".join(arches) or "not recorded"


def _evaluation(raw) -> str:
    """"nominal", or "robust" with every setting (defaults filled, so equal settings read equal)."""
    if raw is None:
        return "nominal"
    from evolve.rollout.robust import Robust

    try:
        r = Robust.from_config(raw).to_json()
    except (ValueError, TypeError):
        return f"robust {raw}"
    scale = f"±{r['action_scale']:g} {r['action_noise']}"
    extra = [k if v is True else f"{k} {v}" for k, v in r.items()
             if k not in ("episodes", "statistic", "action_scale", "action_noise") and v]
    return f"robust {r['episodes']} x {r['statistic']} {scale}" + "".join(f", {x}" for x in extra)


def _selection(raw) -> str:
    """"none", or the final selection's settings."""
    if raw is None:
        return "none"
    from evolve.config import FinalSelection

    try:
        s = FinalSelection.from_config(raw).to_json()
    except (ValueError, TypeError):
        return str(raw)
    return (f"{s['candidates']} candidates, {s['episodes']} episodes {s['statistic']}, tolerance "
            f"{s['tolerance']:g}, rank {s['rank']}" + (f", confirm {s['confirm']}" if s["confirm"] else ""))


def _classic(settings: dict[str, str], pooled: Sequence[str]) -> str:
    """The label plots have always used: method, "robust", a body size other than 5x5, "from gN"."""
    label = settings["method"]
    if "evaluation" not in pooled and settings["evaluation"].startswith("robust"):
        label += " robust"
    if "shape" not in pooled and settings["shape"] not in ("5x5", "?"):
        label += f" {settings['shape']}"
    if "start" not in pooled and settings["start"].startswith("from"):
        label += f" {settings['start']}"
    return label


SHORT = {"pop": "pop", "generations": "generations", "steps": "steps", "evaluation": "",
         "selection": "final selection", "precision": "", "arch": "arch", "shape": "", "start": ""}


def _difference(key: str, value: str, values: Sequence[str]) -> str:
    """What a label shows of a setting in which groups of one name differ: of a value listing
    several items (evaluation, final selection), the items that not every group has."""
    if key == "selection" and value == "none":
        return "no final selection"
    common = set.intersection(*(set(v.split(", ")) for v in values))
    shown = ", ".join(p for p in value.split(", ") if p not in common) or value
    return f"{SHORT[key]} {shown}".strip()


def group_runs(run_dirs: Sequence[Path], pool: Sequence[str] = ()) -> list[Group]:
    """The runs' groups (module docstring), sorted by task and label; runs keep their order."""
    by_key: dict[tuple, Group] = {}
    values: dict[tuple, dict[str, set[str]]] = defaultdict(lambda: defaultdict(set))
    for d in run_dirs:
        s = run_settings(Path(d))
        key = tuple(s[k] for k in SETTINGS if k not in pool)
        for k in pool:
            values[key][k].add(s[k])
        if key not in by_key:
            by_key[key] = Group("", s["task"], s)
        by_key[key].runs.append(Path(d))
    groups = list(by_key.values())
    for key, g in by_key.items():
        g.settings = {**g.settings, **{k: " / ".join(sorted(v)) + " (pooled)" if len(v) > 1 else next(iter(v))
                                       for k, v in values[key].items()}}
        g.classic = _classic(g.settings, pool)
    alike: dict[tuple[str, str], list[Group]] = defaultdict(list)
    for g in groups:
        alike[(g.classic, g.task)].append(g)
    for same in alike.values():
        differ = [k for k in POOLABLE if len({g.settings[k] for g in same}) > 1]
        for g in same:
            tell = [_difference(k, g.settings[k], [o.settings[k] for o in same]) for k in differ]
            g.label = g.classic + (f" ({', '.join(tell)})" if tell else "")
    return sorted(groups, key=lambda g: (g.task, g.label))


def group_of_each_run(run_dirs: Sequence[Path], pool: Sequence[str] = ()) -> dict[Path, Group]:
    """Each run's group (`group_runs`)."""
    return {d: g for g in group_runs(run_dirs, pool) for d in g.runs}
