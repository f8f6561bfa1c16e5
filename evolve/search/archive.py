"""MAP-Elites' search (the map-elites method, evolve/methods/map_elites.py): an archive of the best
robot per cell of a grid over descriptors, bred with NEAT's operators; beside NEAT's own search
(evolve/search/neat_search.py), with the same face (`generation`, `step()`, `best`, `population`,
`decode`, `state()`).

The archive is pyribs' `GridArchive` (an optional extra: `pip install 'sgr[qd]'`). pyribs stores
solutions as float vectors, so its solution is the genome's key, and the genomes (with their
scores) live in this search's store of elites keyed by the archive's cell index. Honest by
default, elites are re-scored as evaluations accumulate (`robust: accumulate`): up to
`qd.rescore` elites with the fewest scores get one more evaluation a generation until they have
`settle`; an elite's objective is the mean of its scores so far. pyribs only ever raises a cell's
objective, so after the re-scoring the archive is rebuilt from the store (cleared, the elites added
with their new means, then the children offered): the store is what the checkpoint holds, the
archive is a function of it. An elite whose mean turns NaN (an unstable episode) leaves the archive.

The method's problem gives the search its settings (`problem.qd`: descriptors and their measure,
resolution, batch, parent selection, ...), its decoder and its evaluation.
"""

from __future__ import annotations

import math
import random
import statistics
import time
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np

from evolve.search.body_distance import mean_pairwise_body_distance
from evolve.search.genome import peek
from evolve.search.state_codec import (
    StateError,
    check,
    decode_genomes,
    decode_random,
    encode_genomes,
    encode_random,
    get,
    row,
)
from tasks.behaviour import FEATURES

MAX_TRIES = 20  # genomes made per child asked for, at most, before a generation goes on with fewer valid
STATE_FORMAT = "sgr-map-elites-1"
TOURNAMENT = 4  # elites drawn for each exploiting parent, the fittest taken


@dataclass
class Elite:
    """A genome in (or offered to) the archive: its phenotype, descriptors, the sum and tags of its
    scores (its fitness is their mean, summed in the order they came) and, when the run records
    behaviour, the sum of its evaluations' behaviour features (its descriptors read their mean)."""
    genome: Any
    phenotype: Any
    measures: np.ndarray
    total: float
    tags: list[str]
    born: int  # the search's generation (from 0) it was made in
    features_total: np.ndarray | None = None

    @property
    def fitness(self) -> float:
        """The mean of its scores."""
        return self.total / len(self.tags)

    @property
    def features(self) -> np.ndarray | None:
        """The mean of its evaluations' behaviour features (None: not recorded)."""
        return None if self.features_total is None else self.features_total / len(self.tags)


