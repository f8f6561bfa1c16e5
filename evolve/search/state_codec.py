"""A NEAT search's checkpoint state as plain JSON data, and back, checked field by field.

`NeatSearch.state()` holds neat-python objects (genomes, species, the reproduction's counters and
innovation tracker) and Python's `random` state. `encode_search_state` turns it into lists,
numbers and strings only; `decode_search_state` checks every field's type and shape and builds
the objects again from the run's own neat-python config. Nothing named in the data is imported or
called: gene types come from the config, and activation and aggregation names must be in the fixed
tables of evolve/nn/activations.py.

Every genome is stored once, in columns (`encode_genomes`), and the population, the species
(members and representatives) and the best genome refer to it by index, so objects shared in
memory are shared again after loading (a fitness set on a population genome is seen by its
species). Every dict keeps its order, which neat-python's iteration (and so the random numbers it
draws) depends on. An attribute this module does not know on any object makes encoding fail
rather than silently dropping state.
"""

from __future__ import annotations

import base64
from operator import attrgetter

import numpy as np

from evolve.nn.activations import NEAT_ACTIVATIONS, NEAT_AGGREGATIONS
from evolve.nn.genome_record import genome_size_problem
from tsim.errors import SgrError

GENOME_ATTRS = {"key", "nodes", "connections", "fitness"}
NODE_ATTRS = ("bias", "response", "activation", "aggregation", "time_constant")
SPECIES_ATTRS = ("key", "created", "last_improved", "representative", "members", "fitness",
                 "adjusted_fitness", "fitness_history")
SPECIES_SET_ATTRS = {"species_set_config", "reporters", "indexer", "species", "genome_to_species"}
REPRODUCTION_ATTRS = {"reproduction_config", "reporters", "genome_indexer", "stagnation", "ancestors",
                      "innovation_tracker"}
MUTATION_TYPES = ("add_connection", "add_node_in", "add_node_out", "initial_connection")
MT_STATE_WORDS = 625  # Python's Mersenne Twister state: 624 words and the position


class StateError(SgrError):
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


def _b64(values, dtype: str) -> str:
    return base64.b64encode(np.asarray(values, dtype=dtype).tobytes()).decode()


def encode_genomes(genomes: list) -> dict:
    """Genomes as columns: per genome its key, fitness and gene counts; the genes of all genomes
    one after the other, numbers as base64 of little-endian arrays (exact, and fast to write),
    activation and aggregation as indices into `names`."""
    for g in genomes:
        _known(g, GENOME_ATTRS, "a genome")
    nodes = [n for g in genomes for n in g.nodes.values()]
    conns = [c for g in genomes for c in g.connections.values()]
    for genes, attrs, what in ((nodes, {"key", *NODE_ATTRS}, "a node gene"),
                               (conns, {"key", "weight", "enabled", "innovation"}, "a connection gene")):
        if genes and (set(map(len, map(vars, genes))) != {len(attrs)} or set(vars(genes[0])) != attrs):
            raise TypeError(f"cannot checkpoint {what}: its attributes are not {sorted(attrs)}")
    act, agg = list(map(attrgetter("activation"), nodes)), list(map(attrgetter("aggregation"), nodes))
    names = sorted(set(act) | set(agg))
    code = {n: i for i, n in enumerate(names)}
    ckeys = list(map(attrgetter("key"), conns))
    return {
        "key": [g.key for g in genomes], "fitness": [_float(g.fitness) for g in genomes],
        "n_nodes": [len(g.nodes) for g in genomes], "n_connections": [len(g.connections) for g in genomes],
        "names": names,
        "node_key": _b64(list(map(attrgetter("key"), nodes)), "<i8"),
        "node_float": _b64([list(map(attrgetter(a), nodes)) for a in ("bias", "response", "time_constant")],
                           "<f8"),
        "node_fn": _b64([[code[n] for n in act], [code[n] for n in agg]], "<u2"),
        "conn_int": _b64([[k[0] for k in ckeys], [k[1] for k in ckeys],
                          list(map(attrgetter("innovation"), conns))], "<i8"),
        "conn_weight": _b64(list(map(attrgetter("weight"), conns)), "<f8"),
        "conn_enabled": _b64(list(map(attrgetter("enabled"), conns)), "u1"),
    }


def encode_search_state(state: dict) -> dict:
    """`NeatSearch.state()` (format 2) as JSON data (module docstring)."""
    table: list = []
    index: dict[int, int] = {}

    def ref(g) -> int:
        if id(g) not in index:
            index[id(g)] = len(table)
            table.append(g)
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
    # the stagnation keeps no state of its own (species hold theirs): rebuilt from the config
    _known(repro["stagnation"], {"stagnation_config", "species_fitness_func", "reporters"},
           "the stagnation")
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
        "genomes": None,  # below, once every genome has its index
        "population": population,
        "species": species,
        "genome_to_species": [[g, s] for g, s in sp["genome_to_species"].items()],
        "ancestors": [[k, list(v)] for k, v in repro["ancestors"].items()],
        "innovations": {"global_counter": tracker.global_counter,
                        "generation": [[i, o, t, n]
                                       for (i, o, t), n in tracker.generation_innovations.items()]},
        "best": None if best is None else {"fitness": float(best["fitness"]),
                                           "generation": best["generation"], "key": best["key"],
                                           "genome": ref(best["genome"])}
        | ({"tags": list(best["tags"])} if "tags" in best else {}),
    } | {"genomes": encode_genomes(table)} | _encode_scores(state.get("scores"))


