"""The run config: one run's configuration, frozen and typed (`RunConfig`), read by attribute only.

Its keys, their YAML types and their defaults are listed once, as the fields of `RunConfig` (each
field's `key(...)`); `COMMON` is derived from them. A method's own keys (`Problem.config_keys`) are
declared by the method and read by attribute too (`cfg.cppn_outputs`). The object sits below the
methods (evolve/methods imports it; it imports only the rollout's `Robust`), so nothing imports
upward to read a config. evolve/runs/config.py checks a YAML config into one; `RunConfig.of` reads a
run folder's config.yaml back (older files, keys missing, included); `to_yaml` gives what a run
folder's config.yaml holds.

Honest by default: a config (a YAML file, or a dict given to `Experiment.from_config`) that leaves
out `robust` and `final_selection` evolves under actuator noise and chooses its champion at the end
(`HONEST_ROBUST`, `HONEST_SELECTION`: what `sgr evolve`'s default run, configs/sgr/quick.yaml,
spells out); `robust: null` / `final_selection: null` ask for the paper's nominal evaluation. A run
folder's config.yaml that lacks them was written before they existed and meant nominal
(`ABSENT_BEFORE`). `FinalSelection` (the `final_selection` key) lives here beside `Robust`'s
parsing; choosing the champion is evolve/runs/final_selection.py's."""

from __future__ import annotations

import copy
from collections.abc import Iterable, Mapping
from dataclasses import asdict, dataclass, field, fields, replace
from types import MappingProxyType
from typing import Any

from evolve.nn.genome_record import MAX_POP  # noqa: F401 (the config's bound, kept with the INI's)
from evolve.rollout.robust import MAX_EPISODES, STATISTICS, Robust, config_dataclass
from tasks.specs import MAX_STEPS, TASKS
from tsim.backend import DEFAULT_PRECISION
from tsim.errors import SgrError

# docs/EVOLVE.md "Robust evaluation": every action carries uniform(+-1e-3) actuator noise, one fresh
# episode per genome and generation, a survivor's fitness the mean of its scores so far (8 at most)
HONEST_ROBUST = {"episodes": 1, "action_noise": "uniform", "action_scale": 0.001, "offset": 0.0,
                 "statistic": "mean", "reevaluate": True, "accumulate": True, "settle": 8}
# evolve/runs/final_selection.py: the champion chosen at the end among the final elites
HONEST_SELECTION = {"candidates": "auto", "episodes": "auto", "statistic": "mean", "tolerance": 0.05,
                    "rank": "pooled", "confirm": "auto", "holdout": "auto"}
# what a run folder's config.yaml that lacks a key meant: written before the key existed
ABSENT_BEFORE = {"robust": None, "final_selection": None}

# ------------------------------------------------ final_selection (evolve/runs/final_selection.py)
RANKS = ("min", "score", "pooled")
AUTO = "auto"
MAX_EPISODE_STEPS = MAX_STEPS  # a longer episode in a config or a record is a typo or a planted value
SHARE = 0.2  # the most the selection may simulate, as a share of the episodes the run asks for
MAXIMA = {"candidates": 16, "episodes": 32, "confirm": 32}  # an `auto` count's value on a long run
FLOORS = {"candidates": 2, "episodes": 8, "confirm": 8}  # ... and the least it shrinks to
COUNTS = ("candidates", "episodes", "confirm", "holdout")