class MapElitesSearch:
    """MAP-Elites over a `MapElitesProblem`: `step` per generation; `elites` maps a cell index of
    the archive to its `Elite`; `best` is the best elite (as `NeatSearch.best`); `state` checkpoints
    it exactly (JSON data)."""

    def __init__(self, problem: Any, neat_config, *, seed: int, state: dict | None = None):
        from neat.innovation import InnovationTracker
        from ribs.archives import GridArchive

        self.problem, self.config, self.qd = problem, neat_config, problem.qd
        self.decode = problem.decode
        robust = problem.cfg.robust
        self.reevaluate = robust is not None and robust.reevaluate
        self.accumulate = robust is not None and robust.accumulate
        self.settle = robust.settle if robust is not None else 0
        self.archive = GridArchive(solution_dim=1, dims=list(self.qd.resolution), ranges=list(self.qd.ranges),
                                   qd_score_offset=self.qd.score_offset, dtype=np.float64)
        self.elites: dict[int, Elite] = {}
        self.curiosity: dict[int, float] = {}  # genome key of an elite -> its curiosity score
        self.best: dict | None = None
        gc = neat_config.genome_config
        if state is None:
            self.generation, self.next_key = 0, 1
            gc.node_indexer = None  # neat-python starts it after the output nodes
            self.tracker = InnovationTracker()
            self._random_state = random.Random(seed).getstate()
        else:
            self._restore(state)
        gc.innovation_tracker = self.tracker

    @contextmanager
    def _own_random(self) -> Iterator[None]:
        """Python's `random` (which neat-python's operators draw from) is this search's own state
        while inside; the caller's is put back after."""
        caller = random.getstate()
        random.setstate(self._random_state)
        try:
            yield
        finally:
            self._random_state = random.getstate()
            random.setstate(caller)

    @property
    def population(self) -> dict[int, Any]:
        """The elites' genomes by key, each with its fitness (final selection's candidates)."""
        return {e.genome.key: e.genome for e in self.elites.values()}

    def cell(self, index: int) -> tuple[int, ...]:
        """The grid coordinates of a cell index of the archive."""
        return tuple(int(i) for i in self.archive.int_to_grid_index([index])[0])

    # ------------------------------------------------------------------ one generation
    def step(self) -> dict:
        """Breed, evaluate and insert one generation; returns its row of generations.csv."""
        with self._own_random():
            return self._step()

    def _step(self) -> dict:
        t0 = time.perf_counter()
        self.tracker.reset_generation()
        bred, n_invalid = self._breed()
        children = [(c, p) for c, p, _ in bred]
        t1 = time.perf_counter()
        again = self._to_rescore()
        g = self.generation
        phenotypes = [p for _, p in children] + [self.elites[c].phenotype for c in again]
        tags = [f"{g}/{c.key}" for c, _ in children] + [f"{g}/{self.elites[c].genome.key}" for c in again]
        fit, episodes = self.problem.evaluate(phenotypes, tags) if phenotypes else (np.zeros(0), 0)
        t2 = time.perf_counter()
        n = len(children)
        # (nothing evaluated, e.g. no valid child: the problem's last behaviour is another batch's)
        beh = self.problem.behaviour if self.qd.behaviour and phenotypes else None
        rows = [None] * len(phenotypes) if beh is None else list(beh)
        for c, f, tag, b in zip(again, fit[n:], tags[n:], rows[n:], strict=True):
            e = self.elites[c]
            if self.accumulate:
                e.total, e.tags = e.total + float(f), [*e.tags, tag]
                if b is not None:
                    e.features_total = e.features_total + b
            else:
                e.total, e.tags = float(f), [tag]
                if b is not None:
                    e.features_total = b.copy()
            if b is not None:  # what it does, measured again: it may move to another cell
                e.measures = self.qd.measure(e.phenotype.body, e.features)
        offered = [Elite(c, p, self.qd.measure(p.body, b), float(f), [tag], g,
                         None if b is None else b.copy())
                   for (c, p), f, tag, b in zip(children, fit[:n], tags[:n], rows[:n], strict=True)]
        self.insert(offered, keep=list(self.elites.values()))
        self._credit(bred)
        fits = [e.fitness for e in self.elites.values()]
        stats = self.archive.stats
        row = {"generation": g,
               "best": max(fits) if fits else math.nan,
               "mean": statistics.fmean(fits) if fits else math.nan,
               "median": statistics.median(fits) if fits else math.nan,
               "n_valid": n, "n_invalid": n_invalid, "episodes": int(episodes),
               "coverage": float(stats.coverage), "qd_score": self.qd_score(),
               "n_elites": len(self.elites),
               "body_diversity": mean_pairwise_body_distance([e.phenotype.body
                                                              for e in self.elites.values()]),
               "build_s": t1 - t0, "sim_s": t2 - t1, "neat_s": time.perf_counter() - t2,
               "total_s": time.perf_counter() - t0}
        self.generation += 1
        return row

    def qd_score(self) -> float:
        """The archive's QD score: the sum over elites of max(0, fitness - score_offset), which never
        falls as elites are added or improve (an elite below the offset adds nothing)."""
        total = 0.0
        for c in sorted(self.elites):
            total += max(0.0, self.elites[c].fitness - self.qd.score_offset)
        return total

    def _parent(self, cells: list[int], exploit: bool) -> Any:
        """One parent's genome: the fittest of TOURNAMENT elites drawn (`exploit`), else one drawn
        uniformly or, with `selection: curiosity`, in proportion to its curiosity score shifted
        to start at 1 (Cully & Demiris 2018)."""
        if exploit:
            drawn = random.sample(cells, min(TOURNAMENT, len(cells)))
            return max((self.elites[c] for c in drawn), key=lambda e: (e.fitness, -e.genome.key)).genome
        if self.qd.selection == "curiosity":
            scores = [self.curiosity.get(self.elites[c].genome.key, 0.0) for c in cells]
            low = min(scores)
            return self.elites[random.choices(cells, weights=[v - low + 1.0 for v in scores])[0]].genome
        return self.elites[random.choice(cells)].genome

    def _breed(self) -> tuple[list[tuple[Any, Any, tuple[int, ...]]], int]:
        """The generation's valid children (genome, phenotype, its parents' genome keys) and the
        number of invalid ones made: `initial` new genomes while the archive is empty, else `batch`
        children of two parents (crossover, then mutation), the first round(exploit x batch) of
        them bred from tournament winners, the rest from parents drawn as `selection` says; at
        most MAX_TRIES genomes per child asked for."""
        want = self.qd.batch if self.elites else self.qd.initial
        cells = sorted(self.elites)
        exploiting = round(self.qd.exploit * want)
        gtype, gc = self.config.genome_type, self.config.genome_config
        out, invalid = [], 0
        for _ in range(MAX_TRIES * want):
            if len(out) == want:
                break
            child = gtype(self.next_key)
            self.next_key += 1
            parents: tuple[int, ...] = ()
            if cells:
                exploit = len(out) < exploiting
                a, b = self._parent(cells, exploit), self._parent(cells, exploit)
                child.configure_crossover(a, b, gc)
                child.mutate(gc)
                parents = (a.key, b.key)
            else:
                child.configure_new(gc)
            p = self.decode(child)
            if p.valid:
                out.append((child, p, parents))
            else:
                invalid += 1
        return out, invalid

    def _credit(self, bred: list[tuple[Any, Any, tuple[int, ...]]]) -> None:
        """Curiosity (`selection: curiosity`): each parent gains 1 for a child of its that entered the
        archive and loses 0.5 for one that did not; the scores of genomes no longer elites go."""
        if self.qd.selection != "curiosity":
            return
        inside = {e.genome.key for e in self.elites.values()}
        for child, _, parents in bred:
            gain = 1.0 if child.key in inside else -0.5
            for key in parents:
                if key in inside:
                    self.curiosity[key] = self.curiosity.get(key, 0.0) + gain
        self.curiosity = {k: v for k, v in sorted(self.curiosity.items()) if k in inside}

    def _to_rescore(self) -> list[int]:
        """The cells whose elites get another evaluation this generation, at most `rescore`: with
        `accumulate`, those with fewer than `settle` scores (0: no limit), fewest first; with
        `reevaluate` alone (fitness = its latest score), those scored longest ago first, so that
        every elite comes round. Ties: the lower cell index."""
        if not self.reevaluate:
            return []
        cells = [c for c in sorted(self.elites)
                 if not (self.accumulate and self.settle and len(self.elites[c].tags) >= self.settle)]
        if self.accumulate:
            cells.sort(key=lambda c: len(self.elites[c].tags))  # stable: cell order within a count
        else:  # a tag is "<generation>/<genome key>" (`step`): its latest score's generation
            cells.sort(key=lambda c: int(self.elites[c].tags[-1].split("/", 1)[0]))
        return cells[:self.qd.rescore]

    def insert(self, offered: list[Elite], keep: list[Elite] | None = None) -> None:
        """Rebuild the archive from `keep` (default: the elites as they are; each with its current
        fitness), then offer it `offered`: a cell takes the best of what falls in it when that
        beats its elite (pyribs' rule). Entries with a NaN fitness or descriptor are left out."""
        keep = list(self.elites.values()) if keep is None else keep
        self.archive.clear()
        pool: dict[int, Elite] = {}
        for group in (keep, offered):
            entries = [e for e in group if math.isfinite(e.fitness) and np.isfinite(e.measures).all()]
            if not entries:
                continue
            pool.update((e.genome.key, e) for e in entries)
            self.archive.add(solution=np.array([[float(e.genome.key)] for e in entries]),
                             objective=np.array([e.fitness for e in entries], dtype=np.float64),
                             measures=np.stack([e.measures for e in entries]))
        index, solution = self.archive.data(["index", "solution"], return_type="tuple")
        pairs = sorted(zip(index.tolist(), solution.tolist(), strict=True))
        self.elites = {int(i): pool[int(s[0])] for i, s in pairs}
        for e in self.elites.values():
            e.genome.fitness = e.fitness
        self._track_best()

    def _track_best(self) -> None:
        """`best`: the elite of the highest fitness (ties: the lower key), as NeatSearch's best."""
        if not self.elites:
            self.best = None
            return
        c, e = max(self.elites.items(), key=lambda kv: (kv[1].fitness, -kv[1].genome.key))
        self.best = self.elite_entry(c)

    def elite_entry(self, index: int) -> dict:
        """An elite as `NeatSearch.best` holds the best genome (what champion records are made of),
        with its cell."""
        e = self.elites[index]
        entry = {"fitness": e.fitness, "generation": e.born, "key": e.genome.key, "genome": e.genome,
                 "phenotype": e.phenotype, "tags": list(e.tags), "cell": self.cell(index),
                 "measures": dict(zip(self.qd.descriptors, e.measures.tolist(), strict=True))}
        if e.features is not None:
            entry["behaviour"] = dict(zip(FEATURES, e.features.tolist(), strict=True))
        return entry

    def entry_of_key(self, key: int) -> dict | None:
        """`elite_entry` of the elite whose genome has `key` (None: no elite has it)."""
        for index, e in self.elites.items():
            if e.genome.key == key:
                return self.elite_entry(index)
        return None

    # ------------------------------------------------------------------ checkpoint state
    def state(self) -> dict:
        """Everything that decides the rest of the run, as JSON data: the elites (genomes, scores,
        their generation), the key counters, the innovation tracker and Python's `random`. Their
        phenotypes, descriptors and cells, and the pyribs archive, are rebuilt from them."""
        gc = self.config.genome_config
        node_key, gc.node_indexer = peek(gc.node_indexer)
        cells = sorted(self.elites)
        return {"format": STATE_FORMAT, "generation": self.generation, "next_key": self.next_key,
                "node_indexer": node_key,
                "innovations": {"global_counter": self.tracker.global_counter,
                                "generation": [[i, o, t, n] for (i, o, t), n
                                               in self.tracker.generation_innovations.items()]},
                "random": encode_random(self._random_state),
                "genomes": encode_genomes([self.elites[c].genome for c in cells]),
                "elites": [self._elite_state(c) for c in cells],
                **({"curiosity": [[k, v] for k, v in sorted(self.curiosity.items())]}
                   if self.qd.selection == "curiosity" else {})}

    def _elite_state(self, cell: int) -> dict:
        e = self.elites[cell]
        out = {"cell": cell, "total": e.total, "tags": list(e.tags), "born": e.born}
        if e.features_total is not None:
            out["features"] = e.features_total.tolist()
        return out

    @staticmethod
    def decode_state(data, neat_config, path: str = "search") -> dict:
        """`state`'s data checked field by field (StateError naming the first bad one), genomes
        built from the run's own neat-python config."""
        from neat.innovation import InnovationTracker

        if get(data, "format", path, "str") != STATE_FORMAT:
            raise StateError(f"{path}.format: expected {STATE_FORMAT!r}")
        out = {"generation": get(data, "generation", path, "int"),
               "next_key": get(data, "next_key", path, "int"),
               "node_indexer": get(data, "node_indexer", path, "int?"),
               "random": decode_random(get(data, "random", path, "dict"), f"{path}.random")}
        inn = get(data, "innovations", path, "dict")
        tracker = InnovationTracker(get(inn, "global_counter", f"{path}.innovations", "int"))
        for j, it in enumerate(get(inn, "generation", f"{path}.innovations", "list")):
            i, o, t, n = row(it, f"{path}.innovations.generation[{j}]", ("int", "int", "str", "int"))
            tracker.generation_innovations[(i, o, t)] = n
        out["tracker"] = tracker
        out["curiosity"] = {}
        if isinstance(data, dict) and "curiosity" in data:
            for j, it in enumerate(get(data, "curiosity", path, "list")):
                k, v = row(it, f"{path}.curiosity[{j}]", ("int", "float"))
                out["curiosity"][k] = v
        genomes = decode_genomes(get(data, "genomes", path, "dict"), f"{path}.genomes",
                                 neat_config.genome_type, neat_config.genome_config)
        elites = get(data, "elites", path, "list")
        if len(elites) != len(genomes):
            raise StateError(f"{path}.elites: {len(elites)} elites for {len(genomes)} genomes")
        out["elites"] = []
        for j, (e, genome) in enumerate(zip(elites, genomes, strict=True)):
            p = f"{path}.elites[{j}]"
            tags = [check(t, f"{p}.tags", "str") for t in get(e, "tags", p, "list")]
            if not tags:
                raise StateError(f"{p}.tags: an elite has at least one score")
            features = None
            if isinstance(e, dict) and "features" in e:
                raw = get(e, "features", p, "list")
                features = np.array([check(v, f"{p}.features", "float") for v in raw], dtype=np.float64)
                if len(features) != len(FEATURES):
                    raise StateError(f"{p}.features: {len(features)} features, expected {len(FEATURES)}")
            out["elites"].append((get(e, "cell", p, "int"), genome, get(e, "total", p, "float"), tags,
                                  get(e, "born", p, "int"), features))
        return out

    def _restore(self, state: Mapping) -> None:
        import itertools

        self.generation, self.next_key = state["generation"], state["next_key"]
        self.tracker = state["tracker"]
        self._random_state = state["random"]
        nxt = state["node_indexer"]
        self.config.genome_config.node_indexer = None if nxt is None else itertools.count(nxt)
        keep = []
        for cell, genome, total, tags, born, features in state["elites"]:
            p = self.decode(genome)
            if not p.valid:
                raise StateError(f"search.elites: the elite of cell {cell} decodes to an invalid body")
            if self.qd.behaviour and features is None:
                raise StateError(f"search.elites: the elite of cell {cell} has no behaviour features, "
                                 "which the run's descriptors read (the run's qd settings changed?)")
            e = Elite(genome, p, np.zeros(0), total, list(tags), born,
                      features if self.qd.behaviour else None)
            e.measures = self.qd.measure(p.body, e.features)
            keep.append((cell, e))
        self.insert([], keep=[e for _, e in keep])
        self.curiosity = dict(state.get("curiosity", {}))
        if sorted(self.elites) != sorted(c for c, _ in keep):
            raise StateError("search.elites: the elites do not fall in their recorded cells "
                             "(the run's qd settings changed?)")
