"""Genome sizes: a planted genome of 100,000 nodes in a checkpoint or champion.json is refused in one
line before anything is built from it, and compiling a genome takes time linear in its genes, with
the layers of neat-python 2.0's quadratic `feed_forward_layers` (kept below, written plainly, as
the oracle), so every existing result stays bit for bit."""

from __future__ import annotations

import base64
import json
import random
import shutil
import time
from pathlib import Path
from types import SimpleNamespace

import neat.graphs
import numpy as np
import pytest

from evolve.nn.feedforward import FeedForward, Node, compile_genome, feed_forward_layers
from evolve.records.files import atomic_write
from evolve.records.rundir import RunDir, checkpoint_bytes, read_checkpoint_file
from tests.evolve.attack import Attack
from tests.evolve.conftest import unfinished_run

pytestmark = pytest.mark.slow

PLANTED_NODES = 100_000


# ------------------------------------------------------------ the old compile, as the oracle
def old_required(inputs, outputs, connections) -> set:
    """neat-python 2.0's required_for_output, as it reads: rescan every link each round."""
    required, s = set(outputs), set(outputs)
    while True:
        t = {a for (a, b) in connections if b in s and a not in s}
        if not t:
            break
        layer_nodes = {x for x in t if x not in inputs}
        if not layer_nodes:
            break
        required = required | layer_nodes
        s = s | t
    return required


def old_layers(inputs, outputs, connections) -> tuple[list[set], set]:
    """neat-python 2.0's feed_forward_layers, as it reads (quadratic)."""
    required = old_required(inputs, outputs, connections)
    bias = required - {b for (a, b) in connections}
    layers = [set(bias)] if bias else []
    ready = set(inputs) | bias
    while True:
        candidates = {b for (a, b) in connections if a in ready and b not in ready}
        nxt = set()
        for n in candidates:
            into = [a for (a, b) in connections if b == n and a in required]
            if n in required and all(a in ready for a in into):
                nxt.add(n)
        if not nxt:
            return layers, required
        layers.append(nxt)
        ready = ready | nxt


def old_compile(genome, genome_config) -> FeedForward:
    """compile_genome as it was, over `old_layers`."""
    inputs, outputs = tuple(genome_config.input_keys), tuple(genome_config.output_keys)
    conns = [c.key for c in genome.connections.values() if c.enabled]
    layers, required = old_layers(list(inputs), list(outputs), conns)
    known = required | set(inputs)
    incoming: dict = {}
    for i, o in conns:
        if i in known:
            incoming.setdefault(o, []).append((i, genome.connections[(i, o)].weight))
    return FeedForward(inputs, outputs, tuple(
        tuple(Node(k, genome.nodes[k].bias, genome.nodes[k].response, genome.nodes[k].activation,
                   genome.nodes[k].aggregation, tuple(incoming.get(k, ()))) for k in sorted(layer))
        for layer in layers))


def random_genome(rng: random.Random):
    """A genome of any shape sgr might meet: a random DAG plus, at times, cycles, self-links, links
    into inputs, dangling nodes and disabled links; keys in random order."""
    n_in, n_out, n_hidden = rng.randint(1, 6), rng.randint(1, 4), rng.randint(0, 30)
    inputs, outputs = [-i - 1 for i in range(n_in)], list(range(n_out))
    hidden = rng.sample(range(n_out, n_out + 200), n_hidden)
    order = hidden + outputs
    rng.shuffle(order)
    nodes = {k: SimpleNamespace(bias=rng.uniform(-1, 1), response=rng.uniform(0.5, 1.5),
                                activation=rng.choice(["sigmoid", "tanh", "sin"]), aggregation="sum")
             for k in order}
    conns: dict = {}
    for _ in range(rng.randint(0, 4 * (n_hidden + n_out))):
        if rng.random() < 0.85:  # feed-forward
            j = rng.randrange(len(order))
            a = rng.choice(inputs + order[:j]) if j or rng.random() < 0.5 else rng.choice(inputs)
            b = order[j]
        else:  # anything: backward links, self-links, links into inputs
            a, b = rng.choice(inputs + order), rng.choice(inputs + order)
        conns[(a, b)] = SimpleNamespace(key=(a, b), weight=rng.uniform(-2, 2), enabled=rng.random() < 0.9)
    keys = list(conns)
    rng.shuffle(keys)
    genome = SimpleNamespace(nodes=nodes, connections={k: conns[k] for k in keys})
    return genome, SimpleNamespace(input_keys=inputs, output_keys=outputs)


