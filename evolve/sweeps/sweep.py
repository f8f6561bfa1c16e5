"""Sweeps: every (method, task, seed) of a sweep file as an ordinary run directory, run to the end.

A sweep directory holds `sweep.yaml` (the resolved sweep: absolute config folder, overrides, the
list of runs), `runs/<method>-<task>-s<seed>/`, each a run directory that `sgr evolve --resume`
also accepts, `sweep-runs.json` (the runs this sweep made, each with the sha256 of the config.yaml
it wrote) and `.lock` (held by the sweep command that runs it). Each run is created here (config
resolved, generation 0 checkpointed) and then advanced by `sgr evolve --resume` in its own process,
so a run that dies is retried from its own checkpoints and never takes the others with it, and
resuming a sweep is resuming its runs: a run's results depend on its config alone, not on when,
where or how often it was interrupted.

A sweep folder is data from a stranger (docs/RELIABILITY.md, "Trust"): a sweep resumes only the runs
its record names, each with the config.yaml it made; it follows no link in the folder (runs/, a
run's folder, config.yaml, log.txt, .lock); it deletes nothing but the files its own half-made run
creation left (a run recorded as being made, whose folder holds only the files making a run
writes); its runs get --trust-imports only when the sweep has imports and was trusted itself
(started from a sweep file the user named, or resumed with --trust-imports).

Sweep file:
    methods: [sgr, direct, nested]
    tasks: [Walker-v0, ObstacleTraverser-v1]
    seeds: [0, 1, 2]                  # or a count: 3 -> 0, 1, 2
    configs: path/to/configs          # optional: <method>/<task>.yaml; default the packaged configs
    imports: [mytasks.py]             # optional: modules registering tasks of your own (tasks.register)
    overrides:                        # optional: applied to every run's config ...
      generations: 100
      nested: {inner_generations: 1}  # ... and, under a method's name, to that method's runs only
"""

from __future__ import annotations

import ctypes
import errno
import fcntl
import hashlib
import json
import math
import os
import signal
import stat
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path

import yaml

from evolve.methods import METHODS
from evolve.own_modules import child_env, python_command
from evolve.records.files import atomic_write, read_yaml
from evolve.records.rundir import RunDir
from evolve.runs.config import configs_dir, short_repr
from evolve.runs.stops import hold_passed_on
from tasks.registry import import_tasks
from tasks.specs import TASKS, closest, unknown_task
from tsim.errors import SgrError
from tsim.files import read_bytes

SWEEP_FILE = "sweep.yaml"
MAX_RUNS = 10_000  # runs in one sweep: more is a typo (a seed count of 1e9 would fill memory listing them)
KEYS = ("configs", "imports", "methods", "overrides", "seeds", "tasks")
RETRIES = 2  # a run whose process dies is resumed from its checkpoints this many more times
RECORD_FILE = "sweep-runs.json"  # the runs it made: name -> its config.yaml's sha256 (None: being made)
LOCK_FILE = ".lock"  # held by the sweep command running the folder
MAX_RECORD_BYTES = 16 << 20  # sweep-runs.json of MAX_RUNS runs is about 1 MiB
MAX_CONFIG_BYTES = 1 << 20  # a run's config.yaml: a few KiB
# what making a run writes before its checkpoint 0 (RunDir.lock and create, record_segment), by name
MADE_FILES = frozenset({".lock", "config.yaml", "neat.ini", "generations.csv", "segments.json"})
MADE_CHECKPOINTS = frozenset({"gen-00000.json.gz"})
NO_LINKS = "sgr does not follow links in a sweep folder"


@dataclass(frozen=True)
class SweepRun:
    """One (method, task, seed) of a sweep; hashable, the key of the backends' process tables."""
    method: str
    task: str
    seed: int

    @property
    def name(self) -> str:
        """Its run directory's name under runs/: <method>-<task>-s<seed>."""
        return f"{self.method}-{self.task}-s{self.seed}"


def _fail(source: str, msg: str) -> ValueError:
    return SgrError(f"{source}: {msg}")


def load_sweep(path: str | Path) -> dict:
    """Read and check a sweep file; returns the resolved sweep (what sweep.yaml stores)."""
    path = Path(path)
    return check_sweep(read_yaml(path, "sweep file"), str(path), path.parent)


