"""Running an experiment: config -> run directory, generation loop, checkpoints, resume.

Generations are counted from 1 everywhere a person reads them: generations.csv, champion.json, the
console and the messages of a stop ("after generation 3" = 3 generations evaluated, the state of
checkpoint gen-00003). The NEAT search counts from 0 inside (neat-python's numbering).
A first Ctrl-C or SIGTERM lets the generation under way end, writes a checkpoint and stops
(`Interrupted`, a KeyboardInterrupt); a second stops at once, with a checkpoint of the last finished
generation (evolve/runs/stops.py).
"""

from __future__ import annotations

import json
import numbers
import time
from collections.abc import Callable
from pathlib import Path

from evolve.config import RunConfig
from evolve.methods import METHODS
from evolve.records.rundir import ELITES_FILE, RunDir
from evolve.records.segments import record_segment
from evolve.rollout.pool import BasePool, RolloutPool, resolve_workers
from evolve.runs.checkpoint import checkpoint_data, load_checkpoint
from evolve.runs.config import config_from_dict, load_config, read_run_config
from evolve.runs.continuation import continued_state
from evolve.runs.final_selection import FinalSelection, describe, explain, select_champion
from evolve.runs.reporters import (
    ArchiveFiles,
    ChampionFile,
    ReporterSet,
    builtin_reporters,
    configured_reporters,
)
from evolve.runs.stops import Interrupted, stop_after_generation
from evolve.search.neat_ini import load_neat_config, neat_config_from_text, neat_ini_text
from evolve.search.neat_search import NeatSearch
from tasks.registry import task_reference
from tasks.specs import BUILTIN
from tsim.backend import Backend
from tsim.backend import get as get_backend
from tsim.errors import SgrError


def start_backend(precision: str) -> Backend:
    """Start Taichi in this process on $SGR_ARCH in the run's `precision` (its rollout workers
    follow: they are started with this process's precision, evolve/rollout/pool.py): a backend that
    cannot run here fails now, in one line, before anything is written, and the run records what
    it runs on. The precision is an argument: no environment variable is set."""
    return get_backend(precision=precision)


def _workers(workers: int | str) -> int | str:
    """What a segment records of `workers`: the number of rollout processes, or "ray"."""
    return workers if workers == "ray" else resolve_workers(workers)


def rollout_pool(workers: int | str) -> BasePool:
    """Local worker processes (a number, 'auto'), or the actors of a Ray cluster ('ray')."""
    if workers == "ray":
        from evolve.rollout.ray_cluster import RayRolloutPool
        return RayRolloutPool()
    return RolloutPool(workers)


