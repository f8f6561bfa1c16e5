"""A run that starts from another run's population (config key `start_from`), e.g. at a new size.

    start_from: {run: runs/sgr-5x5, generation: 50}    # generation left out: its newest checkpoint

The new run takes the NEAT state of that run's checkpoint after generation G (population, species,
innovation and key counters, Python's random state) and evolves on from generation G + 1 at its
own config's robot_shape; `generations` counts from the start of the first run, as `sgr evolve
--resume --generations N` does. Fitness measured at the old size does not carry over: every
genome, species and the best-ever record start unscored, and species' stagnation clocks restart
at G. This is for SGR, whose genomes are CPPNs and so free of the body's size (and of the task; the
new run may even draw bodies with another body decoder whose CPPN has as many outputs):
direct NEAT's network has inputs and outputs per cell of its run's shape, and nested NEAT keeps a
controller population per body. The run's config.yaml records where it came from: the run's
absolute path and G.
"""

from __future__ import annotations

from pathlib import Path

from evolve.config import RunConfig
from evolve.methods import METHODS
from evolve.methods.sgr.decoders import DEFAULT, body_decoder
from evolve.records.rundir import RunDir, checkpoint_generation, read_checkpoint_file
from evolve.search.state_codec import decode_search_state
from tsim.errors import SgrError


def check_start_from(cfg: RunConfig, source: str) -> dict:
    """`start_from` checked against the run it names and resolved to {run: absolute path,
    generation: G}; SgrError naming the key otherwise."""
    key = f"{source}: key 'start_from'"
    start = cfg.start_from
    if set(start) - {"run", "generation"} or not isinstance(start.get("run"), str):
        raise SgrError(f"{key} must be {{run: PATH, generation: G}} (generation optional), got {start!r}")
    if not METHODS[cfg.method].starts_from_runs:
        raise SgrError(f"{key}: only sgr runs start from another run's population (its genomes are "
                       f"CPPNs, free of the body's size); a {cfg.method} run continues with "
                       "sgr evolve --resume")
    run = RunDir(Path(start["run"]).resolve())
    if not (run.path / "config.yaml").is_file():
        raise SgrError(f"{key}: {start['run']} is not a run folder (no config.yaml)")
    src = run.config()
    if src.get("method") != cfg.method:
        raise SgrError(f"{key}: {start['run']} is a {src.get('method')} run, not an {cfg.method} one")
    theirs, ours = cppn_outputs(src), cppn_outputs({"cppn_outputs": cfg.cppn_outputs,
                                                     "body_decoder": cfg.body_decoder})
    if theirs != ours:
        raise SgrError(f"{key}: {start['run']} evolved CPPNs with {theirs} outputs (cppn_outputs "
                       f"{src.get('cppn_outputs', 1)}, body_decoder {src.get('body_decoder', DEFAULT)}); "
                       f"this config's have {ours} (cppn_outputs {cfg.cppn_outputs}, body_decoder "
                       f"{cfg.body_decoder})")
    generation = start.get("generation", run.last_checkpoint_generation())
    if generation is None:
        raise SgrError(f"{key}: {start['run']} has no checkpoint to start from")
    if not isinstance(generation, int) or isinstance(generation, bool) or not (
            run.ckpt_dir / f"gen-{generation:05d}.json.gz").is_file():
        kept = ", ".join(str(checkpoint_generation(f)) for f in run.checkpoints()) or "none"
        raise SgrError(f"{key}: {start['run']} has no checkpoint after generation {generation!r} "
                       f"(it keeps: {kept})")
    if cfg.generations <= generation:
        raise SgrError(f"{source}: key 'generations' counts from the start of {start['run']}, which "
                       f"has run {generation}: it must be above {generation}, got {cfg.generations}")
    return {"run": str(run.path), "generation": generation}


def cppn_outputs(raw: dict) -> int:
    """The CPPN outputs of an sgr run's genomes, from its config.yaml (`raw`): its body decoder's
    (an older run's: the paper's substrate, 1), plus the controller's own with cppn_outputs 2."""
    return body_decoder(raw.get("body_decoder", DEFAULT)).body_outputs + int(raw.get("cppn_outputs", 1)) - 1


def continued_state(start_from: dict, neat_config) -> dict:
    """The search state a new run starts from (`NeatSearch(state=...)`): the named checkpoint's NEAT
    state rebuilt with the new run's neat-python config, every fitness forgotten."""
    run = RunDir(start_from["run"])
    g = start_from["generation"]
    path = run.ckpt_dir / f"gen-{g:05d}.json.gz"
    try:
        data = read_checkpoint_file(path)
        state = decode_search_state(data.get("search"), neat_config)
    except (OSError, ValueError, EOFError) as exc:
        raise SgrError(f"start_from: cannot read {path}: {exc}") from None
    if state["generation"] != g:
        raise SgrError(f"start_from: {path} holds generation {state['generation']}, not {g}")
    genomes = list(state["population"].values())
    for s in state["species"]["species"].values():
        genomes += list(s.members.values()) + ([s.representative] if s.representative is not None else [])
        s.fitness = s.adjusted_fitness = None
        s.fitness_history = []
        s.last_improved = g
    for genome in genomes:
        genome.fitness = None
    state.update(best=None, pending_build_s=0.0, problem={})
    return state
