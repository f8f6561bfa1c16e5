"""A NEAT search's checkpoint state as plain JSON data, and back, checked field by field.

`NeatSearch.state()` holds neat-python objects (genomes, species, the reproduction's counters and
innovation tracker) and Python's `random` state. `encode_search_state` turns it into lists,
numbers and strings only; `decode_search_state` checks every field's type and shape and builds
the objects again from the run's own neat-python config. Nothing named in the data is imported or
called: gene types come from the config, and activation and aggregation names must be in the fixed
tables of evolve/nn/activations.py.

Every genome is stored once in a table, and the population, the species (members and
representatives) and the best genome refer to it by index, so objects shared in memory are shared
again after loading (a fitness set on a population genome is seen by its species). Every dict keeps
its order, which neat-python's iteration (and so the random numbers it draws) depends on. An
attribute this module does not know on any object makes encoding fail rather than silently
dropping state.
"""

from __future__ import annotations

import base64

import numpy as np

from evolve.nn.activations import NEAT_ACTIVATIONS, NEAT_AGGREGATIONS

GENOME_ATTRS = {"key", "nodes", "connections", "fitness"}
NODE_ATTRS = ("bias", "response", "activation", "aggregation", "time_constant")
SPECIES_ATTRS = ("key", "created", "last_improved", "representative", "members", "fitness",
                 "adjusted_fitness", "fitness_history")
SPECIES_SET_ATTRS = {"species_set_config", "reporters", "indexer", "species", "genome_to_species"}
REPRODUCTION_ATTRS = {"reproduction_config", "reporters", "genome_indexer", "stagnation", "ancestors",
                      "innovation_tracker"}
MUTATION_TYPES = ("add_connection", "add_node_in", "add_node_out", "initial_connection")
MT_STATE_WORDS = 625  # Python's Mersenne Twister state: 624 words and the position


class StateError(ValueError):
    """Checkpoint data that does not have the expected form (a damaged or foreign file)."""


# ---------------------------------------------------------------------------------- encoding
def _known(obj, attrs: set, what: str) -> None:
    extra = set(vars(obj)) - set(attrs)
    if extra:
        raise TypeError(f"cannot checkpoint {what}: unknown attribute(s) {sorted(extra)}")


def _float(x) -> float | None:
    return None if x is None else float(x)


def encode_random(state: tuple) -> dict:
    """Python's `random.getstate()` as data: version, the 625 words (base64 of little-endian
    uint32) and the cached Gaussian."""
    version, words, gauss = state
    raw = np.asarray(words, dtype="<u4").tobytes()
    return {"version": version, "words": base64.b64encode(raw).decode(), "gauss_next": _float(gauss)}


def encode_search_state(state: dict) -> dict:
    """`NeatSearch.state()` (format 2) as JSON data (module docstring)."""
    table: list[dict] = []
    index: dict[int, int] = {}

    def ref(g) -> int:
        if id(g) not in index:
            _known(g, GENOME_ATTRS, "a genome")
            index[id(g)] = len(table)
            table.append({
                "key": g.key, "fitness": _float(g.fitness),
                "nodes": [[n.key, *(getattr(n, a) for a in NODE_ATTRS)] for n in g.nodes.values()],
                "connections": [[c.key[0], c.key[1], c.weight, c.enabled, c.innovation]
                                for c in g.connections.values()]})
            for n in g.nodes.values():
                _known(n, {"key", *NODE_ATTRS}, "a node gene")
            for c in g.connections.values():
                _known(c, {"key", "weight", "enabled", "innovation"}, "a connection gene")
        return index[id(g)]

    population = [[k, ref(g)] for k, g in state["population"].items()]
    sp = state["species"]
    if set(sp) - SPECIES_SET_ATTRS:
        raise TypeError(f"cannot checkpoint the species set: unknown {sorted(set(sp) - SPECIES_SET_ATTRS)}")
    species = []
    for sid, s in sp["species"].items():
        _known(s, set(SPECIES_ATTRS), "a species")
        species.append({"id": sid, "key": s.key, "created": s.created, "last_improved": s.last_improved,
                        "representative": None if s.representative is None else ref(s.representative),
                        "members": [[k, ref(g)] for k, g in s.members.items()],
                        "fitness": _float(s.fitness), "adjusted_fitness": _float(s.adjusted_fitness),
                        "fitness_history": [float(f) for f in s.fitness_history]})
    repro = state["reproduction"]
    if set(repro) - REPRODUCTION_ATTRS:
        unknown = sorted(set(repro) - REPRODUCTION_ATTRS)
        raise TypeError(f"cannot checkpoint the reproduction: unknown {unknown}")
    tracker = repro["innovation_tracker"]
    _known(tracker, {"global_counter", "generation_innovations"}, "the innovation tracker")
    best = state["best"]
    return {
        "generation": state["generation"],
        "pending_build_s": float(state["pending_build_s"]),
        "node_indexer": state["node_indexer"],
        "species_indexer": sp["indexer"],
        "genome_indexer": repro["genome_indexer"],
        "random": encode_random(state["random"]),
        "genomes": table,
        "population": population,
        "species": species,
        "genome_to_species": [[g, s] for g, s in sp["genome_to_species"].items()],
        "ancestors": [[k, list(v)] for k, v in repro["ancestors"].items()],
        "innovations": {"global_counter": tracker.global_counter,
                        "generation": [[i, o, t, n]
                                       for (i, o, t), n in tracker.generation_innovations.items()]},
        "best": None if best is None else {"fitness": float(best["fitness"]),
                                           "generation": best["generation"], "key": best["key"],
                                           "genome": ref(best["genome"])},
    }