@dataclass(frozen=True)
class FinalSelection:
    """The `final_selection` config key (null: the champion is the best-ever genome). The counts
    may be "auto": sized by the run's length (`sized`, evolve/runs/final_selection.py's docstring)."""
    candidates: int | str = AUTO  # the top final elites by recorded fitness, plus the best-ever genome
    episodes: int | str = AUTO
    statistic: str = "mean"
    tolerance: float = 0.05  # passes: score >= nominal return - tolerance x |nominal return|
    rank: str = "min"  # among those that pass: min(score, nominal return), "score" alone, or "pooled"
    confirm: int | str = 0  # > 0: the test judged again on this many fresh episodes
    holdout: int | str = AUTO  # fresh episodes of the champion alone that give its fitness

    def to_json(self) -> dict:
        """The config mapping (every key)."""
        return asdict(self)

    def robust(self, run_robust: Robust | dict | None, episodes: int | None = None) -> Robust:
        """How candidates are scored: the run's perturbation (uniform(+-1e-3) on a nominal run),
        this selection's episodes (or `episodes`: the confirmation's, the holdout's) and
        statistic, no re-evaluation."""
        base = (run_robust if isinstance(run_robust, Robust) else Robust.from_config(run_robust)) or Robust()
        return Robust(episodes or self.episodes, base.action_noise, base.action_scale, base.offset,
                      self.statistic)

    def sized(self, run_episodes: int) -> FinalSelection:
        """This selection with every "auto" count resolved for a run that asks for `run_episodes`
        episodes: the maxima shrunk by one common factor until the selection's episodes fit
        `SHARE` of them, never below the floors."""
        budget = int(SHARE * run_episodes)
        fixed = {k: getattr(self, k) for k in COUNTS if getattr(self, k) != AUTO}

        def at(step: int) -> dict:
            v = {k: fixed.get(k, max(FLOORS[k], MAXIMA[k] * step // 64)) for k in MAXIMA}
            v["holdout"] = fixed.get("holdout", v["episodes"])
            return v

        for step in range(64, 0, -1):
            counts = at(step)
            if selection_episodes(counts) <= budget:
                break
        return FinalSelection(**{**self.to_json(), **counts})

    @classmethod
    def from_config(cls, raw: object, source: str = "config") -> FinalSelection | None:
        """The checked mapping; None stays None. ValueError naming `source` and the key."""
        if raw is None:
            return None
        name = f"{source}: key 'final_selection"
        sel = config_dataclass(cls, raw, name)
        for key, least in (("candidates", 1), ("episodes", 1), ("confirm", 0), ("holdout", 1)):
            v = getattr(sel, key)
            bad = not isinstance(v, int) or isinstance(v, bool) or not least <= v <= MAX_EPISODES
            if v != AUTO and bad:
                raise SgrError(f"{name}.{key}' must be an int from {least} to {MAX_EPISODES:,} or auto, "
                               f"got {v!r}")
        try:
            Robust.from_config({"statistic": sel.statistic}, source)
        except ValueError:
            raise SgrError(f"{name}.statistic' must be one of {', '.join(STATISTICS)}, "
                           f"got {sel.statistic!r}") from None
        h = sel.tolerance
        if isinstance(h, bool) or not isinstance(h, int | float) or not (0 <= h <= 1):
            raise SgrError(f"{name}.tolerance' must be a number in [0, 1], got {h!r}")
        if sel.rank not in RANKS:
            raise SgrError(f"{name}.rank' must be one of {', '.join(RANKS)}, got {sel.rank!r}")
        return cls(sel.candidates, sel.episodes, sel.statistic, float(h), sel.rank, sel.confirm, sel.holdout)


def not_for(method: str) -> str:
    """Why a method whose evaluation changes state (`Problem.reevaluate_elites`) has no final
    selection."""
    return (f"does not apply to method {method!r}: its evaluation evolves each body's controllers "
            "again, so a candidate has no fixed robot to score")


def selection_episodes(counts: dict) -> int:
    """The episodes a selection of these counts simulates at most (+1s: the best-ever genome, the
    exact episode)."""
    return ((counts["candidates"] + 1) * (counts["episodes"] + 1 + counts["confirm"])
            + counts["holdout"])


# ---------------------------------------------------------------- the run config
def key(yaml_type: Any, default: Any) -> Any:
    """A common config key: the types its YAML value may have and its default (for a new config;
    `default` copies it)."""
    return field(metadata={"yaml": yaml_type, "default": default})


@dataclass(frozen=True)
class RunConfig:
    """One run's configuration, checked once (evolve/runs/config.py, `check_config`) or read back
    from a run folder (`RunConfig.of`). Every field with a `key(...)` is a common config key; its
    attributes are typed (`robust` a Robust, `robot_shape` a tuple). `method_keys` holds the
    method's own keys (`Problem.config_keys`), read as attributes too (`cfg.layout`); `to_yaml()`
    is config.yaml. `arch` and `precision` are recorded, not chosen: the arch the run was created
    on (None: a folder from before it was recorded) and its precision."""
    method: str = key(str, None)
    task: str = key(str, None)
    generations: int = key(int, 250)
    pop_size: int = key(int, 128)
    seed: int = key(int, 0)
    robot_shape: tuple[int, int] = key(list, [5, 5])
    episode_steps: int = key((int, str, type(None)), None)
    neat_config: str | None = key((str, type(None)), None)
    checkpoint_every: int = key(int, 5)
    render_champion: bool = key(bool, True)
    tensorboard: bool = key(bool, False)  # evolve/runs/reporters.py: each generation's scalars
    workers: int | str = key((int, str), "auto")
    imports: tuple[str, ...] = key(list, [])
    robust: Robust | None = key((dict, type(None)), HONEST_ROBUST)  # null: one exact episode
    final_selection: FinalSelection | None = key((dict, type(None)), HONEST_SELECTION)  # null: best-ever
    # evolve/runs/continuation.py; null: a fresh population. {run: PATH, generation: G}: the population
    # of that run's checkpoint after generation G, evolved on at this config's robot_shape (sgr)
    start_from: Mapping[str, Any] | None = key((dict, type(None)), None)
    method_keys: Mapping[str, Any] = field(default_factory=dict)
    arch: str | None = None
    precision: str = DEFAULT_PRECISION

    def __post_init__(self) -> None:
        object.__setattr__(self, "method_keys", MappingProxyType(dict(self.method_keys)))

    def __getattr__(self, name: str) -> Any:
        """A method's own key (only called when no field has the name)."""
        if not name.startswith("_") and name != "method_keys":
            own = self.__dict__.get("method_keys", {})
            if name in own:
                return own[name]
        raise AttributeError(f"{type(self).__name__} has no key {name!r}")

    def with_own(self, absent: Mapping[str, Any]) -> RunConfig:
        """This config with the method's keys it lacks (an older run's) set as `absent` says."""
        missing = {k: v for k, v in absent.items() if k not in self.method_keys}
        return replace(self, method_keys={**self.method_keys, **missing}) if missing else self

    def to_yaml(self) -> dict:
        """The config as config.yaml holds it (YAML values: mappings, lists), in its order: the
        common keys, the method's, then `arch` and `precision`."""
        out = {}
        for k in COMMON:
            value = getattr(self, k)
            if isinstance(value, Robust | FinalSelection):
                value = value.to_json()
            out[k] = list(value) if isinstance(value, tuple) else value
        return {**out, **self.method_keys, "arch": self.arch, "precision": self.precision}

    def replace(self, **changes) -> RunConfig:
        """A copy with `changes` (attributes, typed; a method key by its name)."""
        own = {k: changes.pop(k) for k in list(changes) if k in self.method_keys}
        if own:
            changes["method_keys"] = {**self.method_keys, **own}
        return replace(self, **changes)

    def run_episodes(self) -> int:
        """The episodes the run asks for: generations x pop_size x its robust episodes (1 when
        nominal). From the config alone, so a resumed run sizes its final selection as the
        uninterrupted one did."""
        return self.generations * self.pop_size * (self.robust.episodes if self.robust else 1)

    @classmethod
    def of(cls, raw: RunConfig | Mapping) -> RunConfig:
        """`raw` itself if it is one, else a run folder's config.yaml (a resolved config as a
        mapping) read back without checking it again: common keys an older sgr did not write take
        their defaults, a null or "evogym" `episode_steps` its length for the task, a missing
        `arch` stays None; the method's keys are those present (a method reads a key an older
        run lacks with the meaning it had then: `has`). The task must be registered (its
        `imports` imported) first."""
        if isinstance(raw, RunConfig):
            return raw
        values = {k: raw[k] if k in raw else ABSENT_BEFORE.get(k, fallback)
                  for k, (_, fallback) in COMMON.items()}
        own = [k for k in raw if k not in COMMON and k not in ("arch", "precision")]
        return cls.build({**values, **{k: raw[k] for k in own}}, own, arch=raw.get("arch"),
                         precision=raw.get("precision") or DEFAULT_PRECISION)

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


# key: (type or tuple of types, default), from RunConfig's fields: the one place they are listed
# what each common key does, in a sentence (docs/reference/config.md, `sgr evolve --help`)
KEY_DOCS: dict[str, str] = {
    "method": "How bodies and controllers are evolved: sgr, direct, nested, map-elites or ga-ppo "
              "(docs/EVOLVE.md).",
    "task": "The task robots are scored on: one of sgr's 32 (docs/TASKS.md) or one you register "
            "(imports:).",
    "generations": "How many generations the run evolves.",
    "pop_size": "Genomes per generation (neat-python's pop_size, written into the run's neat.ini).",
    "seed": "The run's seed: the same config, seed and sgr give the same run, bit for bit in f64.",
    "robot_shape": "The body grid, [rows, columns] (the paper's: [5, 5]).",
    "episode_steps": "Steps of each episode: a number, null for the task's paper length, or \"evogym\" "
                     "for evogym's registered length.",
    "neat_config": "The neat-python INI file (relative to this YAML); null: the method's own in "
                   "configs/neat/.",
    "checkpoint_every": "A checkpoint every N generations (and after the last, and at a stop); a "
                        "killed run resumes from the newest.",
    "render_champion": "Write champion.gif (its typical episode) and fitness.png when the run ends.",
    "tensorboard": "TensorBoard events of each generation's scalars in RUN/tensorboard (needs "
                   "sgr[tensorboard]).",
    "workers": "Rollout processes: a number, \"auto\" (every CPU) or \"ray\" (the actors of a Ray "
               "cluster).",
    "imports": "Python files that register your own tasks, imported when the run starts from this "
               "config (read back from a folder: only with --trust-imports).",
    "robust": "Each genome scored by K episodes with noise added to its actions (episodes, "
              "action_noise, action_scale, statistic, ...); null: one exact episode.",
    "final_selection": "At the run's end, the champion chosen afresh among the final elites by many "
                       "perturbed episodes, keeping only those that pass its test; null: the best-ever "
                       "genome.",
    "start_from": "{run: PATH, generation: G}: start from that run's population after generation G "
                  "(sgr; at another robot_shape too); null: a fresh population.",
}

COMMON: dict[str, tuple[Any, Any]] = {f.name: (f.metadata["yaml"], f.metadata["default"])
                                      for f in fields(RunConfig) if "yaml" in f.metadata}


def default(name: str, reevaluate_elites: bool = False) -> Any:
    """A common key's default for a new config (a copy). A method whose evaluation changes state
    (`Problem.reevaluate_elites`: nested, whose fitness is the best of a search run for each
    body) evolves under the same noise without averaging scores (no accumulate, settle) and has
    no final selection: both are refused for it."""
    value = copy.deepcopy(COMMON[name][1])
    if reevaluate_elites and name == "robust":
        return {k: v for k, v in value.items() if k not in ("accumulate", "settle")}
    if reevaluate_elites and name == "final_selection":
        return None
    return value


def run_episodes(cfg: RunConfig | Mapping) -> int:
    """`RunConfig.run_episodes` of a config (a mapping is read as one)."""
    return RunConfig.of(cfg).run_episodes()