def test_the_linear_compile_gives_the_old_layers_and_nodes_on_random_genomes():
    """Over 1,500 random genomes (cycles, links into inputs and dangling nodes among them), the
    linear layering equals neat-python 2.0's and the plain old one, and compile_genome the old
    compile, node for node (the order the networks evaluate in)."""
    rng = random.Random(57)
    layered = 0
    for _ in range(1500):
        genome, gc = random_genome(rng)
        conns = [c.key for c in genome.connections.values() if c.enabled]
        new = feed_forward_layers(gc.input_keys, gc.output_keys, conns)
        assert new == old_layers(gc.input_keys, gc.output_keys, conns)
        assert new == neat.graphs.feed_forward_layers(gc.input_keys, gc.output_keys, conns)
        assert compile_genome(genome, gc) == old_compile(genome, gc)
        layered += len(new[0]) > 2
    assert layered > 100  # deep genomes were among them


def chain(n: int):
    """A genome of `n` hidden nodes in one chain from input -1 to output 0."""
    keys = [*range(1, n + 1), 0]
    nodes = {k: SimpleNamespace(bias=0.0, response=1.0, activation="tanh", aggregation="sum") for k in keys}
    pairs = [(-1, keys[0]), *zip(keys, keys[1:], strict=False)]
    conns = {p: SimpleNamespace(key=p, weight=0.5, enabled=True) for p in pairs}
    return SimpleNamespace(nodes=nodes, connections=conns), SimpleNamespace(input_keys=[-1], output_keys=[0])


def test_a_chain_of_20000_nodes_compiles_in_seconds_not_minutes():
    """Compiling is linear: a 20,000-node chain (the old compile: minutes) in < 5 s, one layer per
    node (0.4 s alone on a 2-vCPU AMD EPYC; 1.3 s once under the whole suite's load there)."""
    genome, gc = chain(20_000)
    t0 = time.perf_counter()
    net = compile_genome(genome, gc)
    assert time.perf_counter() - t0 < 5.0
    assert len(net.layers) == 20_001 and net.layers[-1][0].key == 0


# ------------------------------------------------------------ planted genomes in a run folder
@pytest.fixture(scope="module")
def unfinished(tmp_path_factory) -> Path:
    """A tiny SGR run of 3 generations stopped after 2 (checkpoints after 1 and 2, a champion)."""
    return unfinished_run(tmp_path_factory.mktemp("genomes") / "run")


def _column(d: dict, key: str, dtype: str, rows: int) -> np.ndarray:
    return np.frombuffer(base64.b64decode(d[key]), dtype=dtype).reshape(rows, -1)


def _b64(a: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(a).tobytes()).decode()