def check_sweep(raw, source: str = "sweep", base: Path | None = None, named_in: Path | None = None) -> dict:
    """Check a parsed sweep and resolve it (a seed count becomes a list, `configs` an absolute
    folder, relative to `base` or the cwd); every run's config is loaded, so a bad one fails before
    any run starts. ValueError naming `source`. `named_in`: the sweep folder's file the sweep was read
    from: its imports are code, imported only after --trust-imports (`tasks.registry.import_tasks`)
    and not at all when the sweep's tasks are registered already."""
    if not isinstance(raw, dict):
        raise _fail(source, "a sweep must be a mapping with methods, tasks and seeds")
    unknown = set(raw) - {"methods", "tasks", "seeds", "configs", "overrides", "imports"}
    if unknown:
        key = sorted(unknown)[0]
        raise _fail(source, f"unknown key {key!r}{closest(key, KEYS)} known keys: {', '.join(KEYS)}")
    for key in ("methods", "tasks", "seeds"):
        if key not in raw:
            raise _fail(source, f"missing required key {key!r}")
    methods, tasks, seeds = raw["methods"], raw["tasks"], raw["seeds"]
    imports = raw.get("imports") or []
    if not isinstance(imports, list) or not all(isinstance(m, str) for m in imports):
        raise _fail(source, f"key 'imports' must be a list of module names or .py files, got {imports!r}")
    imports = [str(((base or Path.cwd()) / m).resolve()) if m.endswith(".py") and not Path(m).is_absolute()
               else m for m in imports]
    registered = isinstance(tasks, list) and all(isinstance(t, str) and t in TASKS for t in tasks)
    for ref in imports if named_in is None or not registered else ():  # the user's tasks, before names
        try:
            import_tasks(ref, named_in=named_in)
        except ValueError as exc:
            raise _fail(source, f"key 'imports': {exc}") from None
    if not isinstance(methods, list) or not methods or any(m not in METHODS for m in methods):
        bad = next((m for m in methods if m not in METHODS), None) if isinstance(methods, list) else None
        raise _fail(source, f"key 'methods' must be a list of {', '.join(METHODS)}, got {methods!r}"
                            f"{closest(bad, METHODS)}")
    if not isinstance(tasks, list) or not tasks or any(t not in TASKS for t in tasks):
        bad = next((t for t in tasks if t not in TASKS), None) if isinstance(tasks, list) else None
        raise _fail(source, "key 'tasks': " + (unknown_task(bad) if bad is not None else
                                                  f"must be a list of known tasks, got {tasks!r}"))
    if isinstance(seeds, int) and not isinstance(seeds, bool) and 0 < seeds <= MAX_RUNS:
        seeds = list(range(seeds))
    if (not isinstance(seeds, list) or not seeds
            or any(not isinstance(s, int) or isinstance(s, bool) or s < 0 for s in seeds)):
        raise _fail(source, f"key 'seeds' must be a count from 1 to {MAX_RUNS:,} or a list of seeds >= 0, "
                            f"got {short_repr(seeds)}")
    configs = raw.get("configs")
    if configs is None:
        configs = configs_dir()
    elif not isinstance(configs, str):
        raise _fail(source, f"key 'configs' must be a folder path, got {configs!r}")
    configs = Path(configs) if Path(configs).is_absolute() else (base or Path.cwd()) / configs
    overrides = raw.get("overrides") or {}
    if not isinstance(overrides, dict) or any(m in overrides and not isinstance(overrides[m], dict)
                                              for m in METHODS):
        raise _fail(source, "key 'overrides' must be a mapping of config keys (and of method names to "
                            "mappings of config keys)")
    if "seed" in overrides:
        raise _fail(source, "key 'overrides' must not set 'seed': the sweep's seeds do")
    seeds = list(dict.fromkeys(seeds))
    if len(methods) * len(tasks) * len(seeds) > MAX_RUNS:
        raise _fail(source, f"{len(methods)} methods x {len(tasks)} tasks x {len(seeds)} seeds is more "
                            f"than {MAX_RUNS:,} runs")
    sweep = {"methods": list(methods), "tasks": list(tasks), "seeds": seeds,
             "configs": str(configs.resolve()), "overrides": overrides}
    if imports:
        sweep["imports"] = imports
    for run in runs_of(sweep):  # every config must exist and accept the overrides before any run starts
        run_config(sweep, run, source, named_in)
    return sweep


