"""Reporters: what watches a run's generation loop, in the spirit of neat-python's ReporterSet.

A reporter is any object with some of these methods (each optional):

    start(exp)            the loop starts (a new run, or a resumed one: `exp.search.generation`
                          generations are done)
    generation(exp, row)  a generation ended: `row` is its generations.csv row (generation counted
                          from 1, as the file has it), written with the champion and any checkpoint
    end(exp)              the loop ended: finished, stopped (Ctrl-C, SIGTERM) or failed

    exp.add_reporter(MyReporter())    # before exp.run_all()

The console line, generations.csv and the checkpoints are written by the loop itself, before the
reporters are called: a reporter that fails stops the run, and loses nothing of it.
`TensorBoardReporter` (config key `tensorboard: true`, `sgr evolve --tensorboard`) is one.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

HOOKS = ("start", "generation", "end")
INSTALL_TENSORBOARD = "pip install 'sgr[tensorboard]' (or: pip install tensorboardX)"


class ReporterSet:
    """The reporters of one run, called in the order they were added."""

    def __init__(self, reporters: Iterable[Any] = ()):
        self.reporters: list[Any] = []
        for r in reporters:
            self.add(r)

    def add(self, reporter: Any) -> None:
        """Add `reporter`; a TypeError when it has none of the hooks (a likely mistake)."""
        if not any(callable(getattr(reporter, h, None)) for h in HOOKS):
            raise TypeError(f"a reporter needs one of the methods {', '.join(HOOKS)}; "
                            f"{type(reporter).__name__} has none")
        self.reporters.append(reporter)

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


def tensorboard_scalars(exp: Any, row: dict) -> dict[str, float]:
    """The scalars of a generation, by TensorBoard tag: fitness (best, mean, median, and the
    best-ever genome's, as the console's "ever"), population (species, genomes, the fraction of
    valid bodies, episodes) and seconds (build, sim, neat, total)."""
    n = int(row["n_valid"]) + int(row["n_invalid"])
    best = exp.search.best
    out = {"fitness/best": row["best"], "fitness/mean": row["mean"], "fitness/median": row["median"],
           "fitness/best_ever": best["fitness"] if best else float("nan"),
           "population/species": row["n_species"], "population/genomes": n,
           "population/valid_fraction": int(row["n_valid"]) / n if n else float("nan"),
           "population/episodes": row["episodes"]}
    out.update({f"seconds/{k[:-2]}": row[k] for k in ("build_s", "sim_s", "neat_s", "total_s")})
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
