"""Running an experiment: config -> run directory, generation loop, checkpoints, resume."""

from __future__ import annotations

import ast
import configparser
import contextlib
import io
import math
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import neat

from evolve.config import load_config
from evolve.genome import BodyAwareGenome, FlexibleReproduction
from evolve.neat_search import NeatSearch
from evolve.rollout_pool import RolloutPool
from evolve.rundir import RunDir

SECTIONS = {"DefaultGenome": BodyAwareGenome.__name__,
            "DefaultReproduction": FlexibleReproduction.__name__}


def problem_class(method: str):
    if method == "sgr":
        from evolve.sgr import SgrProblem
        return SgrProblem
    if method == "direct":
        from evolve.direct import DirectProblem
        return DirectProblem
    if method == "nested":
        from evolve.nested import NestedProblem
        return NestedProblem
    raise ValueError(f"method {method!r} is not available yet")


def ini_problem(exc: configparser.Error) -> str:
    """One line for an INI syntax error (configparser's own messages span several lines)."""
    if isinstance(exc, configparser.MissingSectionHeaderError):
        return f"line {exc.lineno}: {exc.line.strip()!r} comes before any [section] header"
    if isinstance(exc, configparser.ParsingError):
        lineno, line = exc.errors[0]
        with contextlib.suppress(ValueError, SyntaxError):
            line = ast.literal_eval(line)  # configparser stores the repr of the line
        return f"line {lineno}: cannot parse {str(line).strip()!r} (not 'key = value')"
    if isinstance(exc, configparser.DuplicateSectionError):
        return f"line {exc.lineno}: section [{exc.section}] appears twice"
    if isinstance(exc, configparser.DuplicateOptionError):
        return f"line {exc.lineno}: key {exc.option!r} appears twice in [{exc.section}]"
    return " ".join(str(exc).split())


def neat_ini_text(path: str, cfg: dict, overrides: dict) -> str:
    """The neat-python INI with pop_size and method-specific values taken from the YAML config."""
    cp = configparser.ConfigParser()
    try:
        if not cp.read(path):
            raise ValueError(f"{path}: neat config file not found")
    except configparser.Error as exc:
        raise ValueError(f"{path}: not a valid INI file: {ini_problem(exc)}") from None
    except UnicodeDecodeError:
        raise ValueError(f"{path}: not a valid INI file: not text") from None
    for section in ("NEAT", *SECTIONS):
        if section not in cp:
            raise ValueError(f"{path}: neat config lacks the [{section}] section")
    cp["NEAT"]["pop_size"] = str(cfg["pop_size"])
    # neat-python reads each section under its class's name
    for default, ours in SECTIONS.items():
        cp[ours] = dict(cp[default])
        cp.remove_section(default)
    for section, values in overrides.items():
        for k, v in values.items():
            cp[SECTIONS.get(section, section)][k] = v
    buf = io.StringIO()
    cp.write(buf)
    return buf.getvalue()


def load_neat_config(ini_path: Path, source: str | Path | None = None) -> neat.Config:
    """neat-python's Config of an INI file; errors name `source` (default: the file)."""
    try:
        return neat.Config(BodyAwareGenome, FlexibleReproduction, neat.DefaultSpeciesSet,
                           neat.DefaultStagnation, str(ini_path))
    except Exception as exc:  # neat-python raises RuntimeError/KeyError for bad INI keys
        what = " ".join(str(exc).split())  # one line
        raise ValueError(f"{source or ini_path}: bad neat-python config: {what}") from None