def runs_of(sweep: dict) -> list[SweepRun]:
    """Every (method, task, seed) of a resolved sweep, methods outermost: the order runs start in."""
    return [SweepRun(m, t, s) for m in sweep["methods"] for t in sweep["tasks"] for s in sweep["seeds"]]


def run_config(sweep: dict, run: SweepRun, source: str = "sweep",
               named_in: Path | None = None) -> tuple[Path, dict]:
    """(config file, overrides) of one run, checked: the resolved config is returned by load_config.
    `named_in`: the sweep folder's sweep.yaml, when the sweep was read back from it (its imports
    are then imported only after --trust-imports: `check_config`)."""
    from evolve.runs.config import load_config

    path = Path(sweep["configs"]) / run.method / f"{run.task}.yaml"
    if not path.is_file():
        raise _fail(source, f"no config for {run.method} on {run.task}: {path} not found")
    ov = sweep["overrides"]
    overrides = {k: v for k, v in ov.items() if k not in METHODS}
    overrides.update(ov.get(run.method, {}))
    if sweep.get("imports"):
        overrides["imports"] = sweep["imports"]
    # the config file's own errors name it
    load_config(path, {"imports": overrides["imports"]} if "imports" in overrides else {}, named_in)
    try:
        load_config(path, {**overrides, "seed": run.seed}, named_in)
    except ValueError as exc:  # an override's: name the sweep file, where it was written
        msg = str(exc).removeprefix(f"{path}: ")
        raise _fail(source, f"key 'overrides' (for {run.method} on {run.task}, config {path}): "
                            f"{msg}") from None
    return path, {**overrides, "seed": run.seed}


def _shown(path: Path | str) -> str:
    """A path as an error line shows it: control characters escaped (a planted file's name is the
    stranger's text, and never reaches the terminal raw)."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in str(path))


def _lstat(path: Path) -> os.stat_result | None:
    """`path`'s own status (a link's, not its target's); None when there is nothing there."""
    try:
        return os.lstat(path)
    except (FileNotFoundError, NotADirectoryError):
        return None


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _take_lock(folder: Path) -> int:
    """An exclusive lock on the sweep folder (`folder`/.lock, opened without following a link), held
    until the descriptor returned is closed; SgrError in one line when another sweep holds it."""
    f = folder / LOCK_FILE
    try:
        fd = os.open(f, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC | os.O_NONBLOCK, 0o666)
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise SgrError(f"{_shown(f)} is a link; {NO_LINKS}") from None
        if exc.errno in (errno.EISDIR, errno.ENXIO):
            raise SgrError(f"{_shown(f)} is not a regular file") from None
        raise
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise SgrError(f"{_shown(f)} is not a regular file")
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 32, 0).decode("ascii", "replace").strip()
            holder = holder if holder.isascii() and holder.isdigit() else "?"
            raise SgrError(f"{_shown(folder)} is being run by another sweep (pid {holder})") from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, str(os.getpid()).encode(), 0)
    except BaseException:
        os.close(fd)
        raise
    return fd


def _made_name(name: str, names: frozenset[str]) -> bool:
    """Whether `name` is one of `names` or atomic_write's temporary file for one (.NAME.XXXXXXXX)."""
    return name in names or any(name.startswith(f".{n}.") for n in names)


