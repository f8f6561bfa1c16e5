"""A neat-python population advanced one generation at a time, with batched evaluation.

neat-python's `Population.run` evaluates one callback per generation; we need more control:
decode every genome once (cached by key), drop invalid genomes before selection (the SGR paper
removes them), skip re-simulating elites (their fitness is known and the simulation is
deterministic), and snapshot the whole state (including Python's `random`, which neat-python
uses) so a resumed run continues exactly.

neat-python draws from the global `random`. A search given a seed keeps its own state of it and
swaps it in around everything it does (`_own_random`), so two searches in one process (a notebook,
a parameter loop) do not draw from each other's stream: each gives the generations it gives alone.
A search without a seed (the nested baseline's inner populations) draws from whatever state is in
place, which inside its owner's `step` is the owner's.
"""

from __future__ import annotations

import inspect
import itertools
import math
import random
import statistics
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any

import numpy as np
from neat.reporting import ReporterSet

from evolve.search.body_distance import mean_pairwise_body_distance
from evolve.search.genome import peek

Decode = Callable[[Any], Any]  # genome -> phenotype with .valid and .body
# valid phenotypes[, their tags "<generation>/<genome key>"] -> fitness, episodes
Evaluate = Callable[..., tuple[np.ndarray, int]]


class NeatSearch:
    """One NEAT population over a method's decode/evaluate: `step` per generation, or `ask`/`tell`
    when the caller simulates. With a `seed` it keeps its own state of Python's `random` (swapped in
    around its work, the caller's left as it was); `state` checkpoints it exactly."""
    def __init__(self, neat_config, decode: Decode, evaluate: Evaluate | None, *, seed: int | None,
                 body_distance_weight: float = 0.0, state: dict | None = None,
                 reevaluate: bool = False, accumulate: bool = False, race: int = 0, settle: int = 0):
        """`seed` None: no random state of its own, the global `random` is drawn from as it is
        (populations nested in another search, inside its `step`); `reevaluate` simulates elites
        again instead of reusing their fitness (when evaluation has side effects, e.g. the nested
        baseline evolves a body's controllers, or is noisy).
        `accumulate` (with `reevaluate`): a genome's fitness is the mean of every score it has had,
        so a survivor's fitness averages over the generations it survives, and a lucky score is
        diluted instead of kept. `race` (with `accumulate`, in `step`): the `race` genomes with the
        highest fitness after a generation's evaluation are evaluated once more (their tags get
        "/race"), so those that could become elites or the champion get more episodes. `settle` (with
        `accumulate`, 0: never): a genome with `settle` scores keeps their mean and is not simulated
        again, so long-lived elites stop costing episodes."""
        if accumulate and not reevaluate:
            raise ValueError("accumulate needs reevaluate: elites must be simulated again")
        if (race or settle) and not accumulate:
            raise ValueError("race and settle need accumulate: a genome's scores are averaged")
        self.config = neat_config
        self.decode = decode
        self.evaluate = evaluate
        self.reevaluate = reevaluate
        self.race, self.settle = race, settle
        # genome key -> (sum of its scores so far, the tags of those evaluations in the order they
        # were added); None: fitness is the latest score
        self.scores: dict[int, tuple[float, list[str]]] | None = {} if accumulate else None
        gc = neat_config.genome_config
        gc.body_distance_weight = body_distance_weight
        gc.body_cache = {}
        self.reporters = ReporterSet()
        self.phenotypes: dict[int, Any] = {}
        self._owns_random = seed is not None
        self._random_state: tuple | None = None  # the own random state while outside _own_random
        self._inside = False
        if state is None:
            with self._own_random(seed):
                self._create(neat_config, gc)
        else:
            with self._own_random(state["random"] if self._owns_random else None):
                self._restore(state)

    def _create(self, neat_config, gc) -> None:
        self.stagnation = neat_config.stagnation_type(neat_config.stagnation_config, self.reporters)
        self.reproduction = neat_config.reproduction_type(neat_config.reproduction_config,
                                                          self.reporters, self.stagnation)
        self.population = self.reproduction.create_new(neat_config.genome_type, gc,
                                                       neat_config.pop_size)
        self.reproduction.ancestors.clear()
        self.species = neat_config.species_set_type(neat_config.species_set_config, self.reporters)
        self.generation = 0
        self.best: dict | None = None
        self.pending_build_s = self._decode_all()
        self.species.speciate(neat_config, self.population, self.generation)

    def _saved_random(self) -> tuple | None:
        """The own random state as it stands outside `_own_random` (None: the global one is it)."""
        return self._random_state if self._owns_random and not self._inside else None

    @contextmanager
    def _own_random(self, start: int | tuple | None = None) -> Iterator[None]:
        """While inside, Python's `random` is this search's own state (seeded with an int `start`,
        or set to a `getstate()` tuple; else the one saved when last outside), and the caller's is
        restored after. Nothing is swapped for a search without a seed, nor when already inside."""
        if not self._owns_random or self._inside:
            yield
            return
        caller = random.getstate()
        if isinstance(start, int):
            random.seed(start)
        else:
            random.setstate(start if start is not None else self._random_state)
        self._inside = True
        try:
            yield
        finally:
            self._inside = False
            self._random_state = random.getstate()
            random.setstate(caller)

    # ------------------------------------------------------------------ one generation
    def step(self) -> dict:
        """Evaluate the current generation, then breed and speciate the next. Returns the row of
        generations.csv for the evaluated generation."""
        with self._own_random():  # evaluate too: a nested method's inner searches draw from it
            return self._step()

    def _step(self) -> dict:
        t0 = time.perf_counter()
        todo = self.ask()
        t1 = time.perf_counter()
        fit, episodes = self._evaluate(todo, "")
        if self.race and todo:
            episodes += self._race(todo, fit)
        sim_s = time.perf_counter() - t1
        row = self.tell(fit, episodes)
        row.update(build_s=self._build_s, sim_s=sim_s, total_s=time.perf_counter() - t0)
        return row

    def _evaluate(self, todo: list[tuple[int, Any]], suffix: str) -> tuple[np.ndarray, int]:
        """Fitness and episodes of `todo`, each tagged "<generation>/<key><suffix>"."""
        phenotypes = [p for _, p in todo]
        if not todo:
            return np.zeros(0), 0
        if _takes_tags(self.evaluate):
            return self.evaluate(phenotypes, [f"{self.generation}/{k}{suffix}" for k, _ in todo])
        return self.evaluate(phenotypes)  # a method written before tags existed

    def _race(self, todo: list[tuple[int, Any]], fit: np.ndarray) -> int:
        """The extra evaluation of the `race` genomes of `todo` whose fitness with this generation's
        score `fit` would be highest (ties: the lower key); their extra score joins `scores` here,
        before `tell` adds `fit`. Returns the episodes simulated."""
        ahead = [self._mean(k, f) for (k, _), f in zip(todo, fit, strict=True)]
        order = sorted(range(len(todo)), key=lambda i: (-_rank_value(ahead[i]), todo[i][0]))
        chosen = [todo[i] for i in order[:self.race]]
        extra, episodes = self._evaluate(chosen, "/race")
        for (k, _), f in zip(chosen, extra, strict=True):
            self._add_score(k, float(f), f"{self.generation}/{k}/race")
        return episodes

    def _settled(self, key: int) -> bool:
        """Whether `key` has the `settle` scores after which its mean stands."""
        return bool(self.settle) and len(self.scores.get(key, (0.0, []))[1]) >= self.settle

    def _mean(self, key: int, score: float) -> float:
        """The fitness `key` would have with one more score."""
        total, tags = self.scores.get(key, (0.0, []))
        return (total + float(score)) / (len(tags) + 1)

    def _add_score(self, key: int, score: float, tag: str) -> float:
        """Adds the score of evaluation `tag` to `key`'s record; returns its fitness, the mean of all
        its scores (summed in the order they came: `rescore_champion` sums them so)."""
        total, tags = self.scores.get(key, (0.0, []))
        self.scores[key] = (total + score, [*tags, tag])
        return (total + score) / (len(tags) + 1)

    def ask(self) -> list[tuple[int, Any]]:
        """(key, phenotype) of the genomes of this generation that need a fitness."""
        with self._own_random():
            return self._ask()

    def _ask(self) -> list[tuple[int, Any]]:
        self._build_s = self.pending_build_s + self._decode_all()
        self._todo = [k for k, g in self.population.items() if self.phenotypes[k].valid
                      and (g.fitness is None or self.reevaluate and not self._settled(k))]
        return [(k, self.phenotypes[k]) for k in self._todo]

    def tell(self, fitness: Sequence[float], episodes: int | None = None) -> dict:
        """Fitness for the genomes `ask` returned; breeds the next generation."""
        with self._own_random():
            return self._tell(fitness, episodes)

    def _tell(self, fitness: Sequence[float], episodes: int | None) -> dict:
        for k, f in zip(self._todo, fitness, strict=True):
            self.population[k].fitness = (float(f) if self.scores is None
                                          else self._add_score(k, float(f), f"{self.generation}/{k}"))
        valid = {k: g for k, g in self.population.items() if self.phenotypes[k].valid}
        n_invalid = len(self.population) - len(valid)
        row = self._stats(valid, n_invalid, len(self._todo) if episodes is None else episodes)
        self._track_best(valid)
        t2 = time.perf_counter()
        self._drop(valid)
        self.population = self.reproduction.reproduce(self.config, self.species, self.config.pop_size,
                                                      self.generation)
        if not self.species.species:  # complete extinction: start afresh (reset_on_extinction)
            self.population = self.reproduction.create_new(self.config.genome_type,
                                                           self.config.genome_config,
                                                           self.config.pop_size)
        self._trim_history()
        if self.scores is not None:  # only the living can be scored again
            self.scores = {k: v for k, v in self.scores.items() if k in self.population}
        neat_s = time.perf_counter() - t2
        self.pending_build_s = self._decode_all()
        t3 = time.perf_counter()
        self.species.speciate(self.config, self.population, self.generation)
        row["neat_s"] = neat_s + time.perf_counter() - t3
        self.generation += 1
        return row

    def _trim_history(self) -> None:
        """neat-python keeps two records that grow with every generation and are pickled into every
        checkpoint: the reproduction's `ancestors` (the parents of every genome ever made; nothing
        reads it) and each species' whole `fitness_history`, of which stagnation reads only the
        maximum. Drop the first and keep the second as its maximum. No result changes: Python's max
        folds from the left, so max([max(h), x]) is max(h + [x]) for any values, NaN included."""
        self.reproduction.ancestors.clear()
        for s in self.species.species.values():
            if len(s.fitness_history) > 1:
                s.fitness_history[:] = [max(s.fitness_history)]

    def _decode_all(self) -> float:
        """Decode the genomes not decoded yet; returns the seconds it took, which make a generation's
        decoding time (generations.csv's build_s, the console's "decode")."""
        t = time.perf_counter()
        self.phenotypes = {k: self.phenotypes.get(k) or self.decode(g) for k, g in self.population.items()}
        # speciation compares with last generation's representatives: keep their bodies too
        old = self.config.genome_config.body_cache
        cache = {k: p.body for k, p in self.phenotypes.items()}
        for s in self.species.species.values():
            r = s.representative
            if r is not None and r.key not in cache:
                cache[r.key] = old[r.key] if r.key in old else self.decode(r).body
        self.config.genome_config.body_cache = cache
        return time.perf_counter() - t

    def _drop(self, valid: dict) -> None:
        """Invalid genomes leave the population and their species before selection."""
        self.population = valid
        for sid in list(self.species.species):
            s = self.species.species[sid]
            s.members = {k: g for k, g in s.members.items() if k in valid}
            if not s.members:
                del self.species.species[sid]

    def _stats(self, valid: dict, n_invalid: int, episodes: int) -> dict:
        f = [g.fitness for g in valid.values()]
        return {"generation": self.generation,
                "best": max(f) if f else float("nan"),
                "mean": statistics.fmean(f) if f else float("nan"),
                "median": statistics.median(f) if f else float("nan"),
                "n_species": len(self.species.species), "n_valid": len(valid),
                "n_invalid": n_invalid, "episodes": episodes,
                "body_diversity": self._body_diversity(valid)}

    def _body_diversity(self, valid: dict) -> float:
        """The mean pairwise body distance of the generation's valid genomes (eq. 2 per cell,
        `mean_pairwise_body_distance`), NaN where phenotypes have no body; reads nothing random."""
        bodies = [getattr(self.phenotypes[k], "body", None) for k in valid]
        if any(b is None for b in bodies):
            return float("nan")
        return mean_pairwise_body_distance(bodies)

    def _track_best(self, valid: dict) -> None:
        if not valid:
            return
        k, g = max(valid.items(), key=lambda kv: (kv[1].fitness, -kv[0]))
        if self.best is None or g.fitness > self.best["fitness"]:
            self.best = {"fitness": g.fitness, "generation": self.generation, "key": k,
                         "genome": g, "phenotype": self.phenotypes[k]}
            if self.scores is not None:  # the evaluations its fitness averages
                self.best["tags"] = list(self.scores[k][1])

    # ------------------------------------------------------------------ checkpoint state
    def state(self) -> dict:
        """Everything that decides the rest of the run, picklable, taken without side effects.

        Besides the population, species, reproduction and Python's `random`, neat-python 2 keeps
        run state in counters (genome, species and node keys; the node counter lives on the
        genome config, which a new process rebuilds from the INI) and in the innovation tracker
        (held by the reproduction). Counters are stored as their next value: pickling neat-python's
        own objects would consume one."""
        gc = self.config.genome_config
        node_key, gc.node_indexer = peek(gc.node_indexer)
        species_key, self.species.indexer = peek(self.species.indexer)
        genome_key, self.reproduction.genome_indexer = peek(self.reproduction.genome_indexer)
        repro = dict(self.reproduction.__dict__, genome_indexer=genome_key, reporters=None)
        species = dict(self.species.__dict__, indexer=species_key, reporters=None)
        best = None if self.best is None else {k: v for k, v in self.best.items() if k != "phenotype"}
        state = {"format": STATE_FORMAT, "generation": self.generation, "population": self.population,
                 "species": species, "reproduction": repro, "node_indexer": node_key,
                 "random": own if (own := self._saved_random()) is not None else random.getstate(),
                 "best": best, "pending_build_s": self.pending_build_s}
        if self.scores is not None:
            state["scores"] = {k: (total, list(tags)) for k, (total, tags) in self.scores.items()}
        return state

    def _restore(self, state: dict) -> None:
        self.generation = state["generation"]
        self.population = state["population"]
        self.species = self.config.species_set_type(self.config.species_set_config, self.reporters)
        self.species.__dict__.update(_counted(state["species"], "indexer"), reporters=self.reporters)
        self.reproduction = self.config.reproduction_type(self.config.reproduction_config,
                                                          self.reporters, None)
        self.reproduction.__dict__.update(_counted(state["reproduction"], "genome_indexer"),
                                          reporters=self.reporters)
        self.stagnation = self.reproduction.stagnation
        self.stagnation.reporters = self.reporters
        gc = self.config.genome_config
        gc.innovation_tracker = self.reproduction.innovation_tracker
        nxt = state.get("node_indexer")
        gc.node_indexer = None if nxt is None else itertools.count(nxt)
        if not self._owns_random:  # (an owned state is set by _own_random)
            random.setstate(state["random"])
        if self.scores is not None:
            if state.get("scores") is None:
                raise ValueError("the checkpoint holds no score records, which this run's accumulated "
                                 "fitness needs")
            self.scores = {k: (total, list(tags)) for k, (total, tags) in state["scores"].items()}
        self.pending_build_s = state["pending_build_s"]
        self._decode_all()
        self.best = state["best"]
        if self.best is not None:
            self.best["phenotype"] = self.decode(self.best["genome"])


def _rank_value(f: float) -> float:
    """A fitness for ranking: NaN (an unstable episode) last."""
    return -math.inf if math.isnan(f) else f


def _takes_tags(evaluate: Callable) -> bool:
    """Whether `evaluate` accepts the tags (robust evaluation's noise names) after the phenotypes."""
    try:
        params = list(inspect.signature(evaluate).parameters.values())
    except (TypeError, ValueError):
        return True
    positional = [p for p in params if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
    return len(positional) >= 2 or any(p.kind == p.VAR_POSITIONAL for p in params)


STATE_FORMAT = 2  # 1 (unversioned): species pickled whole, no node counter


def _counted(saved, key: str) -> dict:
    """A saved object's attributes with counter `key` (stored as its next value) made a counter
    again; format-1 checkpoints hold the species set itself."""
    attrs = dict(saved if isinstance(saved, dict) else vars(saved))
    if isinstance(attrs.get(key), int):
        attrs[key] = itertools.count(attrs[key])
    return attrs
