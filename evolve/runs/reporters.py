"""Reporters: what watches a run's generation loop, in the spirit of neat-python's ReporterSet.

A reporter is any object with some of these methods (each optional):

    start(exp)            the loop starts (a new run, or a resumed one: `exp.search.generation`
                          generations are done)
    generation(exp, row)  a generation ended: `row` is its generations.csv row (generation counted
                          from 1, as the file has it)
    end(exp)              the loop ended: finished, stopped (Ctrl-C, SIGTERM) or failed

    exp.add_reporter(MyReporter())                          # before exp.run_all()
    exp.replace_reporter(ConsoleProgress, MyConsole())      # instead of a built-in one

Every run starts with the built-in reporters (`builtin_reporters`), in this order: generations.csv's
row (`GenerationsCsv`), champion.json (`ChampionFile`), the checkpoint schedule (`Checkpointer`),
the console line (`ConsoleProgress`) and the population-growth warning (`PopulationWarning`). The
ones added later run after them, so a reporter sees its generation's row, champion and checkpoint
written, and one that fails stops the run and loses nothing of it. `TensorBoardReporter` (config
key `tensorboard: true`, `sgr evolve --tensorboard`) is one.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from evolve.records.champion import best_ever_record
from evolve.records.elites import FORMAT as ELITES_FORMAT

HOOKS = ("start", "generation", "end")
INSTALL_TENSORBOARD = "pip install 'sgr[tensorboard]' (or: pip install tensorboardX)"


def _checked(reporter: Any) -> Any:
    """`reporter`, or a TypeError when it has none of the hooks (a likely mistake)."""
    if not any(callable(getattr(reporter, h, None)) for h in HOOKS):
        raise TypeError(f"a reporter needs one of the methods {', '.join(HOOKS)}; "
                        f"{type(reporter).__name__} has none")
    return reporter


class ReporterSet:
    """The reporters of one run, called in the order they were added."""

    def __init__(self, reporters: Iterable[Any] = ()):
        self.reporters: list[Any] = []
        for r in reporters:
            self.add(r)

    def add(self, reporter: Any) -> None:
        """Add `reporter`; a TypeError when it has none of the hooks (a likely mistake)."""
        self.reporters.append(_checked(reporter))

    def replace(self, kind: type, reporter: Any) -> None:
        """Put `reporter` where the reporter of type `kind` is (the same place in the order); a
        ValueError when there is none."""
        for i, r in enumerate(self.reporters):
            if type(r) is kind:
                self.reporters[i] = _checked(reporter)
                return
        raise ValueError(f"no reporter of type {kind.__name__} to replace: "
                         f"{', '.join(type(r).__name__ for r in self.reporters) or 'none'}")

    def insert_after(self, kind: type, reporter: Any) -> None:
        """Put `reporter` just after the reporter of type `kind` (at the end when there is none)."""
        at = next((i + 1 for i, r in enumerate(self.reporters) if type(r) is kind), len(self.reporters))
        self.reporters.insert(at, _checked(reporter))

    def _call(self, hook: str, *args: Any) -> None:
        for r in self.reporters:
            fn = getattr(r, hook, None)
            if callable(fn):
                fn(*args)

    def generation(self, exp: Any, row: dict) -> None:
        """Each reporter's `generation(exp, row)`."""
        self._call("generation", exp, row)

    @contextmanager
    def running(self, exp: Any) -> Iterator[None]:
        """`start(exp)` on entering, `end(exp)` on leaving, however the loop ends."""
        self._call("start", exp)
        try:
            yield
        finally:
            self._call("end", exp)


# The reporters every run has, added first and in this order (`builtin_reporters`): what the loop
# itself once wrote. Each is replaceable (`Experiment.replace_reporter`); the order is the files'
# promise: a generation's row, then its champion, then its checkpoint, then the console.


class GenerationsCsv:
    """Appends each generation's row to the run's generations.csv."""

    def generation(self, exp: Any, row: dict) -> None:
        """The row as the file has it (generation counted from 1)."""
        exp.run.append_row(row)


class ChampionFile:
    """Writes the best-ever genome to champion.json after each generation; the last one of a run
    with final selection is that selection's (chosen before the row: a run killed while choosing
    runs its last generation again)."""

    def generation(self, exp: Any, row: dict) -> None:
        """champion.json, unless final selection chose it this generation."""
        if exp.selection is not None and exp.search.generation == exp.cfg.generations:
            return
        if exp.search.best is not None:
            exp.run.write_champion(best_ever_record(exp.cfg, exp.problem, exp.search.best))


class ArchiveFiles:
    """A map-elites run's archive (evolve/search/archive.py): every elite's record in
    elites.json after each generation (`load_champion(run, cell=...)`), written after
    champion.json and before the checkpoint; archive.png (evolve/report/archive.py) on the
    checkpoints' schedule (under a second) and with the end files."""

    def generation(self, exp: Any, row: dict) -> None:
        """elites.json, replaced whole; archive.png when a checkpoint is due."""
        exp.run.write_elites(elites_record(exp.cfg, exp.problem, exp.search))
        g, cfg = exp.search.generation, exp.cfg
        if g % cfg.checkpoint_every == 0 or g == cfg.generations:
            from evolve.report.archive import plot_archive

            plot_archive(exp.run.path)