class Sweep:
    """A sweep directory: create it from a sweep file, or open it to resume."""

    def __init__(self, out: str | Path, sweep: dict, named_in: Path | None = None, trusted: bool = False):
        """`named_in`: the sweep.yaml it was opened from (a folder's: its imports are data);
        `trusted`: whether its runs may import the code its sweep names (`trust_flag`)."""
        self.path = Path(out)
        self.sweep = sweep
        self.runs = runs_of(sweep)
        self.named_in = named_in
        self.trusted = trusted
        self.made: dict[str, str | None] = {}  # the record (RECORD_FILE): the runs this sweep made
        self.older = False  # resumed from a folder an older sgr made: no record at all
        self._lock_fd: int | None = None

    @classmethod
    def create(cls, sweep_file: str | Path, out: str | Path, lock: bool = False) -> Sweep:
        """A new sweep directory from a sweep file (checked first), trusted with the imports the
        file names (the user named it); `lock`: hold the folder's lock (`lock`) from now on.
        SgrError when `out` already holds a sweep, or a run folder of this sweep (none is its
        own yet), or runs/ is a link."""
        sweep = load_sweep(sweep_file)
        out = Path(out)
        held = f"{_shown(out)} already holds a sweep; use sgr sweep --resume {_shown(out)} or another --out"
        if os.path.lexists(out / SWEEP_FILE):
            raise SgrError(held)
        out.mkdir(parents=True, exist_ok=True)
        new = cls(out, sweep, trusted=True)
        if lock:
            new.lock()
        try:
            if os.path.lexists(out / SWEEP_FILE):  # made meanwhile by another sweep
                raise SgrError(held)
            new.check_runs()
            (out / "runs").mkdir(exist_ok=True)
            atomic_write(out / SWEEP_FILE, yaml.safe_dump(sweep, sort_keys=False).encode())
            new._save_record()
        except BaseException:
            new.unlock()
            raise
        return new

    @classmethod
    def open(cls, out: str | Path, lock: bool = False) -> Sweep:
        """An existing sweep directory, to resume; its sweep.yaml is checked again (the configs must
        still exist), and every run folder of it (`check_runs`). Its imports are trusted only after
        --trust-imports (`tasks.registry.trust_imports`). `lock`: hold the folder's lock from now on."""
        from tasks.registry import imports_trusted

        out = Path(out)
        f = out / SWEEP_FILE
        if f.is_symlink():
            raise SgrError(f"{_shown(f)} is a link; {NO_LINKS}")
        if not f.is_file():
            raise SgrError(f"{out} is not a sweep directory (no {SWEEP_FILE})")
        fd = _take_lock(out) if lock else None
        try:
            sweep = cls(out, check_sweep(read_yaml(f), str(f), named_in=f), named_in=f,
                        trusted=imports_trusted())
            sweep._lock_fd = fd
            sweep.older = _lstat(out / RECORD_FILE) is None  # (a sweep of an older sgr)
            sweep.made = sweep._read_record()
            sweep.check_runs()
        except BaseException:
            if fd is not None:
                os.close(fd)
            raise
        old = [r.name for r in sweep.runs if sweep.run_dir(r).pickled_checkpoints()
               and not sweep.run_dir(r).checkpoints()]
        if old:  # refused before any run starts (each would fail, and be retried, alone)
            sweep.unlock()
            names = ", ".join(old[:3]) + (", ..." if len(old) > 3 else "")
            raise SgrError(f"{len(old)} run(s) of {out} ({names}) "
                           "hold only pickled checkpoints of an older sgr; sgr does not load pickles, "
                           "which can run any code; if you trust this folder, convert them with: "
                           f"sgr migrate {out} --trust-pickle")
        return sweep

    # ------------------------------------------------------------------ the folder's lock
    @property
    def locked(self) -> bool:
        """Whether this object holds the folder's lock."""
        return self._lock_fd is not None

    def lock(self) -> None:
        """Hold the sweep folder for this command (an flock on its .lock, which is never a link):
        SgrError `DIR is being run by another sweep (pid P)` while another sweep holds it, so two
        sweeps never run, make or refuse each other's runs."""
        if self._lock_fd is None:
            self._lock_fd = _take_lock(self.path)

    def unlock(self) -> None:
        """Release the lock taken by `lock`; nothing happens when it is not held."""
        if self._lock_fd is not None:
            os.close(self._lock_fd)
            self._lock_fd = None

    # ------------------------------------------------------------------ the record of its runs
    def _read_record(self) -> dict[str, str | None]:
        """RECORD_FILE's runs: name -> sha256 of the config.yaml the sweep wrote (None: being made);
        {} without the file (a sweep of an older sgr: it made none that it knows of)."""
        f = self.path / RECORD_FILE
        if _lstat(f) is None:
            return {}
        data = read_bytes(f, MAX_RECORD_BYTES)
        try:
            raw = json.loads(data)
        except (ValueError, RecursionError):
            raw = None
        runs = raw.get("runs") if isinstance(raw, dict) else None
        if not isinstance(runs, dict) or not all(
                isinstance(v, str) and len(v) == 64 and all(c in "0123456789abcdef" for c in v) or v is None
                for v in runs.values()):
            raise SgrError(f"{_shown(f)}: not a sweep's record of its runs ({{\"runs\": {{name: sha256}}}})")
        return dict(runs)

    def _save_record(self) -> None:
        atomic_write(self.path / RECORD_FILE,
                     (json.dumps({"runs": self.made}, indent=1, sort_keys=True) + "\n").encode())

    # ------------------------------------------------------------------ its runs
    def run_dir(self, run: SweepRun) -> RunDir:
        """The RunDir of `run` (runs/<name>), whether or not it exists yet."""
        return RunDir(self.path / "runs" / run.name)

    def check_runs(self) -> None:
        """Refuse, in one line and before any run starts, a sweep folder this sweep may not run:
        runs/ a link or not a folder, or a run folder it may neither resume nor make (`_state`)."""
        runs = self.path / "runs"
        st = _lstat(runs)
        if st is not None and stat.S_ISLNK(st.st_mode):
            raise SgrError(f"{_shown(runs)} is a link; {NO_LINKS}")
        if st is not None and not stat.S_ISDIR(st.st_mode):
            raise SgrError(f"{_shown(runs)} is not a folder")
        for run in self.runs:
            self._state(run)

    def _state(self, run: SweepRun) -> str:
        """What `prepare` does with `run`'s folder: "new" (there is none: make it), "remake" (the
        sweep's own run, stopped while being made: its files removed, made anew) or "resume" (a run
        this sweep made, its config.yaml unchanged, with a checkpoint). SgrError in one line, naming
        the folder, for anything else: a link, a folder the sweep's record does not name, a changed
        config.yaml, a run without config.yaml or checkpoint (reported, never removed)."""
        p = self.run_dir(run).path
        st = _lstat(p)
        if st is None:
            return "new"
        if stat.S_ISLNK(st.st_mode):
            raise SgrError(f"{_shown(p)} is a link; {NO_LINKS}")
        if not stat.S_ISDIR(st.st_mode):
            raise SgrError(f"{_shown(p)} is not a folder")
        move = "sgr neither resumes nor removes it: move it away and the sweep makes the run anew"
        if run.name not in self.made:
            if self.older:  # resuming an older sgr's sweep: it kept no record
                raise SgrError(f"{_shown(p)}: {_shown(self.path)} was made by an older sgr, which kept no "
                               f"record of the runs it made ({RECORD_FILE}); if its runs are yours, record "
                               f"them with: sgr migrate {_shown(self.path)}")
            raise SgrError(f"{_shown(p)} is not a run this sweep made ({RECORD_FILE} has no record of it); "
                           f"{move}, or resume it alone with sgr evolve --resume {_shown(p)}")
        if self.made[run.name] is None:
            self._half_made_files(p)
            return "remake"
        for name in (".lock", "log.txt", "checkpoints", "generations.csv", "neat.ini", "segments.json"):
            f = p / name
            if (fst := _lstat(f)) is not None and stat.S_ISLNK(fst.st_mode):
                raise SgrError(f"{_shown(f)} is a link; {NO_LINKS}")
        cfg = p / "config.yaml"
        if _lstat(cfg) is None:
            raise SgrError(f"{_shown(p)} has no config.yaml; {move}")
        data = read_bytes(cfg, MAX_CONFIG_BYTES)
        if _sha256(data) != self.made[run.name]:
            raise SgrError(f"{_shown(cfg)} is not the config this sweep made for the run (it changed since); "
                           f"{move}")
        if trust_flag(self):  # the imports its process will be trusted with: the sweep's own
            raw = yaml.safe_load(data)
            if not isinstance(raw, dict) or raw.get("imports") != self.sweep["imports"]:
                raise SgrError(f"{_shown(cfg)} names other imports than {self.named_in or 'the sweep file'}; "
                               f"{move}")
        if not self.run_dir(run).has_checkpoint():
            raise SgrError(f"{_shown(p)} has no checkpoint; {move}")
        return "resume"

    def _half_made_files(self, p: Path) -> list[Path]:
        """The files of a run folder that making a run writes before its first checkpoint (by name,
        regular files and the checkpoints folder, no links); SgrError naming the first other file."""
        found: list[Path] = []
        for entry in sorted(os.scandir(p), key=lambda e: e.name):
            if entry.name == "checkpoints" and entry.is_dir(follow_symlinks=False):
                for sub in sorted(os.scandir(entry.path), key=lambda e: e.name):
                    if not (sub.is_file(follow_symlinks=False) and _made_name(sub.name, MADE_CHECKPOINTS)):
                        raise self._not_made(p, Path(sub.path))
                    found.append(Path(sub.path))
            elif entry.is_file(follow_symlinks=False) and _made_name(entry.name, MADE_FILES):
                found.append(Path(entry.path))
            else:
                raise self._not_made(p, Path(entry.path))
        return found

    @staticmethod
    def _not_made(p: Path, f: Path) -> SgrError:
        return SgrError(f"{_shown(p)} was being made by this sweep, but holds {_shown(f.relative_to(p))}, "
                        "which making a run does not write; sgr neither resumes nor removes it: move it away "
                        "and the sweep makes the run anew")

    def status(self, run: SweepRun) -> tuple[int, int]:
        """(generations done, generations wanted) from the run's files; (0, 0) before it exists."""
        rd = self.run_dir(run)
        if not (rd.path / "config.yaml").is_file():
            return 0, 0
        return len(rd.rows()), int(rd.config()["generations"])

    def prepare(self, run: SweepRun) -> None:
        """Make the run directory (config, generation-0 checkpoint) unless it holds a run this sweep
        made and may resume (`_state`); a run of its own left without a checkpoint (killed while being
        made) is made anew, once the files making it wrote are removed (nothing else ever is). The
        run is recorded as being made before, and with its config.yaml's sha256 after."""
        from evolve.runs.experiment import Experiment

        state = self._state(run)
        if state == "resume":
            return
        rd = self.run_dir(run)
        if state == "remake":
            rd.lock()  # (no process of a run holds it meanwhile)
            try:
                files = self._half_made_files(rd.path)
                for f in files:
                    if f.name != LOCK_FILE:
                        f.unlink()
                if (rd.path / "checkpoints").is_dir():
                    (rd.path / "checkpoints").rmdir()  # (empty now)
            finally:
                rd.unlock()
        if self.made.get(run.name, "") is not None:
            self.made[run.name] = None
            self._save_record()
        path, overrides = run_config(self.sweep, run, named_in=self.named_in)
        Experiment.create(str(path), str(rd.path), overrides, quiet=True, named_in=self.named_in).close()
        self.made[run.name] = _sha256(read_bytes(rd.path / "config.yaml", MAX_CONFIG_BYTES))
        self._save_record()

    def pending(self) -> list[SweepRun]:
        """Runs not finished yet, including those not created yet, in sweep order."""
        out = []
        for run in self.runs:
            done, want = self.status(run)
            if want == 0 or done < want:
                out.append(run)
        return out