def _encode_scores(scores: dict | None) -> dict:
    """Accumulated fitness (NeatSearch `accumulate`): each living genome's key, score sum and tags;
    nothing at all for a search that keeps none (its checkpoints stay as they were)."""
    if scores is None:
        return {}
    return {"scores": [[k, float(total), list(tags)] for k, (total, tags) in scores.items()]}


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


def _array(d, key: str, path: str, dtype: str, shape: tuple[int, ...]) -> list:
    """A base64 column of `encode_genomes` as Python numbers, its length checked."""
    try:
        raw = base64.b64decode(get(d, key, path, "str"), validate=True)
    except ValueError:
        raise _fail(f"{path}.{key}", "not base64") from None
    size = int(np.prod(shape)) * np.dtype(dtype).itemsize
    if len(raw) != size:
        raise _fail(f"{path}.{key}", f"expected {size} bytes, got {len(raw)}")
    return np.frombuffer(raw, dtype=dtype).reshape(shape).tolist()


def decode_genomes(d, path: str, genome_type, gc) -> list:
    """`encode_genomes`'s columns back as genomes of `genome_type` with the config's gene types;
    activation and aggregation names must be in the fixed tables."""
    keys = [check(k, f"{path}.key", "int") for k in get(d, "key", path, "list")]
    n = len(keys)
    cols = {c: get(d, c, path, "list") for c in ("fitness", "n_nodes", "n_connections")}
    if any(len(v) != n for v in cols.values()):
        raise _fail(path, "columns of different lengths")
    fitness = [check(f, f"{path}.fitness", "float?") for f in cols["fitness"]]
    n_nodes = [check(k, f"{path}.n_nodes", "int") for k in cols["n_nodes"]]
    n_conns = [check(k, f"{path}.n_connections", "int") for k in cols["n_connections"]]
    if min(n_nodes + n_conns, default=0) < 0:
        raise _fail(path, "negative gene count")
    for key, nn, nc in zip(keys, n_nodes, n_conns, strict=True):  # before any gene is read
        if (why := genome_size_problem(nn, nc)) is not None:
            raise _fail(path, f"genome {key} has {why}")
    names = [check(x, f"{path}.names", "str") for x in get(d, "names", path, "list")]
    for x in names:
        if x not in NEAT_ACTIVATIONS and x not in NEAT_AGGREGATIONS:
            raise _fail(f"{path}.names", f"unknown activation or aggregation {x!r}")
    tn, tc = sum(n_nodes), sum(n_conns)
    node_key = _array(d, "node_key", path, "<i8", (tn,))
    bias, response, tconst = _array(d, "node_float", path, "<f8", (3, tn))
    act, agg = _array(d, "node_fn", path, "<u2", (2, tn))
    if any(i >= len(names) for i in act + agg):
        raise _fail(f"{path}.node_fn", "name index out of range")
    if any(names[i] not in NEAT_ACTIVATIONS for i in act) or any(names[i] not in NEAT_AGGREGATIONS
                                                                 for i in agg):
        raise _fail(f"{path}.node_fn", "an activation that is an aggregation or the reverse")
    c_in, c_out, c_inn = _array(d, "conn_int", path, "<i8", (3, tc))
    weight = _array(d, "conn_weight", path, "<f8", (tc,))
    enabled = _array(d, "conn_enabled", path, "u1", (tc,))
    if any(e > 1 for e in enabled):
        raise _fail(f"{path}.conn_enabled", "not 0 or 1")
    genomes, i, j = [], 0, 0
    for key, fit, nn, nc in zip(keys, fitness, n_nodes, n_conns, strict=True):
        g = genome_type(key)
        g.fitness = fit
        for k in range(i, i + nn):
            gene = gc.node_gene_type(node_key[k])
            gene.bias, gene.response, gene.time_constant = bias[k], response[k], tconst[k]
            gene.activation, gene.aggregation = names[act[k]], names[agg[k]]
            g.nodes[node_key[k]] = gene
        for k in range(j, j + nc):
            gene = gc.connection_gene_type((c_in[k], c_out[k]), innovation=c_inn[k])
            gene.weight, gene.enabled = weight[k], bool(enabled[k])
            g.connections[(c_in[k], c_out[k])] = gene
        if len(g.nodes) != nn or len(g.connections) != nc:
            raise _fail(path, f"genome {key} has a gene twice")
        i, j = i + nn, j + nc
        genomes.append(g)
    return genomes


def decode_search_state(data, neat_config, path: str = "search") -> dict:
    """`encode_search_state`'s data back as the dict `NeatSearch` restores from (format 2); every
    field checked (StateError naming the first bad one)."""
    from neat.innovation import InnovationTracker
    from neat.species import Species

    check(data, path, "dict")
    gc = neat_config.genome_config
    genomes = decode_genomes(get(data, "genomes", path, "dict"), f"{path}.genomes",
                             neat_config.genome_type, gc)

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
        if "tags" in data["best"]:
            best["tags"] = [check(t, f"{path}.best.tags", "str")
                            for t in get(data["best"], "tags", f"{path}.best", "list")]
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
        "scores": _decode_scores(data, path),
    }


def _decode_scores(data: dict, path: str) -> dict | None:
    """`_encode_scores`'s records back as {key: (sum, tags)}; None when the checkpoint has none."""
    if "scores" not in data:
        return None
    out = {}
    for j, it in enumerate(get(data, "scores", path, "list")):
        p = f"{path}.scores[{j}]"
        k, total, tags = row(it, p, ("int", "float", "list"))
        if not tags or k in out:
            raise _fail(p, "a record needs at least one tag, and a key appears once")
        out[k] = (total, [check(t, p, "str") for t in tags])
    return out