def neat_config_from_text(ini: str, source: str | Path | None = None) -> neat.Config:
    """neat-python reads configs only from files: load INI text through a temporary one; errors
    name `source`, the INI the text came from."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "neat.ini"
        path.write_text(ini)
        return load_neat_config(path, source or "neat config")


def genome_json(genome) -> dict:
    return {"key": genome.key,
            "nodes": [{"key": n.key, "bias": n.bias, "response": n.response, "activation": n.activation,
                       "aggregation": n.aggregation} for n in genome.nodes.values()],
            "connections": [{"in": c.key[0], "out": c.key[1], "weight": c.weight, "enabled": c.enabled}
                            for c in genome.connections.values()]}


def rollout_pool(workers: int | str):
    """Local worker processes (a number, 'auto'), or the actors of a Ray cluster ('ray')."""
    if workers == "ray":
        from evolve.ray_backend import RayRolloutPool
        return RayRolloutPool()
    return RolloutPool(workers)


class Experiment:
    def __init__(self, run: RunDir, cfg: dict, state: dict | None = None, quiet: bool = False,
                 workers: int | str | None = None):
        """`workers` overrides the config's (a resumed run may use another machine's CPUs)."""
        self.run, self.cfg, self.quiet = run, cfg, quiet
        self.neat_config = load_neat_config(run.path / "neat.ini")
        self.pool = rollout_pool(cfg.get("workers", "auto") if workers is None else workers)
        self.problem = problem_class(cfg["method"])(cfg, self.neat_config, self.pool)
        if state is not None and hasattr(self.problem, "restore"):
            self.problem.restore(state["problem"])
        self.search = NeatSearch(self.neat_config, self.problem.decode, self.problem.evaluate,
                                 seed=cfg["seed"], body_distance_weight=cfg.get("body_distance_weight", 0.0),
                                 state=state, reevaluate=cfg["method"] == "nested")

    @classmethod
    def create(cls, config_path: str, out: str, overrides: dict, quiet: bool = False) -> Experiment:
        cfg = load_config(config_path, overrides)
        problem = problem_class(cfg["method"])
        ini = neat_ini_text(cfg["neat_config"], cfg, problem.neat_overrides(cfg))
        neat_config_from_text(ini, cfg["neat_config"])  # a bad INI must fail before the run exists
        if cfg["workers"] == "ray":
            from evolve.ray_backend import require_ray
            require_ray("workers: ray")
        if hasattr(problem, "check_config"):  # e.g. the nested method's controller INI
            problem.check_config(cfg)
        run = RunDir(out)
        run.lock()
        try:
            run.create(cfg, ini)
            exp = cls(run, cfg, quiet=quiet)
            run.save_checkpoint(0, exp.state())
        except BaseException:
            run.unlock()
            raise
        return exp

    @classmethod
    def resume(cls, out: str, quiet: bool = False, workers: int | str | None = None,
               generations: int | None = None) -> Experiment:
        """Continue a run from its newest usable checkpoint; `generations` extends a run (finished
        or not) to that many generations, exactly as if it had been asked for from the start."""
        run = RunDir(out)
        cfg = run.config()
        run.lock()
        try:
            state = run.latest_checkpoint()
            if state is None:
                raise ValueError(f"{out} has no checkpoint to resume from")
            done = state["generation"]
            if generations is not None:
                if generations < done:
                    raise ValueError(f"{out} has already run {done} generations; --generations must be "
                                     f">= {done}")
                if generations != cfg["generations"]:
                    cfg = {**cfg, "generations": generations}
                    run.update_config(cfg)
            if done >= cfg["generations"]:
                raise ValueError(f"{out} is finished ({done} of {cfg['generations']} generations); "
                                 "add --generations N to extend it")
            run.truncate_rows(done)
            return cls(run, cfg, state=state, quiet=quiet, workers=workers)
        except BaseException:
            run.unlock()
            raise

    def state(self) -> dict:
        state = self.search.state()
        if hasattr(self.problem, "state"):
            state["problem"] = self.problem.state()
        return state

    def run_all(self, after_generation: Callable[[Experiment], None] | None = None) -> None:
        """Run to the configured number of generations; `after_generation(self)` is called once
        each generation's row, champion and checkpoint are written (bench/soak.py measures there)."""
        cfg, search = self.cfg, self.search
        t_start = time.perf_counter()
        while search.generation < cfg["generations"]:
            row = search.step()
            self.run.append_row(row)
            self._write_champion()
            if search.generation % cfg["checkpoint_every"] == 0 or search.generation == cfg["generations"]:
                self.run.save_checkpoint(search.generation, self.state())
            self._progress(row, time.perf_counter() - t_start)
            if after_generation is not None:
                after_generation(self)

    def _write_champion(self) -> None:
        best = self.search.best
        if best is None:
            return
        champ = {"format": "sgr-champion-1", "method": self.cfg["method"], "task": self.cfg["task"],
                 "episode_steps": self.cfg["episode_steps"], "fitness": best["fitness"],
                 "generation": best["generation"], "genome": genome_json(best["genome"])}
        champ.update(self.problem.champion(best["phenotype"]))
        self.run.write_champion(champ)

    def _progress(self, row: dict, elapsed: float) -> None:
        if self.quiet:
            return
        best = self.search.best["fitness"] if self.search.best else math.nan
        print(f"gen {row['generation'] + 1:>4}/{self.cfg['generations']}  best {row['best']:8.3f}  "
              f"(ever {best:7.3f})  mean {row['mean']:7.3f}  species {row['n_species']:>3}  "
              f"valid {row['n_valid']:>4}/{row['n_valid'] + row['n_invalid']}  "
              f"{row['total_s']:5.1f} s/gen (build {row['build_s']:.2f} sim {row['sim_s']:.2f} "
              f"neat {row['neat_s']:.2f})  {elapsed:6.0f} s", file=sys.stdout, flush=True)

    def close(self) -> None:
        """Stop the rollout worker processes and let go of the run directory."""
        self.pool.close()
        self.run.unlock()

    def finish(self) -> None:
        """End-of-run artefacts: fitness.png always, champion.gif when render_champion is set."""
        from evolve.champion import champion_gif
        from evolve.plots import plot_run

        self.close()
        plot_run(self.run.path, self.run.path / "fitness.png")
        best = self.search.best
        if best is None:
            return
        if self.cfg.get("render_champion", True):
            champion_gif(self.run.path)
        if not self.quiet:
            print(f"champion: fitness {best['fitness']:.3f} (generation {best['generation']}) -> "
                  f"{self.run.path / 'champion.json'}; plots and GIF in {self.run.path}")