# ---------------------------------------------------------------------------------- decoding
def _fail(path: str, msg: str) -> StateError:
    return StateError(f"{path}: {msg}")


def is_int(x) -> bool:
    """An int that is not a bool (JSON's true is Python's True, an int)."""
    return isinstance(x, int) and not isinstance(x, bool)


def get(d, key: str, path: str, kind: str):
    """d[key], checked to be of `kind`: int, float (an int is a float), str, bool, list, dict,
    float? / int? (or null)."""
    if not isinstance(d, dict):
        raise _fail(path, "not a mapping")
    if key not in d:
        raise _fail(path, f"missing {key!r}")
    return check(d[key], f"{path}.{key}", kind)


def check(x, path: str, kind: str):
    """`x` if it is of `kind` (see `get`), else StateError naming `path`."""
    if kind.endswith("?"):
        if x is None:
            return None
        kind = kind[:-1]
    ok = {"int": is_int(x), "float": is_int(x) or isinstance(x, float), "str": isinstance(x, str),
          "bool": isinstance(x, bool), "list": isinstance(x, list), "dict": isinstance(x, dict)}[kind]
    if not ok:
        raise _fail(path, f"expected {kind}, got {type(x).__name__}")
    return float(x) if kind == "float" else x


def row(x, path: str, kinds: tuple[str, ...]) -> list:
    """A fixed-length list whose items are of `kinds`."""
    check(x, path, "list")
    if len(x) != len(kinds):
        raise _fail(path, f"expected {len(kinds)} items, got {len(x)}")
    return [check(v, f"{path}[{i}]", k) for i, (v, k) in enumerate(zip(x, kinds, strict=True))]


def decode_random(d, path: str) -> tuple:
    """The `random.setstate` tuple of `encode_random`'s data."""
    version = get(d, "version", path, "int")
    try:
        raw = base64.b64decode(get(d, "words", path, "str"), validate=True)
    except ValueError:
        raise _fail(f"{path}.words", "not base64") from None
    if len(raw) != 4 * MT_STATE_WORDS:
        raise _fail(f"{path}.words", f"expected {MT_STATE_WORDS} words")
    words = tuple(int(w) for w in np.frombuffer(raw, dtype="<u4"))
    if words[-1] > 624:
        raise _fail(f"{path}.words", "position out of range")
    return version, words, get(d, "gauss_next", path, "float?")


def _genome(d, path: str, genome_type, gc):
    g = genome_type(get(d, "key", path, "int"))
    g.fitness = get(d, "fitness", path, "float?")
    for i, n in enumerate(get(d, "nodes", path, "list")):
        key, bias, response, act, agg, tc = row(n, f"{path}.nodes[{i}]",
                                               ("int", "float", "float", "str", "str", "float"))
        if act not in NEAT_ACTIVATIONS or agg not in NEAT_AGGREGATIONS:
            raise _fail(f"{path}.nodes[{i}]", f"unknown activation or aggregation {act!r}/{agg!r}")
        if key in g.nodes:
            raise _fail(f"{path}.nodes[{i}]", f"node {key} twice")
        gene = gc.node_gene_type(key)
        gene.bias, gene.response, gene.activation, gene.aggregation, gene.time_constant = \
            bias, response, act, agg, tc
        g.nodes[key] = gene
    for i, c in enumerate(get(d, "connections", path, "list")):
        a, b, w, enabled, inn = row(c, f"{path}.connections[{i}]", ("int", "int", "float", "bool", "int"))
        if (a, b) in g.connections:
            raise _fail(f"{path}.connections[{i}]", f"connection {(a, b)} twice")
        gene = gc.connection_gene_type((a, b), innovation=inn)
        gene.weight, gene.enabled = w, enabled
        g.connections[(a, b)] = gene
    return g


