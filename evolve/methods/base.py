"""The contract of a method: a `Problem` turns genomes into robots and robots into fitness.

`NeatSearch` (evolve/search) runs NEAT over the method's genomes and asks the problem for
everything method-specific: how a genome decodes (`decode`), how a generation of decoded robots
is evaluated (`evaluate`), what the champion file holds (`champion`), which neat-python settings
the method fixes (`neat_overrides`), its config keys, and any state of its own that a checkpoint
must keep (`state`/`restore`), what it can do (`starts_from_runs`, `keeps_archive`,
`decode_refusal`) and the config sgr ships for it (`packaged`). A method is one file with one
`Problem` subclass and one registration (evolve/methods/__init__.py).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from typing import Any, ClassVar, Protocol

import numpy as np

from evolve.config import RunConfig
from evolve.methods.packaged import PackagedConfig
from evolve.nn.genome_record import genome_json
from evolve.rollout.pool import PolicyFactory, RolloutPool
from evolve.rollout.robust import Robust
from evolve.search.state_codec import decode_search_state, encode_search_state
from tasks.behaviour import FEATURES
from tsim.errors import SgrError

# config key -> (type or tuple of types, default)
Schema = dict[str, tuple[Any, Any]]


class Phenotype(Protocol):
    """What `decode` returns: at least the body and whether it is a valid robot (invalid genomes
    are removed before selection and never simulated)."""

    body: np.ndarray
    valid: bool


class Problem:
    """Base class of a method: it turns genomes into robots and robots into fitness.

    Subclass it, set `name`, and add it to evolve.methods.METHODS. `NeatSearch` runs NEAT over the
    method's genomes and asks the problem for everything method-specific: how a genome decodes
    (`decode`), how a generation of decoded robots is evaluated (`evaluate`), what the champion
    file holds (`champion`), which neat-python settings the method fixes (`neat_overrides`), its
    config keys, and any state of its own that a checkpoint must keep (`state`/`restore`). The
    module docstring of evolve/methods/base.py says more.
    """
    name: ClassVar[str]  # the config's `method`
    config_keys: ClassVar[Schema] = {}  # the method's keys beyond the common ones (evolve/runs/config.py)
    config_docs: ClassVar[dict[str, str]] = {}  # what each of `config_keys` does, in a sentence
    # keys holding files (relative to the YAML that names them) -> default file in configs/neat/
    default_files: ClassVar[dict[str, str]] = {}
    uses_neat: ClassVar[bool] = True  # False: no neat-python config (no neat.ini in its runs)
    reevaluate_elites: ClassVar[bool] = False  # True when evaluation changes state (nested's inner search)
    # what a key of `config_keys` that an older run's config.yaml lacks meant, where that is not its
    # default (the key did not exist then)
    absent_before: ClassVar[dict[str, Any]] = {}
    # whether `rollout` records behaviour features (a search that places robots by what they do sets
    # it), and the last rollout's, (n, len(FEATURES)), when it did
    record_behaviour: bool = False
    behaviour: np.ndarray | None = None
    # what the method can do, declared here so that no other module names it
    starts_from_runs: ClassVar[bool] = False  # `start_from`/`--from`: its genomes continue a run of it
    keeps_archive: ClassVar[bool] = False  # its search keeps an archive (elites.json, archive.png)
    # the config sgr ships for it per task, configs/<name>/<task>.yaml (tools/gen_configs.py writes
    # them); None: none (a method of the user's gives `default_config` instead)
    packaged: ClassVar[PackagedConfig | None] = None

    @classmethod
    def decode_refusal(cls, cfg: RunConfig, shape: tuple[int, int]) -> str | None:
        """Why a run's champion genome cannot be decoded at `shape` (`sgr decode`), None when it can.

        A method without NEAT genomes cannot; the others can at any size unless they say.
        """
        if not cls.uses_neat:
            return (f"a {cls.name} run's champion is a body and a controller trained for it, no genome to "
                    "decode at another size (decode sgr runs)")
        return None

    def __init__(self, cfg: RunConfig | Mapping, neat_config, pool: RolloutPool | None = None):
        """`cfg` is the run's config (`RunConfig`; a resolved config mapping is read as one);
        `pool` simulates episodes. The method's keys an older run lacks read as they meant then
        (`absent_before`, else the key's default)."""
        absent = {k: self.absent_before.get(k, d) for k, (_, d) in self.config_keys.items()}
        self.cfg = RunConfig.of(cfg).with_own(absent)
        self.neat_config = neat_config
        self.pool = pool or RolloutPool(1)

    def body_distance_weight(self) -> float:
        """The body's weight in speciation's genome distance.

        It is the `body_distance_weight` key of sgr and direct; a method without it gets 0 (plain
        NEAT speciation).
        """
        return self.cfg.body_distance_weight if "body_distance_weight" in self.config_keys else 0.0

    @classmethod
    def validate(cls, cfg: RunConfig, source: str) -> None:
        """Value checks beyond the schema's types; raise ValueError naming `source` and the key."""

    @classmethod
    def neat_overrides(cls, cfg: RunConfig) -> dict[str, dict[str, str]]:
        """INI values the method fixes, by section (e.g. the network's input and output counts)."""
        return {}

    @classmethod
    def default_config(cls, task: str) -> dict | None:
        """The config `sgr evolve --method NAME --task TASK` runs where sgr ships none for the task.

        That is where there is no configs/NAME/TASK.yaml (a method of the user's). The config's keys
        beyond `method` and `task`; None: none.
        """
        return None

    def decode(self, genome) -> Phenotype:
        """One genome -> its phenotype, without simulating.

        It must be deterministic and free of side effects: the search caches it by genome key and
        decodes again after a resume.
        """
        raise NotImplementedError

    def evaluate(self, phenotypes: Sequence[Phenotype],
                 tags: Sequence[str] | None = None) -> tuple[np.ndarray, int]:
        """Fitness of each (valid) phenotype and the number of episodes simulated.

        Args:
            phenotypes: The phenotypes to score, as `decode` returned them (valid ones).
            tags: Name each phenotype's evaluation uniquely within the run (the search passes
                "<generation>/<genome key>"); robust evaluation draws its noise from them (`rollout`).

        Returns:
            The fitnesses, one per phenotype, and the number of episodes simulated.
        """
        raise NotImplementedError

    def rollout(self, bodies: Sequence[np.ndarray], items: Sequence, factory: PolicyFactory,
                tags: Sequence[str] | None) -> tuple[np.ndarray, int]:
        """Fitness of each robot and the number of episodes simulated.

        A robot's fitness is its episode return, or with the config's `robust` key the statistic
        over K perturbed episodes, the K episodes of every robot in one batch; episode k of the
        robot tagged t is perturbed by `episode_keys(seed, [t], k)` alone (`Robust.noise`).

        With `record_behaviour` set, `behaviour` is then each robot's behaviour features
        (tasks/behaviour.py), the mean over its K episodes.

        Args:
            bodies: The robots' bodies, as `RolloutPool.run` takes them.
            items: What `factory` makes each robot's policy of, as `RolloutPool.run` takes them.
            factory: Makes the policies, as `RolloutPool.run` takes it.
            tags: Name each robot's evaluation (as `evaluate`'s); None: their indices.

        Returns:
            The fitnesses, one per robot, and the number of episodes simulated.
        """
        cfg = self.cfg
        robust = cfg.robust  # parsed once, with the config
        record = self.record_behaviour
        self.behaviour = None
        if robust is None:
            out = self.pool.run(cfg.task, bodies, items, factory, cfg.episode_steps, record=record)
            if record:
                out, self.behaviour = out[:, 0].copy(), out[:, 1:]
            return out, len(bodies)
        n, k = len(bodies), robust.episodes
        if n == 0:
            if record:
                self.behaviour = np.zeros((0, len(FEATURES)))
            return np.zeros(0), 0
        tags = [str(i) for i in range(n)] if tags is None else list(tags)
        returns = self.pool.run(cfg.task, list(bodies) * k, list(items) * k, factory,
                                cfg.episode_steps, robust.noise(cfg.seed, tags), record=record)
        if record:
            self.behaviour = returns[:, 1:].reshape(k, n, -1).mean(axis=0)
            returns = returns[:, 0].copy()
        return robust.score(returns.reshape(k, n)), n * k

    @contextmanager
    def scored_with(self, robust: Robust | dict | None) -> Iterator[None]:
        """Inside, `evaluate` scores as `robust` says instead of as the run's config does.

        A run's final selection scores its candidates this way.

        Args:
            robust: The scoring: a mapping is the config key; None: one exact episode.
        """
        cfg = self.cfg
        if not isinstance(robust, Robust | None):
            robust = Robust.from_config(robust)
        self.cfg = cfg.replace(robust=robust)
        try:
            yield
        finally:
            self.cfg = cfg

    def champion(self, phenotype: Phenotype) -> dict:
        """The champion file's method-specific keys: at least `body` and `controller` (JSON)."""
        raise NotImplementedError

    def champion_of(self, genome, phenotype: Phenotype) -> dict:
        """`champion`'s keys for `genome`, decoded to `phenotype`.

        A method whose controller is a function of the genome may record it as that (SGR:
        evolve/methods/sgr/record.py), since the champion file holds the genome too.
        """
        return self.champion(phenotype)

    def genome_record(self, genome) -> dict:
        """What champion.json holds as `genome`: a NEAT genome's record (`genome_json`).

        A method whose search has no NEAT genome records what it has (at least `key`).
        """
        return genome_json(genome)

    @classmethod
    def compact_controller(cls, record: dict, controller, raw: dict | None) -> dict | None:
        """An older champion `record`'s controller in the method's shortest exact format, or None.

        What `sgr migrate` writes, once it reads back as the same controller bit for bit; None keeps
        the record's as it is.

        Args:
            record: The older champion record.
            controller (Any): Its `controller`, as read.
            raw: Its run's config.yaml, when there is one.
        """
        return None

    def state(self) -> dict:
        """The method's own run state for checkpoints (beyond the NEAT population), as JSON data.

        Numbers, strings, lists and dicts only: checkpoints are JSON, never pickles.
        """
        return {}

    @classmethod
    def decode_state(cls, data, cfg: RunConfig) -> dict:
        """`state`'s data read back from a checkpoint, checked and made into what `restore` takes.

        It must build nothing from names in the data.

        Raises:
            ValueError: A field is bad; the message names it.
        """
        if data != {}:
            raise ValueError(f"problem: {cls.name} keeps no state of its own, got {str(data)[:60]}")
        return {}

    def restore(self, state: dict) -> None:
        """Take back what `decode_state` returned, in a fresh process."""

    def make_search(self, neat_config, seed: int, state: dict | None = None) -> Any | None:
        """The method's own search, or None for NEAT's (`NeatSearch`, built by the run).

        One of its own has NeatSearch's face: `generation`, `step()` -> the generation's row,
        `best`, `population`, `decode` and `state()` (evolve/search/archive.py).
        """
        return None

    @classmethod
    def encode_search(cls, state: dict) -> dict:
        """The search's `state()` as a checkpoint's JSON data (NEAT's: evolve/search/state_codec.py)."""
        return encode_search_state(state)

    @classmethod
    def decode_search(cls, data, neat_config, cfg: RunConfig) -> dict:
        """`encode_search`'s data checked and built back into the state the search restores from."""
        return decode_search_state(data, neat_config)


def positive(cfg: RunConfig, source: str, *keys: str) -> None:
    """Raise naming the first of `keys` whose value is below 1."""
    for key in keys:
        if getattr(cfg, key) < 1:
            raise SgrError(f"{source}: key {key!r} must be >= 1, got {getattr(cfg, key)}")