def grow_first_genome(genomes: dict, n: int) -> None:
    """Give the checkpoint's first genome `n` more hidden nodes, chained from input -1 into output 0
    (a well-formed genome, only large), in `encode_genomes`' columns."""
    nk = np.frombuffer(base64.b64decode(genomes["node_key"]), dtype="<i8")
    tn, tc = len(nk), sum(genomes["n_connections"])
    nf, fn = _column(genomes, "node_float", "<f8", 3), _column(genomes, "node_fn", "<u2", 2)
    ci = _column(genomes, "conn_int", "<i8", 3)
    w = np.frombuffer(base64.b64decode(genomes["conn_weight"]), "<f8")
    en = np.frombuffer(base64.b64decode(genomes["conn_enabled"]), "u1")
    assert nf.shape[1] == tn and ci.shape[1] == tc
    keys = np.arange(10**7, 10**7 + n, dtype="<i8")
    src, dst = np.concatenate([[-1], keys]), np.concatenate([keys, [0]])
    genomes["node_key"] = _b64(np.concatenate([keys, nk]))
    genomes["node_float"] = _b64(np.concatenate([np.tile(nf[:, :1], n), nf], axis=1))
    genomes["node_fn"] = _b64(np.concatenate([np.tile(fn[:, :1], n), fn], axis=1))
    innovations = np.arange(len(src)) + 10**7
    genomes["conn_int"] = _b64(np.concatenate([np.stack([src, dst, innovations]), ci], axis=1))
    genomes["conn_weight"] = _b64(np.concatenate([np.full(len(src), 0.5), w]))
    genomes["conn_enabled"] = _b64(np.concatenate([np.ones(len(src), "u1"), en]))
    genomes["n_nodes"][0] += n
    genomes["n_connections"][0] += len(src)


def test_a_planted_100000_node_genome_in_the_checkpoints_is_refused_quickly(unfinished, tmp_path, capsys):
    """`sgr evolve --resume` of a run whose checkpoints hold a genome of 100,000 nodes refuses it in
    one line naming the checkpoints, in < 2 s, before compiling it (that took minutes)."""
    attack = Attack(tmp_path)
    run = tmp_path / "run"
    shutil.copytree(unfinished, run)
    for f in RunDir(run).checkpoints():
        data = read_checkpoint_file(f)
        grow_first_genome(data["search"]["genomes"], PLANTED_NODES)
        atomic_write(f, checkpoint_bytes({k: v for k, v in data.items() if k not in ("format", "version")}))
    with attack.watching(run):
        r = attack.main("evolve", "--resume", str(run), capsys=capsys, timeout=60)
    line = r.error_line()
    assert f"no usable checkpoint in {run / 'checkpoints'}" in line and "gen-00002.json.gz" in line, line
    assert f"{PLANTED_NODES + 1:,} nodes, over the 20,000" in line, line
    assert r.seconds < 2, r.seconds


def test_a_planted_100000_node_genome_in_champion_json_is_refused_quickly(unfinished, tmp_path, capsys):
    """`sgr render RUN` of a champion.json whose genome has 100,000 nodes: one line naming the file
    and the key, in < 2 s, before the genome is compiled."""
    attack = Attack(tmp_path)
    run = tmp_path / "run"
    shutil.copytree(unfinished, run)
    champ = json.loads((run / "champion.json").read_text())
    nodes, conns = champ["genome"]["nodes"], champ["genome"]["connections"]
    keys = list(range(10**7, 10**7 + PLANTED_NODES))
    for col, value in (("bias", 0.0), ("response", 1.0), ("activation", "tanh"), ("aggregation", "sum")):
        nodes[col] = [value] * PLANTED_NODES + nodes[col]
    nodes["key"] = keys + nodes["key"]
    links = list(zip([-1, *keys], [*keys, 0], strict=True))
    conns["in"] = [a for a, _ in links] + conns["in"]
    conns["out"] = [b for _, b in links] + conns["out"]
    conns["weight"] = [0.5] * len(links) + conns["weight"]
    conns["enabled"] = [True] * len(links) + conns["enabled"]
    (run / "champion.json").write_text(json.dumps(champ))
    with attack.watching(run):
        r = attack.main("render", str(run), capsys=capsys, timeout=60)
    line = r.error_line()
    says = f"{run / 'champion.json'}: key 'genome': {len(nodes['key']):,} nodes, over the 20,000"
    assert says in line, line
    assert r.seconds < 2, r.seconds
