"""`sgr migrate RUN [--trust-pickle]`: an older sgr's files brought to today's formats, in one command.

Two kinds of old files, each converted so that the run is the same run afterwards:
- pickles (checkpoints gen-XXXXX.pkl, a script's task.pkl): made JSON checkpoints and a task
  reference (evolve/records/legacy.py; each pickled checkpoint is restored into an Experiment
  here, `convert_run`). Loading a pickle can run any code, so this needs `--trust-pickle`;
  without it a folder holding pickles is refused before anything is changed.
- champion files (champion*.json) in an older layout: rewritten in today's compact one, holding
  the very same robot, bit for bit (evolve/records/compact.py; a method says how its controller is
  written shortest: `Problem.compact_controller`).

RUN is a run folder, a sweep folder, or any folder holding champion files (e.g. docs/): pickles are
looked for in the runs of a run or sweep folder, champion files everywhere below RUN. The older
commands `sgr convert-checkpoints` and `python -m evolve.records.compact` are aliases of this one.
"""

from __future__ import annotations

from pathlib import Path

from evolve.records.legacy import load_trusted_pickle
from evolve.records.rundir import RunDir
from tsim.errors import SgrError


def pickle_runs(path: Path) -> list[RunDir]:
    """The runs of `path` (a run, or a sweep's runs; none for another folder) holding pickles."""
    from evolve.records.legacy import run_dirs
    from tasks.registry import OLD_TASK_FILE

    path = Path(path)
    if not ((path / "config.yaml").is_file() or (path / "sweep.yaml").is_file()):
        return []
    return [r for r in run_dirs(path) if r.pickled_checkpoints() or (r.path / OLD_TASK_FILE).is_file()]


def migrate(path: str | Path, trust_pickle: bool = False) -> list[str]:
    """Convert `path`'s old files (module docstring); the lines saying what was written. SgrError,
    nothing changed, when `path` does not exist or holds pickles and `trust_pickle` is not set."""
    from evolve.records.compact import champion_files, compact_file
    from evolve.records.legacy import convert_task
    from tasks.registry import imports_trusted, trust_imports

    path = Path(path)
    if not path.exists():
        raise SgrError(f"{path} does not exist")
    runs = pickle_runs(path)
    if runs and not trust_pickle:
        raise SgrError(f"{', '.join(str(r.path) for r in runs)} hold(s) an older sgr's pickles, and loading "
                       "a pickle runs any code its author put in it: add --trust-pickle only if you "
                       f"trust everyone who could write {path}")
    lines = []
    was = imports_trusted()
    trust_imports()  # the folder is trusted: the code its configs name loads, for its checkpoints
    try:
        for run in runs:
            written = convert_task(run) + convert_run(run)
            if written:
                lines.append(f"{run.path}: {', '.join(written)}")
    finally:
        trust_imports(was)
    before = after = 0
    files = champion_files([path])
    for f in files:
        try:
            b, a = compact_file(f)
        except (OSError, UnicodeDecodeError, ValueError) as exc:
            raise SgrError(f"{f}: not a readable champion file ({exc}); the files before it are "
                           "migrated") from None
        before, after = before + b, after + a
        if a != b:
            lines.append(f"{f}: {b} -> {a} bytes")
    if files:
        lines.append(f"{len(files)} champion files: {before} -> {after} bytes")
    if not lines:  # a silent exit would leave the user guessing whether it looked at all
        lines.append(f"{path}: nothing to migrate (no pickled checkpoints, task.pkl or champion files)")
    return lines


def convert_run(run: RunDir) -> list[str]:
    """Convert every pickled checkpoint of `run` (oldest first), holding its lock; the names of the
    files written. Each state is restored into an Experiment, exactly as an older sgr resumed it,
    and saved from there."""
    from evolve.runs.experiment import Experiment

    written = []
    cfg = run.config()
    if run.pickled_checkpoints():
        run.load_task(cfg)  # a task of the user's (the folder is trusted: `sgr migrate`)
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