class Experiment:
    """One run: its directory, the method's `Problem`, the NEAT search and the rollout workers.

    It holds worker processes and the run's lock: use it in a `with` block (or call `close`).

        cfg = {"method": "sgr", "task": "Walker-v0", "generations": 5}
        with Experiment.from_config(cfg, "runs/x") as exp:
            exp.run_all(); exp.finish()
    """

    _closed = False  # `close` was called: its workers are stopped and its folder let go
    _marked_end = False  # run_all marked the run's end files due (RunDir.begin_end_files)
    _ran_to_end = False  # run_all returned (no stop, no failure)
    _finishing = False  # finish was called: it writes the end files

    def __repr__(self) -> str:
        search = getattr(self, "search", None)
        done = getattr(search, "generation", "?")
        return (f"Experiment({self.cfg.method} on {self.cfg.task}, {str(self.run.path)!r}, generation "
                f"{done} of {self.cfg.generations}{', closed' if self._closed else ''})")

    def __init__(self, run: RunDir, cfg: RunConfig | dict, state: dict | None = None, quiet: bool = False,
                 workers: int | str | None = None):
        """`cfg`: the run's config (a run folder's config.yaml as read: `RunConfig.of`); `workers`
        overrides the config's (a resumed run may use another machine's CPUs)."""
        cfg = RunConfig.of(cfg)
        self.run, self.cfg, self.quiet = run, cfg, quiet
        # row, champion, checkpoint, console line, warnings; then the config's (evolve/runs/reporters.py)
        self.reporters = ReporterSet(builtin_reporters() + configured_reporters(cfg, run.path))
        self._stop = None  # the loop's stop request, while it runs (`stopping`)
        # the run's precision for this process and its rollout workers (started with this process's)
        start_backend(cfg.precision)
        method = METHODS[cfg.method]
        self.neat_config = load_neat_config(run.path / "neat.ini") if method.uses_neat else None
        self.pool = rollout_pool(cfg.workers if workers is None else workers)
        self.problem = method(cfg, self.neat_config, self.pool)
        if state is not None:
            self.problem.restore(state.get("problem", {}))
        self.selection = cfg.final_selection
        robust = cfg.robust
        # (body_distance_weight is a key of sgr and direct; nested has none: plain NEAT speciation)
        own = self.problem.make_search(self.neat_config, cfg.seed, state)  # map-elites' archive
        self.search = own if own is not None else NeatSearch(
            self.neat_config, self.problem.decode, self.problem.evaluate,
            seed=cfg.seed, body_distance_weight=self.problem.body_distance_weight(),
            state=state, reevaluate=method.reevaluate_elites or (robust is not None and robust.reevaluate),
            accumulate=robust is not None and robust.accumulate,
            race=robust.race if robust else 0, settle=robust.settle if robust else 0)
        if method.keeps_archive:  # an archive: elites.json after champion.json
            self.reporters.insert_after(ChampionFile, ArchiveFiles())

    @classmethod
    def create(cls, config_path: str | Path, out: str | Path, overrides: dict | None = None,
               quiet: bool = False, named_in: Path | None = None) -> Experiment:
        """A new run in `out` from a YAML config, with `overrides` set over its keys.

        Args:
            config_path: The YAML config.
            out: The run's folder.
            overrides: Values set over the config's keys; a None value sets null (the CLI leaves out
                the flags not given).
            quiet: Print no console lines.
            named_in: The config was read back from this run or sweep folder (`check_config`).
        """
        return cls._start(load_config(config_path, overrides, named_in), out, quiet)

    @classmethod
    def from_config(cls, config: dict, out: str | Path, quiet: bool = False) -> Experiment:
        """A new run in `out` from a config dict (no YAML file needed).

        Relative paths are taken from the current folder, left-out files are the method's packaged
        defaults, left-out `robust`/`final_selection` the honest evaluation of `sgr evolve`'s default
        run.

        Args:
            config: The config's keys and values, as a YAML config holds them.
            out: The run's folder.
            quiet: Print no console lines.
        """
        return cls._start(config_from_dict(config, "config"), out, quiet)

    @classmethod
    def _start(cls, cfg: RunConfig, out: str | Path, quiet: bool) -> Experiment:
        ini = None
        if METHODS[cfg.method].uses_neat:
            ini = neat_ini_text(cfg.neat_config, cfg.pop_size, METHODS[cfg.method].neat_overrides(cfg))
            neat_config_from_text(ini, cfg.neat_config)  # a bad INI must fail before the run exists
        if cfg.workers == "ray":
            from evolve.rollout.ray_cluster import require_ray
            require_ray("workers: ray")
        here = start_backend(cfg.precision)  # one that cannot start fails before the run exists
        run = RunDir(out)
        with run.locked_unless_it_fails():
            run.create(cfg, ini)
            record_segment(run.path, 0, here.record(), _workers(cfg.workers))
            if cfg.task not in BUILTIN and not cfg.imports:  # registered in a script
                run.save_task(task_reference(cfg.task))
            state = None
            if cfg.start_from is not None:  # another run's population (evolve/runs/continuation.py)
                state = continued_state(cfg.start_from, load_neat_config(run.path / "neat.ini"))
            exp = cls(run, cfg, state=state, quiet=quiet)
            run.save_checkpoint(exp.search.generation, exp.state())
        return exp

    @classmethod
    def resume(cls, out: str | Path, quiet: bool = False, workers: int | str | None = None,
               generations: int | None = None) -> Experiment:
        """Continue a run from its newest usable checkpoint.

        Args:
            out: The run's folder.
            quiet: Print no console lines.
            workers: Overrides the config's `workers` (a resumed run may use another machine's CPUs).
            generations: Extend the run (finished or not) to that many generations, exactly as if
                they had been asked for from the start.

        Raises:
            ValueError: The run cannot be resumed (no checkpoint, finished, or already past
                `generations`); the message says why.
        """
        run = RunDir(out)
        # the run's own task (its imports, or the one a script registered), then every value of its
        # config.yaml and neat.ini checked as a new run's are: the folder may be a stranger's
        raw, cfg = read_run_config(run, running=True)
        here = start_backend(cfg.precision)  # the run's; the arch: this process's
        with run.locked_unless_it_fails():
            state = load_checkpoint(run, cfg)
            if state is None:
                raise SgrError(f"{out} has no checkpoint to resume from")
            done = state["generation"]
            run.check_rows()  # a damaged generations.csv is refused before anything changes
            if generations is not None:
                if (isinstance(generations, bool) or not isinstance(generations, numbers.Integral)
                        or generations < 1):
                    raise SgrError(f"generations must be a positive integer, got {generations!r}")
                generations = int(generations)
                if generations < done:
                    raise SgrError(f"{out} has already run {done} generations; --generations must be "
                                   f">= {done}")
                if generations != cfg.generations:
                    cfg = cfg.replace(generations=generations)
                    run.update_config({**raw, "generations": generations})  # its keys as they were
            if done >= cfg.generations and not run.end_files_pending():
                raise SgrError(f"{out} is finished ({done} of {cfg.generations} generations); "
                               "add --generations N to extend it")
            run.truncate_rows(done)
            exp = cls(run, cfg, state=state, quiet=quiet, workers=workers)
            record_segment(run.path, done, here.record(), _workers(workers or exp.cfg.workers))
            return exp

    def state(self) -> dict:
        """What a checkpoint holds, as JSON data: the NEAT search's state and the method's own.

        The layout is evolve/runs/checkpoint.py's.
        """
        return checkpoint_data(self.search, self.problem)

    def add_reporter(self, reporter) -> None:
        """Watch the generation loop with `reporter`.

        Args:
            reporter (object): An object with any of the methods start(exp), generation(exp, row), end(exp)
                (evolve/runs/reporters.py).
        """
        self.reporters.add(reporter)

    def replace_reporter(self, kind: type, reporter) -> None:
        """Use `reporter` in place of the built-in reporter of type `kind`, at its place in the order.

        Args:
            kind: The built-in reporter's type, say `ConsoleProgress` (evolve/runs/reporters.py).
            reporter (object): The reporter that takes its place.
        """
        self.reporters.replace(kind, reporter)

    @property
    def stopping(self) -> bool:
        """Whether a stop (Ctrl-C, SIGTERM) was asked for.

        The loop then ends after this generation, once its reporters (the checkpoint's included)
        have run.
        """
        return self._stop is not None and self._stop.is_set()

    def run_all(self, after_generation: Callable[[Experiment], None] | None = None) -> None:
        """Run to the configured number of generations.

        On Ctrl-C (SIGINT) or SIGTERM, the generation under way ends, a checkpoint is written, then
        `Interrupted` (a KeyboardInterrupt) is raised; a second one raises it at once, after a
        checkpoint of the last finished generation where the newest is older.

        Args:
            after_generation: Called with this experiment once each generation's row, champion and
                checkpoint are written (bench/soak.py measures there).
        """
        self._check_open("run_all")
        cfg, search = self.cfg, self.search
        with stop_after_generation() as stop, self.reporters.running(self):
            self._stop = stop
            finished = None  # (generation, state) of the last finished generation while it has no checkpoint
            try:
                while search.generation < cfg.generations:
                    finished = self._unsaved_state()
                    row = search.step()
                    if search.generation == cfg.generations:  # the last: its end files are due from here
                        # on, marked before its row and checkpoint make the run look finished, so a
                        # kill at any point after this makes `resume` write them (`finish`)
                        self.run.begin_end_files()
                        self._marked_end = True
                    final = self.selection is not None and search.generation == cfg.generations
                    if final:  # before the row: a run killed while choosing runs its last generation again
                        chosen = self._select_champion()
                    # its row, champion (the best-ever's, unless final selection chose it), checkpoint,
                    # console line and warnings, then the reporters added (evolve/runs/reporters.py)
                    self.reporters.generation(self, {**row, "generation": row["generation"] + 1})
                    if final and not self.quiet:
                        print(chosen, flush=True)
                    if after_generation is not None:
                        after_generation(self)
                    if stop.is_set() and search.generation < cfg.generations:
                        raise Interrupted(stop.signum)
                self._ran_to_end = True
                if search.best is not None:  # the champion is final: its one figure goes in its record
                    record_end_figures(self.run)
            except Interrupted as exc:
                if exc.at_once and finished is not None:
                    self._save_finished(*finished)
                raise
            finally:
                self._stop = None

    def _unsaved_state(self) -> tuple[int, str] | None:
        """The state after the last finished generation, as JSON text (a copy the next generation
        cannot change), when its checkpoint was not written (the schedule skipped it): what a
        second signal's stop, which cuts the next generation short, saves (`_save_finished`).
        None when the newest checkpoint is of that generation."""
        if self.run.last_checkpoint_generation(self.search.generation) == self.search.generation:
            return None
        return self.search.generation, json.dumps(self.state())

    def _save_finished(self, generation: int, state: str) -> None:
        """Write the checkpoint of finished `generation` (its state, as `_unsaved_state` took it)
        unless one as new is there: a run stopped at once resumes after its last finished
        generation, exactly as the run would have gone on."""
        newest = self.run.last_checkpoint_generation(generation)
        if newest is None or newest < generation:
            self.run.save_checkpoint(generation, json.loads(state))

    def _select_champion(self) -> str:
        """The run's end with `final_selection`: the champion chosen afresh among the final elites
        (evolve/runs/final_selection.py); returns the console's lines on it: what was chosen, in
        how long, and why."""
        t0 = time.perf_counter()
        champ = select_champion(self, self.selection)
        return (f"final selection: {describe(champ)} ({time.perf_counter() - t0:.1f} s)\n"
                f"final selection {explain(champ)}")

    def write_failed(self, exc: OSError) -> str:
        """One line for a write that failed (a full disk): the file, why, and how to complete the run.

        The line says where the run stands and gives the command that completes it. Every file is
        still whole (written whole or not at all).

        Args:
            exc: The write's error.
        """
        what = f"cannot write {exc.filename or 'a file'}: {exc.strerror or exc}"
        resume = f"sgr evolve --resume {self.run.path}"
        done = self.search.generation
        if (self.run.end_files_pending() and done == self.cfg.generations
                and self.run.last_checkpoint_generation() == done):
            return (f"{what}; the run's {self.search.generation} generations are done and checkpointed, "
                    f"its end files (fitness.png, champion.gif) are not: make room, then {resume} "
                    "writes them")
        return (f"{what}; the run stopped during generation {self.search.generation + 1} and keeps its "
                f"last checkpoint: make room, then {resume}")

    def close(self) -> None:
        """Stop the rollout worker processes and let go of the run directory (again: nothing).

        The object then runs nothing more: another process may have taken the run.
        """
        self._closed = True
        self.pool.close()
        if self._marked_end and self._ran_to_end and not self._finishing:
            # run_all ended and `finish` was not asked for (a script that wants no plot): the run is
            # as finished as it was before the mark
            self.run.end_files_written()
            self._marked_end = False
        self.run.unlock()

    def _check_open(self, what: str) -> None:
        """SgrError for `what` on a closed Experiment: without the run's lock it would advance the
        run beside whoever holds it now (generations written twice)."""
        if self._closed:
            raise SgrError(f"{what}: this Experiment of {self.run.path} is closed (its workers "
                           "stopped, its folder let go); continue the run with "
                           f"Experiment.resume({str(self.run.path)!r})")

    def __enter__(self) -> Experiment:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def finish(self) -> None:
        """Write the end-of-run artefacts: fitness.png always, champion.gif when render_champion is set.

        Each is written whole or not at all, and a run stopped while writing them (a full disk)
        writes them again on `resume`. It may be called after `close` too (a `with` block's end):
        it writes files only.
        """
        self._finishing = True
        self.close()
        write_end_files(self.run, self.cfg, champion=self.search.best is not None)
        if self.search.best is not None and not self.quiet:
            print("\n".join(champion_lines(self.run)), flush=True)