class BackendLost(RuntimeError):
    """The machines a sweep runs on are gone (a whole Ray cluster): the sweep stops, to be resumed."""


def trust_flag(sweep: Sweep) -> list[str]:
    """`--trust-imports` for a run's process, only when the sweep names imports and was trusted with
    them itself (`Sweep.trusted`); the run's config.yaml is the one the sweep made (`Sweep.prepare`
    checked it), so the run imports only what the sweep names."""
    return ["--trust-imports"] if sweep.trusted and sweep.sweep.get("imports") else []


def open_log(path: Path) -> int:
    """A run's log.txt opened for appending (created when missing), as a file descriptor; SgrError
    in one line when it is a link or not a regular file (a write never follows a link out of the
    folder, and a FIFO never blocks)."""
    try:
        fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC
                     | os.O_NONBLOCK, 0o666)
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise SgrError(f"{path} is a link; {NO_LINKS}") from None
        if exc.errno == errno.ENXIO:  # a FIFO nobody reads
            raise SgrError(f"{path} is not a regular file") from None
        raise
    if not stat.S_ISREG(os.fstat(fd).st_mode):
        os.close(fd)
        raise SgrError(f"{path} is not a regular file")
    return fd


def die_with_parent() -> None:
    """In a run's process: SIGKILL when the sweep process dies, so a killed sweep leaves no run
    going on alone (Linux; elsewhere the run's lock still keeps a resumed sweep from doubling it)."""
    try:
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