def decode_search_state(data, neat_config, path: str = "search") -> dict:
    """`encode_search_state`'s data back as the dict `NeatSearch` restores from (format 2); every
    field checked (StateError naming the first bad one)."""
    from neat.innovation import InnovationTracker
    from neat.species import Species

    check(data, path, "dict")
    gc = neat_config.genome_config
    genomes = [_genome(g, f"{path}.genomes[{i}]", neat_config.genome_type, gc)
               for i, g in enumerate(get(data, "genomes", path, "list"))]

    def deref(i, p: str):
        check(i, p, "int")
        if not 0 <= i < len(genomes):
            raise _fail(p, f"no genome {i}")
        return genomes[i]

    def keyed(items, p: str) -> dict:
        out = {}
        for j, it in enumerate(check(items, p, "list")):
            k, i = row(it, f"{p}[{j}]", ("int", "int"))
            g = deref(i, f"{p}[{j}]")
            if g.key != k or k in out:
                raise _fail(f"{p}[{j}]", f"genome key {k} does not match or repeats")
            out[k] = g
        return out

    population = keyed(get(data, "population", path, "list"), f"{path}.population")
    species = {}
    for j, s in enumerate(get(data, "species", path, "list")):
        p = f"{path}.species[{j}]"
        sid = get(s, "id", p, "int")
        obj = Species(get(s, "key", p, "int"), get(s, "created", p, "int"))
        obj.last_improved = get(s, "last_improved", p, "int")
        rep = get(s, "representative", p, "int?")
        obj.representative = None if rep is None else deref(rep, f"{p}.representative")
        obj.members = keyed(get(s, "members", p, "list"), f"{p}.members")
        obj.fitness = get(s, "fitness", p, "float?")
        obj.adjusted_fitness = get(s, "adjusted_fitness", p, "float?")
        obj.fitness_history = [check(f, f"{p}.fitness_history", "float")
                               for f in get(s, "fitness_history", p, "list")]
        species[sid] = obj
    g2s = {}
    for j, it in enumerate(get(data, "genome_to_species", path, "list")):
        g, s = row(it, f"{path}.genome_to_species[{j}]", ("int", "int"))
        g2s[g] = s
    ancestors = {}
    for j, it in enumerate(get(data, "ancestors", path, "list")):
        k, parents = row(it, f"{path}.ancestors[{j}]", ("int", "list"))
        ancestors[k] = tuple(check(x, f"{path}.ancestors[{j}]", "int") for x in parents)
    inn = get(data, "innovations", path, "dict")
    tracker = InnovationTracker(get(inn, "global_counter", f"{path}.innovations", "int"))
    for j, it in enumerate(get(inn, "generation", f"{path}.innovations", "list")):
        i, o, t, n = row(it, f"{path}.innovations.generation[{j}]", ("int", "int", "str", "int"))
        if t not in MUTATION_TYPES:
            raise _fail(f"{path}.innovations.generation[{j}]", f"unknown mutation type {t!r}")
        tracker.generation_innovations[(i, o, t)] = n
    best = get(data, "best", path, "dict?")
    if best is not None:
        best = {"fitness": get(best, "fitness", f"{path}.best", "float"),
                "generation": get(best, "generation", f"{path}.best", "int"),
                "key": get(best, "key", f"{path}.best", "int"),
                "genome": deref(get(best, "genome", f"{path}.best", "int"), f"{path}.best.genome")}
    counters = {k: get(data, k, path, "int?") for k in ("node_indexer", "species_indexer", "genome_indexer")}
    for k in ("species_indexer", "genome_indexer"):
        if counters[k] is None:
            raise _fail(f"{path}.{k}", "expected int, got null")
    stagnation = neat_config.stagnation_type(neat_config.stagnation_config, None)
    return {
        "format": 2, "generation": get(data, "generation", path, "int"), "population": population,
        "species": {"species_set_config": neat_config.species_set_config, "reporters": None,
                    "indexer": counters["species_indexer"], "species": species, "genome_to_species": g2s},
        "reproduction": {"reproduction_config": neat_config.reproduction_config, "reporters": None,
                         "genome_indexer": counters["genome_indexer"], "stagnation": stagnation,
                         "ancestors": ancestors, "innovation_tracker": tracker},
        "node_indexer": counters["node_indexer"],
        "random": decode_random(get(data, "random", path, "dict"), f"{path}.random"),
        "best": best,
        "pending_build_s": get(data, "pending_build_s", path, "float"),
    }

