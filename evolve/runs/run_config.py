"""The run-config object: one run's configuration, frozen and typed (`RunConfig`), and the common
schema its keys come from (`COMMON`: types and defaults, the one place the defaults live).
evolve/runs/config.py checks a YAML config into one; `RunConfig.of` reads a run folder's
config.yaml back. Methods, the search and the rollouts read it; none parses a key again.

Honest by default: a config (a YAML file, or a dict given to `Experiment.from_config`) that leaves
out `robust` and `final_selection` evolves under actuator noise and chooses its champion at the end
(`HONEST_ROBUST`, `HONEST_SELECTION`: what `sgr evolve`'s default run, configs/sgr/quick.yaml,
spells out); `robust: null` / `final_selection: null` ask for the paper's nominal evaluation. A run
folder's config.yaml that lacks them was written before they existed and meant nominal
(`ABSENT_BEFORE`)."""

from __future__ import annotations

import copy
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field, fields, replace
from types import MappingProxyType
from typing import Any

from evolve.rollout.robust import Robust
from evolve.runs.final_selection import FinalSelection
from tasks.specs import TASKS

# docs/EVOLVE.md "Robust evaluation": every action carries uniform(+-1e-3) actuator noise, one fresh
# episode per genome and generation, a survivor's fitness the mean of its scores so far (8 at most)
HONEST_ROBUST = {"episodes": 1, "action_noise": "uniform", "action_scale": 0.001, "offset": 0.0,
                 "statistic": "mean", "reevaluate": True, "accumulate": True, "settle": 8}
# evolve/runs/final_selection.py: the champion chosen at the end among the final elites
HONEST_SELECTION = {"candidates": "auto", "episodes": "auto", "statistic": "mean", "tolerance": 0.05,
                    "rank": "pooled", "confirm": "auto", "holdout": "auto"}
# key: (type or tuple of types, default); the method's own keys come from its Problem class
COMMON: dict[str, tuple[Any, Any]] = {
    "method": (str, None),
    "task": (str, None),
    "generations": (int, 250),
    "pop_size": (int, 128),
    "seed": (int, 0),
    "robot_shape": (list, [5, 5]),
    "episode_steps": ((int, str, type(None)), None),
    "neat_config": ((str, type(None)), None),
    "checkpoint_every": (int, 5),
    "render_champion": (bool, True),
    "tensorboard": (bool, False),  # evolve/runs/reporters.py: each generation's scalars in RUN/tensorboard
    "workers": ((int, str), "auto"),
    "imports": (list, []),
    "robust": ((dict, type(None)), HONEST_ROBUST),  # evolve/rollout/robust.py; null: one exact episode
    # evolve/runs/final_selection.py; null: the champion is the best-ever genome
    "final_selection": ((dict, type(None)), HONEST_SELECTION),
    # evolve/runs/continuation.py; null: a fresh population. {run: PATH, generation: G}: the population
    # of that run's checkpoint after generation G, evolved on at this config's robot_shape (sgr)
    "start_from": ((dict, type(None)), None),
}
# what a run folder's config.yaml that lacks a key meant: written before the key existed
ABSENT_BEFORE = {"robust": None, "final_selection": None}


def default(key: str, reevaluate_elites: bool = False) -> Any:
    """A common key's default for a new config (a copy). A method whose evaluation changes state
    (`Problem.reevaluate_elites`: nested, whose fitness is the best of a search run for each
    body) evolves under the same noise without averaging scores (no accumulate, settle) and has
    no final selection: both are refused for it."""
    value = copy.deepcopy(COMMON[key][1])
    if reevaluate_elites and key == "robust":
        return {k: v for k, v in value.items() if k not in ("accumulate", "settle")}
    if reevaluate_elites and key == "final_selection":
        return None
    return value


