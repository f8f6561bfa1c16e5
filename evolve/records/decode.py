"""A run's champion genome decoded at another body size (`sgr decode`).

SGR's genome is a CPPN, a function of the substrate's coordinates: queried on a 10x10 grid it draws
a 10x10 body and the controller of that body, with no further evolution. The result is written as a
champion folder (a folder holding champion.json, the file `load_champion`, `sgr render` and the
replays read from any run), so a decoded champion is used like any other. Decoded at the run's own
size it is the run's champion again, bit for bit: the genome is rebuilt from champion.json's
"genome" record in its stored order, and the record keeps the run's fitness and evaluation. At
another size its fitness is scored here as the run's champion was (one exact episode, or the run's
robust statistic over its perturbed episodes), so `rescore_champion` reproduces it.

Direct NEAT's body is queried per cell coordinate, but its network's inputs hold the observation of
a full body of its run's size (and, in the paper's layout, one output per cell): its controller has
no meaning at another size, so it decodes at its own size only. Nested NEAT's champion controller is
one genome of an inner population evolved for one body: it is refused.
"""

from __future__ import annotations

import numbers
from pathlib import Path

import numpy as np

from evolve.methods import METHODS
from evolve.nn.genome_record import genome_from_record
from evolve.records.champion import champion_record, precision_of, read_champion
from evolve.records.run_config import read_run_config
from evolve.records.rundir import RunDir
from evolve.search.neat_ini import load_neat_config
from tasks.specs import body_fit_problem
from tsim.backend import get as get_backend
from tsim.errors import SgrError


def decoded_champion(run_dir: str | Path, shape: tuple[int, int]) -> dict:
    """The champion.json record of `run_dir`'s champion genome decoded at `shape` (rows, cols);
    SgrError in one line when the method cannot be decoded there, the body does not fit the task's
    world, or the genome draws no valid robot at that size."""
    if isinstance(shape, np.ndarray):
        shape = shape.tolist()
    if (not isinstance(shape, tuple | list) or len(shape) != 2
            or not all(isinstance(v, numbers.Integral) and not isinstance(v, bool) and v > 0 for v in shape)):
        raise SgrError(f"shape must be (rows, cols) of positive integers, got {shape!r}")
    run = RunDir(run_dir)
    _, cfg = read_run_config(run, running=True)  # its task registered, config.yaml and neat.ini checked
    shape = (int(shape[0]), int(shape[1]))
    own = shape == cfg.robot_shape
    size = f"{shape[0]}x{shape[1]}"
    if (why := METHODS[cfg.method].decode_refusal(cfg, shape)) is not None:  # what the method says
        raise SgrError(f"{run_dir}: {why}")
    if (why := body_fit_problem(cfg.task, shape)) is not None:
        raise SgrError(f"--shape {size}: {why}")
    record, _, _ = read_champion(run.path)
    get_backend(precision=precision_of(record))  # scored in the champion's precision, as its run did
    if "genome" not in record:
        raise SgrError(f"{run.path / 'champion.json'}: no 'genome' record to decode")
    neat_config = load_neat_config(run.neat_ini())  # (a FIFO or a link refused in one line)
    genome = genome_from_record(record["genome"], neat_config.genome_config)
    problem = METHODS[cfg.method](cfg.replace(robot_shape=shape), neat_config)
    try:
        phenotype = problem.decode(genome)
        if not phenotype.valid:
            raise SgrError(f"at {size} the champion's genome draws no valid robot (not connected, or no "
                           "actuator)")
        origin = {"run": str(run.path.resolve()), "run_shape": list(cfg.robot_shape), "shape": list(shape)}
        if own:  # the run's champion itself: its fitness and how it was scored stand
            evaluation = {k: v for k, v in (record.get("evaluation") or {}).items()}
            fitness = record["fitness"]
        else:  # scored as the run scored its champion, under its own tag
            evaluation = {"robust": (record.get("evaluation") or {}).get("robust"),
                          "seed": (record.get("evaluation") or {}).get("seed", cfg.seed),
                          "tag": f"decoded/{size}"}
            problem.cfg = problem.cfg.replace(seed=evaluation["seed"])
            with problem.scored_with(evaluation["robust"]):
                fit, _ = problem.evaluate([phenotype], [evaluation["tag"]])
            fitness = float(fit[0])
        champ = champion_record(problem.cfg, problem, genome, phenotype, fitness, record.get("generation"),
                                evaluation)
    finally:
        problem.pool.close()
    champ["decoded"] = origin
    return champ


def write_decoded(run_dir: str | Path, shape: tuple[int, int], out: str | Path | None = None) -> Path:
    """`decoded_champion` written as OUT/champion.json (default: the folder <run>-RxC beside the
    run); returns the folder. A run folder (config.yaml) is never written into."""
    out = Path(out) if out is not None else Path(f"{Path(run_dir).resolve()}-{shape[0]}x{shape[1]}")
    if out.name == "champion.json":
        out = out.parent
    if (out / "config.yaml").exists():
        raise SgrError(f"--out {out}: a run folder; give a new folder for the decoded champion")
    champ = decoded_champion(run_dir, shape)
    out.mkdir(parents=True, exist_ok=True)
    RunDir(out).write_champion(champ)
    return out
