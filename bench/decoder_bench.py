"""Decoding time per genome by body decoder (`body_decoder`, evolve/methods/sgr/decoders/; not run by CI).

    python bench/decoder_bench.py [--shape 10x10] [--genomes 100] [--mutations 6] [--task Walker-v0]

For each decoder, `--genomes` random genomes of configs/neat/sgr.ini (with the decoder's CPPN
outputs), each mutated `--mutations` times (seed 0), are decoded at `--shape` as a run decodes them
(`sgr_decoder.decode`: compile the CPPN, draw the body, check it, build the controller of a valid
one). Prints per decoder: milliseconds per genome (the best of 3 passes), of which the body alone,
and the share of valid bodies. A generation decodes its new genomes once each (pop_size of them),
so at pop 128 a decoder of 10 ms/genome spends 1.3 s of the generation decoding.
"""

from __future__ import annotations

import argparse
import random
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import neat  # noqa: E402

from evolve.cli.common import parse_shape  # noqa: E402
from evolve.methods.sgr.decoder import DecoderSettings, body_from_cppn, decode, is_valid_robot  # noqa: E402
from evolve.methods.sgr.decoders import DECODERS  # noqa: E402
from evolve.nn.cppn import CompiledCPPN  # noqa: E402
from evolve.search.neat_ini import load_neat_config, neat_ini_text  # noqa: E402


def genomes(n_outputs: int, n: int, mutations: int) -> tuple[list, object]:
    """`n` fresh genomes with `n_outputs` CPPN outputs, each mutated `mutations` times (seed 0)."""
    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "sgr.ini"
        p.write_text(neat_ini_text(str(ROOT / "configs/neat/sgr.ini"), n,
                                   {"DefaultGenome": {"num_outputs": str(n_outputs)}}))
        config = load_neat_config(p)
    random.seed(0)
    repro = neat.DefaultReproduction(config.reproduction_config, neat.reporting.ReporterSet(), None)
    gs = list(repro.create_new(config.genome_type, config.genome_config, n).values())
    for g in gs:
        for _ in range(mutations):
            g.mutate(config.genome_config)
    return gs, config.genome_config


def best_of(passes: int, fn) -> float:
    """The least wall seconds of `passes` calls of `fn`."""
    out = []
    for _ in range(passes):
        t = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t)
    return min(out)


def main(argv: list[str] | None = None) -> int:
    """Print each decoder's decoding time per genome."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--shape", default="10x10")
    ap.add_argument("--genomes", type=int, default=100)
    ap.add_argument("--mutations", type=int, default=6)
    ap.add_argument("--task", default="Walker-v0")
    args = ap.parse_args(argv)
    shape = parse_shape(args.shape)
    print(f"{'decoder':<10} {'ms/genome':>9} {'body ms':>8} {'valid':>6}  ({args.genomes} genomes at "
          f"{shape[0]}x{shape[1]}, {args.task})")
    for name, d in DECODERS.items():
        s = DecoderSettings(shape=shape, body_decoder=name, body_settings=d.resolve({}))
        gs, gc = genomes(s.n_outputs, args.genomes, args.mutations)
        total = best_of(3, lambda gs=gs, gc=gc, s=s: [decode(g, gc, args.task, s) for g in gs])
        cppns = [CompiledCPPN(g, gc) for g in gs]
        body = best_of(3, lambda cppns=cppns, s=s: [body_from_cppn(c, s) for c in cppns])
        valid = sum(is_valid_robot(body_from_cppn(c, s)) for c in cppns) / len(gs)
        print(f"{name:<10} {1e3 * total / len(gs):9.2f} {1e3 * body / len(gs):8.2f} {valid:6.0%}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