def elites_record(cfg, problem, search) -> dict:
    """elites.json's data of a `MapElitesSearch` after its generation (counted from 1)."""
    qd = search.qd
    stats = search.archive.stats
    elites = []
    for index in sorted(search.elites):
        entry = search.elite_entry(index)
        record = best_ever_record(cfg, problem, entry)
        record.pop("archive", None)  # (the entry says it)
        elites.append({"cell": list(entry["cell"]), "measures": entry["measures"],
                       **({"behaviour": entry["behaviour"]} if "behaviour" in entry else {}),
                       "champion": record})
    return {"format": ELITES_FORMAT, "generation": search.generation, "descriptors": list(qd.descriptors),
            "ranges": [list(r) for r in qd.ranges], "resolution": list(qd.resolution),
            "coverage": float(stats.coverage), "qd_score": search.qd_score(),
            "score_offset": qd.score_offset, "elites": elites}


class Checkpointer:
    """A checkpoint every `every` generations (default: the config's `checkpoint_every`), after the
    last one, and after the generation under way when a stop was asked for (Ctrl-C, SIGTERM): the
    loop honours the stop only after this reporter."""

    def __init__(self, every: int | None = None):
        self.every = every

    def generation(self, exp: Any, row: dict) -> None:
        """Save the state when the schedule (or a stop) says so."""
        g, cfg = exp.search.generation, exp.cfg
        if g % (self.every or cfg.checkpoint_every) == 0 or g == cfg.generations or exp.stopping:
            exp.run.save_checkpoint(g, exp.state())


class ConsoleProgress:
    """The console's line per generation (nothing for a quiet run): fitness, species, valid bodies,
    seconds per generation by phase (decode: the genomes decoded into bodies and controllers,
    generations.csv's build_s; sim; neat: selection, breeding and speciation), the population's body
    diversity, and the run's seconds so far: those of the generations before a resume (their
    generations.csv total_s) and those since, so the column goes on where it stopped."""

    def start(self, exp: Any) -> None:
        """The clock of the line's last column, from the seconds of the generations already done."""
        self.t_start = time.perf_counter()
        self.before = 0.0
        run = getattr(exp, "run", None)  # (a stand-in experiment may have no folder)
        for r in run.rows() if run is not None and not exp.quiet else ():  # (quiet: no line to time)
            try:
                seconds = float(r.get("total_s") or 0.0)
            except ValueError:  # an older or hand-edited row: it counts no time
                continue
            if math.isfinite(seconds) and seconds > 0:
                self.before += seconds

    def generation(self, exp: Any, row: dict) -> None:
        """One line on stdout, flushed."""
        if exp.quiet:
            return
        elapsed = getattr(self, "before", 0.0) + time.perf_counter() - self.t_start
        best = exp.search.best["fitness"] if exp.search.best else math.nan
        if "coverage" in row:  # an archive (map-elites)
            print(f"gen {row['generation']:>4}/{exp.cfg.generations}  best {row['best']:8.3f}  "
                  f"coverage {row['coverage']:6.1%} ({row['n_elites']} elites)  QD score "
                  f"{row['qd_score']:9.3f}  valid {row['n_valid']:>4}/{row['n_valid'] + row['n_invalid']}  "
                  f"episodes {row['episodes']:>4}  {row['total_s']:5.1f} s/gen (build {row['build_s']:.2f} "
                  f"sim {row['sim_s']:.2f} archive {row['neat_s']:.2f})  {elapsed:6.0f} s",
                  file=sys.stdout, flush=True)
            return
        if "trained" in row:  # bodies trained by PPO (ga-ppo)
            print(f"gen {row['generation']:>4}/{exp.cfg.generations}  best {row['best']:8.3f}  "
                  f"(ever {best:7.3f})  mean {row['mean']:7.3f}  trained {row['trained']:>3} bodies x "
                  f"{row['timesteps'] // max(row['trained'], 1):,} steps  {row['total_s']:6.1f} s/gen "
                  f"(ga {row['neat_s']:.2f} ppo {row['build_s']:.1f} score {row['sim_s']:.1f})"
                  f"{_diversity(row)}  {elapsed:6.0f} s", file=sys.stdout, flush=True)
            return
        print(f"gen {row['generation']:>4}/{exp.cfg.generations}  best {row['best']:8.3f}  "
              f"(ever {best:7.3f})  mean {row['mean']:7.3f}  species {row['n_species']:>3}  "
              f"valid {row['n_valid']:>4}/{row['n_valid'] + row['n_invalid']}  "
              f"{row['total_s']:5.1f} s/gen (decode {row['build_s']:.2f} sim {row['sim_s']:.2f} "
              f"neat {row['neat_s']:.2f}){_diversity(row)}  {elapsed:6.0f} s", file=sys.stdout, flush=True)