def run_process_setup() -> None:
    """A run's process, before its program starts (Popen's preexec_fn): it dies with the sweep's
    process (`die_with_parent`) and holds a stop passed on until its loop can honour it
    (evolve/runs/stops.py `hold_passed_on`; imported already: nothing is imported after a fork)."""
    die_with_parent()
    hold_passed_on()


class LocalBackend:
    """Runs on this machine, `parallel` at a time, each with cpus / parallel rollout workers."""

    resume_args = ""  # what `sgr sweep --resume DIR` needs besides DIR to resume on this backend

    def __init__(self, parallel: int = 1):
        self.parallel = parallel
        self.procs: dict[SweepRun, subprocess.Popen] = {}

    def start(self, sweep: Sweep, run: SweepRun) -> None:
        """Start `run` (already prepared) as `sgr evolve --resume` in a child process writing to its
        log.txt, with CPUs / parallel rollout workers."""
        from evolve.rollout.pool import resolve_workers

        workers = max(1, resolve_workers("auto") // self.parallel)
        log = open_log(sweep.run_dir(run).path / "log.txt")
        try:
            self.procs[run] = subprocess.Popen(
                python_command("evolve.cli", "evolve", "--resume", str(sweep.run_dir(run).path),
                               "--workers", str(workers), "--quiet", *trust_flag(sweep)),
                stdout=log, stderr=subprocess.STDOUT, env=child_env(), preexec_fn=run_process_setup)
        finally:
            os.close(log)

    def poll(self) -> dict[SweepRun, int]:
        """Runs that ended since the last call, with their exit codes."""
        ended = {r: p.returncode for r, p in self.procs.items() if p.poll() is not None}
        for r in ended:
            del self.procs[r]
        return ended

    def stop(self) -> None:
        """Ask every running run to stop and wait: each ends its generation and writes a checkpoint,
        as on its first Ctrl-C or SIGTERM. The ask (SIGUSR1, evolve/runs/stops.py) never counts as a
        second signal, so a run that got Ctrl-C or a scheduler's SIGTERM itself still finishes its
        generation. A second Ctrl-C or SIGTERM while waiting kills the runs: each keeps its last
        checkpoint."""
        from evolve.runs.stops import PASSED_ON

        for p in self.procs.values():
            if p.poll() is None:
                p.send_signal(PASSED_ON)
        try:
            for p in self.procs.values():
                p.wait()
        except KeyboardInterrupt:
            for p in self.procs.values():
                p.kill()
                p.wait()
            raise
        finally:
            self.procs = {}


def _hms(seconds: float) -> str:
    if not math.isfinite(seconds):
        return "?"
    m, s = divmod(int(seconds), 60)
    h, m = divmod(m, 60)
    return f"{h}h{m:02d}m" if h else f"{m}m{s:02d}s"


def run_sweep(sweep: Sweep, backend: LocalBackend, quiet: bool = False, every: float = 30.0) -> int:
    """Run every unfinished run; returns the number of runs that failed after their retries. Ctrl-C
    or SIGTERM (a cluster's scheduler) stops the runs (`backend.stop`) and raises KeyboardInterrupt
    (`Interrupted` for SIGTERM)."""
    from evolve.runs.stops import sigterm_interrupts

    took = not sweep.locked
    if took:  # (the CLI holds it from before the sweep is opened)
        sweep.lock()
    try:
        sweep.check_runs()
        with sigterm_interrupts():  # and a second SIGTERM, while the runs stop, as a second Ctrl-C
            return _run_sweep(sweep, backend, quiet, every)
    finally:
        if took:
            sweep.unlock()


def _run_sweep(sweep: Sweep, backend: LocalBackend, quiet: bool, every: float) -> int:
    total = len(sweep.runs)
    queue = sweep.pending()
    failures: dict[SweepRun, int] = {}
    t0 = time.monotonic()
    gens_at_start = sum(sweep.status(r)[0] for r in sweep.runs)
    last_report = time.monotonic()

    def say(msg: str) -> None:
        print(f"[sweep {_hms(time.monotonic() - t0)}] {msg}", flush=True)

    say(f"{total - len(queue)}/{total} runs done; {len(queue)} to run, {backend.parallel} at a time")
    try:
        while queue or backend.procs:
            while queue and len(backend.procs) < backend.parallel:
                run = queue.pop(0)
                sweep.prepare(run)
                backend.start(sweep, run)
                say(f"start {run.name} at generation {sweep.status(run)[0]}")
            time.sleep(0.5)
            for run, rc in backend.poll().items():
                done, want = sweep.status(run)
                if done >= want:
                    say(f"done {run.name}: best {_best(sweep, run)}")
                    continue
                failures[run] = failures.get(run, 0) + 1
                log = sweep.run_dir(run).path / "log.txt"
                if failures[run] <= RETRIES:
                    say(f"{run.name} stopped (exit {rc}) at generation {done}; resuming it (see {log})")
                    queue.insert(0, run)
                else:
                    say(f"{run.name} failed {failures[run]} times (exit {rc}); giving up on it (see {log})")
            if not quiet and time.monotonic() - last_report >= every:
                last_report = time.monotonic()
                say(_progress(sweep, backend, t0, gens_at_start))
    except KeyboardInterrupt as exc:
        try:
            backend.stop()
        finally:  # a second signal while the runs stop (it kills them) is raised, with the same words
            signum = getattr(exc, "signum", signal.SIGINT)
            by = f" by {signal.Signals(signum).name}" if signum != signal.SIGINT else ""  # (Ctrl-C: as ever)
            say(f"interrupted{by}; continue with: sgr sweep --resume {sweep.path}")
        raise
    except SgrError:  # a run refused as it was about to start (its folder changed meanwhile): one line
        backend.stop()
        raise
    except BackendLost as exc:  # one line, `sgr: error: ...`, exit 2
        backend.stop()
        raise SgrError(f"{exc}; every run keeps its last checkpoint; continue with: "
                       f"sgr sweep --resume {sweep.path}{getattr(backend, 'resume_args', '')}") from None
    failed = [r for r, n in failures.items() if n > RETRIES]
    say(f"{total - len(sweep.pending())}/{total} runs done"
        + (f"; failed: {', '.join(r.name for r in failed)}" if failed else "")
        + f"; report with: sgr report {sweep.path}")
    return len(failed)


def _best(sweep: Sweep, run: SweepRun) -> str:
    rows = sweep.run_dir(run).rows()
    return f"{max(float(r['best']) for r in rows):.3f}" if rows else "-"


def _progress(sweep: Sweep, backend: LocalBackend, t0: float, gens_at_start: int) -> str:
    done_runs = total_gens = done_gens = 0
    for run in sweep.runs:
        done, want = sweep.status(run)
        want = want or _wanted(sweep, run)
        done_runs += done >= want
        done_gens += done
        total_gens += want
    rate = (done_gens - gens_at_start) / max(1e-9, time.monotonic() - t0)  # generations per second
    eta = (total_gens - done_gens) / rate if rate > 0 else math.inf
    running = ", ".join(f"{r.name} {sweep.status(r)[0]}/{sweep.status(r)[1]} best {_best(sweep, r)}"
                        for r in backend.procs)
    return f"{done_runs}/{len(sweep.runs)} runs done; running: {running or '-'}; ETA {_hms(eta)}"


def _wanted(sweep: Sweep, run: SweepRun) -> int:
    from evolve.runs.config import load_config

    path, overrides = run_config(sweep.sweep, run, named_in=sweep.named_in)
    return int(load_config(path, overrides, sweep.named_in).generations)



def record_older_sweep(path: str | Path) -> list[str]:
    """Write the record of an older sgr's sweep folder (which kept none): each run folder under
    runs/ with a config.yaml, by that file's sha256, so that `sgr sweep --resume` resumes them.

    Only for a folder the user names in `sgr migrate DIR`: the record says "this sweep made these
    runs", which a folder received from someone else must not be able to say of itself.

    Returns:
        The lines saying what was recorded (none for a folder that is not such a sweep).

    Raises:
        SgrError: a link or a file that is not a regular one where a run's config.yaml belongs.
    """
    path = Path(path)
    if _lstat(path / SWEEP_FILE) is None or _lstat(path / RECORD_FILE) is not None:
        return []
    runs = path / "runs"
    st = _lstat(runs)
    if st is None or not stat.S_ISDIR(st.st_mode):
        return []
    made: dict[str, str | None] = {}
    for p in sorted(runs.iterdir()):
        pst = _lstat(p)
        if pst is None or not stat.S_ISDIR(pst.st_mode) or _lstat(p / "config.yaml") is None:
            continue  # a link, a file or a folder with no run: not recorded (a resume names it)
        made[p.name] = _sha256(read_bytes(p / "config.yaml", MAX_CONFIG_BYTES))
    atomic_write(path / RECORD_FILE, (json.dumps({"runs": made}, indent=1, sort_keys=True) + "\n").encode(),
                 inside=path)
    return [f"{_shown(path)}: recorded its {len(made)} run{'s' if len(made) != 1 else ''} in {RECORD_FILE} "
            "(a sweep resumes only the runs it recorded)"]
