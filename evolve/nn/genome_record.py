"""A NEAT genome as plain JSON and back: the "genome" record of champion.json.

The record lists every node and connection (disabled ones included) in the genome's own order. That
order matters: a compiled network sums a node's inputs in it, so a genome read back in the stored
order decodes to the same numbers bit for bit (`sgr decode`, and SGR controllers recorded as a
function of their genome, evolve/methods/sgr/record.py). Resuming uses the checkpoints, not this.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import neat
from neat.genes import DefaultConnectionGene, DefaultNodeGene

from tsim.errors import SgrError

# the most genes sgr reads back of one genome (a checkpoint's, a champion record's), checked before
# anything is built from it: the largest genome of results/ has 106 nodes and 1,293 connections
# (direct, Walker-v0 10x10); a 64x64 direct body's network has 4,101 outputs and ~10^6 initial links
MAX_GENOME_NODES = 20_000
MAX_POP = 1_000_000  # a larger population is a typo (neat-python would fill memory making it)
MAX_GENOME_CONNECTIONS = 4_000_000
NODE_COLUMNS = ("key", "bias", "response", "activation", "aggregation")
CONNECTION_COLUMNS = ("in", "out", "weight", "enabled")


def genome_json(genome) -> dict:
    """The genome as plain JSON: its key, and its nodes and connections in the genome's order as
    tables by column (`NODE_COLUMNS`, `CONNECTION_COLUMNS`; row i of every column is gene i), which
    is half the size of one object per gene and loads as it is into a data frame."""
    nodes, conns = list(genome.nodes.values()), list(genome.connections.values())
    return {"key": genome.key,
            "nodes": {"key": [n.key for n in nodes], "bias": [n.bias for n in nodes],
                      "response": [n.response for n in nodes], "activation": [n.activation for n in nodes],
                      "aggregation": [n.aggregation for n in nodes]},
            "connections": {"in": [c.key[0] for c in conns], "out": [c.key[1] for c in conns],
                            "weight": [c.weight for c in conns], "enabled": [c.enabled for c in conns]}}


def genes(table: dict | list, columns: tuple[str, ...]) -> list[dict]:
    """A genome record's node or connection table as one dict per gene: the columns of today's
    records, or the list of objects older records hold."""
    if isinstance(table, list):
        return table
    cols = [list(table[c]) for c in columns]
    if len({len(c) for c in cols}) > 1:
        raise ValueError(f"columns {', '.join(columns)} differ in length")
    return [dict(zip(columns, row, strict=True)) for row in zip(*cols, strict=True)]


def as_columns(record: dict) -> dict:
    """A genome record in today's layout (tables by column, `genome_json`), from either layout."""
    return {**record,
            "nodes": {c: [n[c] for n in genes(record["nodes"], NODE_COLUMNS)] for c in NODE_COLUMNS},
            "connections": {c: [g[c] for g in genes(record["connections"], CONNECTION_COLUMNS)]
                            for c in CONNECTION_COLUMNS}}


@dataclass(frozen=True)
class GenomeKeys:
    """The part of a neat-python genome config that reading a record and compiling its network use:
    the gene types and neat-python's pin keys (inputs -1..-n, outputs 0..m-1). Enough to rebuild a
    recorded genome without its run's neat.ini."""
    num_inputs: int
    num_outputs: int
    node_gene_type: type = field(default=DefaultNodeGene, repr=False)
    connection_gene_type: type = field(default=DefaultConnectionGene, repr=False)

    @property
    def input_keys(self) -> list[int]:
        """neat-python's input pins: -1, -2, ..., -num_inputs."""
        return [-i - 1 for i in range(self.num_inputs)]

    @property
    def output_keys(self) -> list[int]:
        """neat-python's output nodes: 0, 1, ..., num_outputs - 1."""
        return list(range(self.num_outputs))


def genome_size_problem(n_nodes: int, n_connections: int) -> str | None:
    """What is wrong with a genome of this many node and connection genes (over MAX_GENOME_NODES
    or MAX_GENOME_CONNECTIONS), or None."""
    if n_nodes > MAX_GENOME_NODES:
        return f"{n_nodes:,} nodes, over the {MAX_GENOME_NODES:,} sgr reads of one genome"
    if n_connections > MAX_GENOME_CONNECTIONS:
        return f"{n_connections:,} connections, over the {MAX_GENOME_CONNECTIONS:,} sgr reads of one genome"
    return None


def record_size_problem(record: object) -> str | None:
    """`genome_size_problem` of a genome record (either layout), counted before anything is built;
    None for anything that is not a record (reading it says why)."""
    if not isinstance(record, dict):
        return None
    counts = []
    for table, first in (("nodes", "key"), ("connections", "in")):
        t = record.get(table)
        if isinstance(t, dict):
            t = t.get(first)
        counts.append(len(t) if isinstance(t, list) else 0)
    return genome_size_problem(*counts)


def genome_from_record(record: dict, genome_config) -> neat.DefaultGenome:
    """`genome_json`'s record (or an older one: an object per gene) as a neat-python genome, genes in
    their stored order (a compiled network's evaluation order follows it); `genome_config` gives the
    gene types (a run's, or `GenomeKeys`). SgrError when it is not a genome record, or a genome
    larger than sgr reads (`genome_size_problem`)."""
    if (why := record_size_problem(record)) is not None:
        raise SgrError(f"champion.json: key 'genome': {why}")
    try:
        g = neat.DefaultGenome(int(record["key"]))
        for n in genes(record["nodes"], NODE_COLUMNS):
            gene = genome_config.node_gene_type(int(n["key"]))
            gene.bias, gene.response = float(n["bias"]), float(n["response"])
            gene.activation, gene.aggregation = str(n["activation"]), str(n["aggregation"])
            gene.time_constant = 1.0  # not recorded; feed-forward networks never read it
            g.nodes[gene.key] = gene
        for c in genes(record["connections"], CONNECTION_COLUMNS):
            gene = genome_config.connection_gene_type((int(c["in"]), int(c["out"])), innovation=0)
            gene.weight, gene.enabled = float(c["weight"]), bool(c["enabled"])
            g.connections[gene.key] = gene
    except (KeyError, TypeError, ValueError) as exc:
        raise SgrError(f"champion.json: key 'genome': not a genome record "
                       f"({type(exc).__name__}: {exc})") from None
    return g