def champion_lines(run: RunDir) -> list[str]:
    """The console's lines on a finished run's champion: where it is, its body, its GIF, and last
    its headline (champion.json's `headline`: the held-out mean return under the run's noise, sd,
    worst, verdict and exact episode), with a line on why final selection's test and the verdict
    differ where they do (evolve/records/verdict.py, "One headline per champion")."""
    import numpy as np

    from evolve.methods.body_measures import describe, measures
    from evolve.records import verdict as verdict_rule
    from evolve.records.selection import passes, selection_and_verdict

    best = run.champion()
    h = verdict_rule.from_headline(best.get("headline"))
    key = (best.get("genome") or {}).get("key", "?")
    lines = [f"champion: genome {key} of generation {best['generation']} -> "
             f"{run.path / 'champion.json'}; plots and GIF in {run.path}; what each number is: "
             f"sgr explain {run.path}"]
    if best.get("body") is not None:
        lines.append(f"champion body: {describe(measures(np.asarray(best['body'])))}")
    if (run.path / "champion.gif").exists():
        lines.append(f"champion.gif: a typical perturbed episode (the median of {verdict_rule.REPLAYS} "
                     f"replays); the exact episode: sgr render {run.path} --exact")
    sel = best.get("selection")
    if h is not None and sel is not None and passes(sel) != h.holds:
        lines.append(selection_and_verdict(sel, h))
    if h is not None:
        lines.append(f"champion {h.line()}")
    return lines


