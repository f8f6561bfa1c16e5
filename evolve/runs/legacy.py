"""Checkpoints of an older sgr (pickles, gen-XXXXX.pkl) converted to today's JSON checkpoints.

This is the one place where sgr unpickles a file, and it runs only when the user says that they
trust the folder (`sgr convert-checkpoints DIR --trust-pickle`): a pickle can run any code when it
is loaded. Resuming never comes here; it refuses a run holding only pickles with the command above.
A converted checkpoint holds the same state, so the run resumes from it as it would have from the
pickle; each pickle is deleted once its JSON checkpoint is written.
"""

from __future__ import annotations

import io
import pickle
from pathlib import Path

from evolve.runs.rundir import RunDir
from tsim.errors import SgrError

# modules renamed since checkpoints were first written: old checkpoints still load
MOVED_MODULES = {"evolve.genome": "evolve.search.genome"}


class _Unpickler(pickle.Unpickler):
    def find_class(self, module: str, name: str):
        return super().find_class(MOVED_MODULES.get(module, module), name)


def load_trusted_pickle(path: Path) -> dict:
    """An older sgr's checkpoint state. RUNS ANY CODE THE FILE HOLDS: only for folders the user
    trusts."""
    state = _Unpickler(io.BytesIO(Path(path).read_bytes())).load()
    if not isinstance(state, dict) or "generation" not in state:
        raise SgrError(f"{path}: not an sgr checkpoint")
    return state


def run_dirs(path: Path) -> list[RunDir]:
    """The run directories of `path`: itself when it is a run, else those under a sweep's runs/."""
    path = Path(path)
    if (path / "config.yaml").is_file():
        return [RunDir(path)]
    if (path / "sweep.yaml").is_file():
        return [RunDir(p) for p in sorted((path / "runs").iterdir()) if (p / "config.yaml").is_file()]
    raise SgrError(f"{path} is neither a run directory (config.yaml) nor a sweep directory (sweep.yaml)")


def convert_run(run: RunDir) -> list[str]:
    """Convert every pickled checkpoint of `run` (oldest first), holding its lock; the names of the
    files written. Each state is restored into an Experiment, exactly as an older sgr resumed it,
    and saved from there."""
    from evolve.runs.experiment import Experiment

    written = []
    cfg = run.config()
    run.lock()
    try:
        for f in run.pickled_checkpoints():
            try:
                state = load_trusted_pickle(f)
                exp = Experiment(run, cfg, state=state, quiet=True, workers=1)
            except ValueError:
                raise
            except Exception as exc:
                raise SgrError(f"{f}: cannot convert ({type(exc).__name__}: "
                               f"{' '.join(str(exc).split())[:200]})") from None
            try:
                path = run.save_checkpoint(state["generation"], exp.state())
            finally:
                exp.pool.close()
            f.unlink()
            written.append(path.name)
    finally:
        run.unlock()
    return written
