"""champion.json's genome record: written by column, read back as the same genes in the same order
(the order a compiled network sums in), and records of the older layout (an object per gene) read
as the same genome."""

from evolve.nn.genome_record import as_columns, genome_from_record, genome_json


def genes_of(g) -> list:
    return ([(n.key, n.bias, n.response, n.activation, n.aggregation) for n in g.nodes.values()],
            [(c.key, c.weight, c.enabled) for c in g.connections.values()])


def test_a_genome_record_by_columns_reads_back_as_the_same_genes_in_order(neat_config, genomes):
    cfg = neat_config(pop=4)
    g = genomes(cfg, 1, mutations=20, seed=1)[0]
    record = genome_json(g)
    assert set(record["connections"]) == {"in", "out", "weight", "enabled"}
    assert len(record["connections"]["weight"]) == len(g.connections) > 1
    assert genes_of(genome_from_record(record, cfg.genome_config)) == genes_of(g)


def test_an_older_record_with_an_object_per_gene_reads_as_the_same_genome(neat_config, genomes):
    cfg = neat_config(pop=4)
    g = genomes(cfg, 1, mutations=3, seed=2)[0]
    cols = genome_json(g)
    def rows(table: dict) -> list[dict]:
        return [dict(zip(table, row, strict=True)) for row in zip(*table.values(), strict=True)]

    old = {"key": cols["key"], "nodes": rows(cols["nodes"]), "connections": rows(cols["connections"])}
    assert isinstance(old["nodes"][0], dict) and old["nodes"][0]["key"] == cols["nodes"]["key"][0]
    assert genes_of(genome_from_record(old, cfg.genome_config)) == genes_of(g)
    assert as_columns(old) == cols