def record_end_figures(run: RunDir) -> None:
    """The figures a finished run's records carry (each simulated once, kept when there): its
    champion's headline in champion.json (`record_headline`) and, for a map-elites run, each
    elite's exact return in elites.json (`record_elite_nominals`)."""
    from evolve.records.replay import record_elite_nominals, record_headline

    record_headline(run)
    if (run.path / ELITES_FILE).is_file():
        record_elite_nominals(run.path)


def write_end_files(run: RunDir, cfg: RunConfig, champion: bool = True) -> None:
    """The files drawn from a run's results: fitness.png (with its champion) always, archive.png for
    a map-elites run, champion.gif when `render_champion` is set (or the run has one: it must show
    the champion of champion.json). Each is written whole or not at all, and while they are written the run is
    marked so that `sgr evolve --resume` writes them again after a failure."""
    from evolve.records.replay import champion_gif
    from evolve.report.plots import plot_run

    run.begin_end_files()
    if champion:  # (a run killed before run_all recorded them)
        record_end_figures(run)
    plot_run(run.path, run.path / "fitness.png")
    if (run.path / ELITES_FILE).is_file():  # a map-elites run's archive
        from evolve.report.archive import plot_archive

        plot_archive(run.path)
    if champion and (cfg.render_champion or (run.path / "champion.gif").exists()):
        champion_gif(run.path)
    run.end_files_written()


def select_finished_run(run_dir: str | Path, overrides: dict | None = None,
                        workers: int | str = 1) -> dict:
    """`select_champion` (evolve/runs/final_selection.py) on a finished run's last checkpoint (`sgr
    select-champion`): the run's own `final_selection` (else the defaults) with `overrides`; then
    the files drawn from the champion (champion.gif, fitness.png) are drawn again."""
    run = RunDir(run_dir)
    _, cfg = read_run_config(run, running=True)  # its task registered, its files checked
    state = load_checkpoint(run, cfg)
    if state is None:
        raise SgrError(f"{run_dir} has no checkpoint")
    if state["generation"] < cfg.generations:
        raise SgrError(f"{run_dir} is not finished ({state['generation']} of {cfg.generations} "
                       "generations): resume it first")
    settings = FinalSelection.from_config({**(cfg.final_selection.to_json() if cfg.final_selection else {}),
                                           **(overrides or {})},
                                          "sgr select-champion")
    with run.locked_unless_it_fails():
        exp = Experiment(run, cfg, state=state, quiet=True, workers=workers)
    with exp:
        champ = select_champion(exp, settings)
    write_end_files(run, cfg)  # the new champion's GIF and plot: the run's files agree
    return champ