def _diversity(row: dict) -> str:
    """The console's "  diversity 0.123" (nothing for a method without bodies: NaN)."""
    d = float(row.get("body_diversity", math.nan))
    return "" if math.isnan(d) else f"  diversity {d:.3f}"


class PopulationWarning:
    """One line on stderr, once per run, when the population outgrows pop_size by a quarter:
    neat-python keeps each species' elites whatever pop_size says, so a speciation that splits
    nearly every genome off grows the population (and each generation's cost) without bound."""

    def __init__(self):
        self.warned = False

    def generation(self, exp: Any, row: dict) -> None:
        """Warn, the first time the population is too large (an archive has no population)."""
        if "n_species" not in row:
            return
        n, pop = row["n_valid"] + row["n_invalid"], int(exp.cfg.pop_size)
        if self.warned or n <= 1.25 * pop:
            return
        self.warned = True
        print(f"warning: the population has grown to {n} genomes for pop_size {pop}: {row['n_species']} "
              "species each keep their elites. Speciation splits too finely: raise "
              "compatibility_threshold in the NEAT config or lower body_distance_weight",
              file=sys.stderr, flush=True)


def builtin_reporters() -> list[Any]:
    """The reporters every run starts with, in the order they must run."""
    return [GenerationsCsv(), ChampionFile(), Checkpointer(), ConsoleProgress(), PopulationWarning()]


def tensorboard_scalars(exp: Any, row: dict) -> dict[str, float]:
    """The scalars of a generation, by TensorBoard tag: fitness (best, mean, median, and the
    best-ever genome's, as the console's "ever"), population (species, genomes, the fraction of
    valid bodies, episodes, body diversity where the method has bodies), seconds (build: the
    genomes' decoding, sim, neat, total) and a map-elites run's archive (coverage, QD score; no
    species)."""
    n = int(row["n_valid"]) + int(row["n_invalid"])
    best = exp.search.best
    out = {"fitness/best": row["best"], "fitness/mean": row["mean"], "fitness/median": row["median"],
           "fitness/best_ever": best["fitness"] if best else float("nan"),
           "population/species": row.get("n_species", math.nan), "population/genomes": n,
           "population/valid_fraction": int(row["n_valid"]) / n if n else float("nan"),
           "population/episodes": row["episodes"]}
    if not math.isnan(float(row.get("body_diversity", math.nan))):
        out["population/body_diversity"] = row["body_diversity"]
    out.update({f"seconds/{k[:-2]}": row[k] for k in ("build_s", "sim_s", "neat_s", "total_s")})
    out.update({f"archive/{k}": row[k] for k in ("coverage", "qd_score") if k in row})  # map-elites
    return {k: float(v) for k, v in out.items()}


class TensorBoardReporter:
    """Each generation's scalars (`tensorboard_scalars`) as TensorBoard events in `folder` (a run's
    RUN/tensorboard/: `tensorboard --logdir RUN/tensorboard`), step = the generation. Written with
    tensorboardX (no TensorFlow or PyTorch). A resumed run drops the events of the generations it
    computes again (those after its checkpoint), so each generation is there once."""

    def __init__(self, folder: str | Path):
        from tensorboardX import SummaryWriter  # ImportError: the caller says how to install it

        self._writer_class = SummaryWriter
        self.folder = Path(folder)
        self.writer = None

    def start(self, exp: Any) -> None:
        """Open a writer (an events file of its own); on resume, TensorBoard is told to drop the
        events an earlier process wrote for the generations after the checkpoint."""
        done = exp.search.generation
        self.writer = self._writer_class(str(self.folder), purge_step=done + 1 if done else None,
                                         filename_suffix=f".after{done}")

    def generation(self, exp: Any, row: dict) -> None:
        """The generation's scalars, flushed: TensorBoard shows them at once."""
        for tag, value in tensorboard_scalars(exp, row).items():
            self.writer.add_scalar(tag, value, int(row["generation"]))
        self.writer.flush()

    def end(self, exp: Any) -> None:
        """Close the writer."""
        if self.writer is not None:
            self.writer.close()
            self.writer = None


def configured_reporters(cfg: Any, run_path: Path) -> list[Any]:
    """The reporters a run's config asks for: `tensorboard: true` a TensorBoardReporter in
    RUN/tensorboard (without tensorboardX: one line saying how to install it, and the run goes on
    without it)."""
    if not cfg.tensorboard:
        return []
    try:
        return [TensorBoardReporter(run_path / "tensorboard")]
    except ImportError:
        print(f"sgr: warning: tensorboard: true, but tensorboardX is not installed: {INSTALL_TENSORBOARD}; "
              "the run goes on without TensorBoard logging", file=sys.stderr, flush=True)
        return []
