"""What a run's checkpoint holds, as data: the NEAT search's state (evolve/search/state_codec.py)
and the method's own (`Problem.state`), written by RunDir as gzipped JSON.

    {"format": "sgr-checkpoint", "version": 1, "generation": g, "method": "sgr",
     "search": {...}, "problem": {...}}

Loading checks every field against the run's own config and neat-python INI before anything is
built from it, and never unpickles, imports or calls anything the file names: a checkpoint can
hold numbers, strings and lists, not code.
"""

from __future__ import annotations

from collections.abc import Mapping

from evolve.config import RunConfig
from evolve.methods import METHODS
from evolve.records.run_config import read_run_config
from evolve.records.rundir import RunDir
from evolve.search.neat_ini import load_neat_config
from evolve.search.state_codec import StateError


def checkpoint_data(search, problem) -> dict:
    """A checkpoint's data (without format and generation, which RunDir adds) of a NeatSearch
    and its method's Problem."""
    return {"method": problem.name, "search": type(problem).encode_search(search.state()),
            "problem": problem.state()}


def decode_checkpoint(data: dict, cfg: RunConfig | Mapping, neat_config) -> dict:
    """A checkpoint's data as the state `Experiment` restores from: the search's (neat-python
    objects rebuilt from `neat_config`) with the method's under "problem"; StateError naming the
    first field that is not as written. `cfg`: the run's config (config.yaml as read: `RunConfig.of`)."""
    cfg = RunConfig.of(cfg)
    if data.get("method") != cfg.method:
        raise StateError(f"checkpoint of method {data.get('method')!r}, the run's is {cfg.method!r}")
    state = METHODS[cfg.method].decode_search(data.get("search"), neat_config, cfg)
    if state["generation"] != data["generation"]:
        raise StateError("search.generation differs from the checkpoint's generation")
    state["problem"] = METHODS[cfg.method].decode_state(data.get("problem"), cfg)
    return state


def load_checkpoint(run: RunDir, cfg: RunConfig | None = None) -> dict | None:
    """The newest usable checkpoint of `run`, decoded (RunDir.latest_checkpoint: damaged ones are
    skipped with one warning line); None when there is none."""
    cfg = read_run_config(run, running=True)[1] if cfg is None else cfg
    neat_config = (load_neat_config(run.neat_ini())  # (a FIFO or a link refused in one line)
                   if METHODS[cfg.method].uses_neat else None)
    return run.latest_checkpoint(lambda data: decode_checkpoint(data, cfg, neat_config))