@dataclass(frozen=True)
class RunConfig(Mapping[str, Any]):
    """One run's configuration, checked once (`check_config`) or read back from a run folder
    (`RunConfig.of`). Its attributes are typed (`robust` a Robust, `robot_shape` a tuple);
    `cfg["key"]` gives a key's YAML value, as config.yaml holds it, and `dict(cfg)` the whole
    file. `method_keys` holds the method's own keys (`Problem.config_keys`), also read as
    `cfg["key"]`. `arch` and `precision` are recorded, not chosen: the arch the run was created
    on (None: a folder from before it was recorded) and its precision."""
    method: str
    task: str
    generations: int
    pop_size: int
    seed: int
    robot_shape: tuple[int, int]
    episode_steps: int
    neat_config: str | None
    checkpoint_every: int
    render_champion: bool
    tensorboard: bool
    workers: int | str
    imports: tuple[str, ...]
    robust: Robust | None
    final_selection: FinalSelection | None
    start_from: Mapping[str, Any] | None
    method_keys: Mapping[str, Any] = field(default_factory=dict)
    arch: str | None = None
    precision: str = "f64"

    def __post_init__(self) -> None:
        object.__setattr__(self, "method_keys", MappingProxyType(dict(self.method_keys)))

    def __getitem__(self, key: str) -> Any:
        if key in self.method_keys:
            return self.method_keys[key]
        if key not in _FIELDS or key == "method_keys":
            raise KeyError(key)
        value = getattr(self, key)
        if isinstance(value, Robust | FinalSelection):
            return value.to_json()
        return list(value) if isinstance(value, tuple) else value

    def __iter__(self) -> Iterator[str]:
        yield from COMMON
        yield from self.method_keys
        yield from ("arch", "precision")

    def __len__(self) -> int:
        return len(COMMON) + len(self.method_keys) + 2

    def replace(self, **changes) -> RunConfig:
        """A copy with `changes` (attributes, typed; a method key by its name)."""
        own = {k: changes.pop(k) for k in list(changes) if k in self.method_keys}
        if own:
            changes["method_keys"] = {**self.method_keys, **own}
        return replace(self, **changes)

    @classmethod
    def of(cls, cfg: Mapping) -> RunConfig:
        """`cfg` itself if it is one, else a run folder's config.yaml (a resolved config as a
        mapping) read back without checking it again: common keys an older sgr did not write take
        their defaults, a null or "evogym" `episode_steps` its length for the task, a missing
        `arch` stays None; the method's keys are those present (a method reads a key an older
        run lacks with the meaning it had then). The task must be registered (its `imports`
        imported) first."""
        if isinstance(cfg, RunConfig):
            return cfg
        values = {k: cfg[k] if k in cfg else ABSENT_BEFORE.get(k, fallback)
                  for k, (_, fallback) in COMMON.items()}
        own = [k for k in cfg if k not in COMMON and k not in ("arch", "precision")]
        return cls.build({**values, **{k: cfg[k] for k in own}}, own, arch=cfg.get("arch"),
                         precision=cfg.get("precision") or "f64")

    @classmethod
    def build(cls, values: Mapping, method_keys: Iterable[str], *, arch: str | None, precision: str,
              robust: Robust | None = None, selection: FinalSelection | None = None) -> RunConfig:
        """From a config's values (every common key, and `method_keys`); `robust` and `selection`
        already parsed, else parsed here."""
        common = {k: values[k] for k in COMMON}
        common["robot_shape"] = tuple(common["robot_shape"])
        common["imports"] = tuple(common["imports"] or ())
        common["episode_steps"] = TASKS[common["task"]].episode_length(common["episode_steps"])
        common["robust"] = robust or Robust.from_config(common["robust"])
        common["final_selection"] = selection or FinalSelection.from_config(common["final_selection"])
        return cls(**common, method_keys={k: values[k] for k in method_keys}, arch=arch,
                   precision=precision)


_FIELDS = {f.name for f in fields(RunConfig)}
