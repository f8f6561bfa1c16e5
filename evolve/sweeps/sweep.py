"""Sweeps: every (method, task, seed) of a sweep file as an ordinary run directory, run to the end.

A sweep directory holds `sweep.yaml` (the resolved sweep: absolute config folder, overrides, the
list of runs) and `runs/<method>-<task>-s<seed>/`, each a run directory that `sgr evolve --resume`
also accepts. Each run is created here (config resolved, generation 0 checkpointed) and then
advanced by `sgr evolve --resume` in its own process, so a run that dies is retried from its own
checkpoints and never takes the others with it, and resuming a sweep is resuming its runs: a
run's results depend on its config alone, not on when, where or how often it was interrupted.

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
import math
import shutil
import signal
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
from tasks.registry import import_tasks
from tasks.specs import TASKS, closest, unknown_task
from tsim.errors import SgrError

SWEEP_FILE = "sweep.yaml"
MAX_RUNS = 10_000  # runs in one sweep: more is a typo (a seed count of 1e9 would fill memory listing them)
KEYS = ("configs", "imports", "methods", "overrides", "seeds", "tasks")
RETRIES = 2  # a run whose process dies is resumed from its checkpoints this many more times


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


class Sweep:
    """A sweep directory: create it from a sweep file, or open it to resume."""

    def __init__(self, out: str | Path, sweep: dict, named_in: Path | None = None):
        """`named_in`: the sweep.yaml it was opened from (a folder's: its imports are data)."""
        self.path = Path(out)
        self.sweep = sweep
        self.runs = runs_of(sweep)
        self.named_in = named_in

    @classmethod
    def create(cls, sweep_file: str | Path, out: str | Path) -> Sweep:
        """A new sweep directory from a sweep file (checked first); ValueError when `out` already
        holds a sweep."""
        sweep = load_sweep(sweep_file)
        out = Path(out)
        if (out / SWEEP_FILE).exists():
            raise SgrError(f"{out} already holds a sweep; use sgr sweep --resume {out} or another --out")
        (out / "runs").mkdir(parents=True, exist_ok=True)
        atomic_write(out / SWEEP_FILE, yaml.safe_dump(sweep, sort_keys=False).encode())
        return cls(out, sweep)

    @classmethod
    def open(cls, out: str | Path) -> Sweep:
        """An existing sweep directory, to resume; its sweep.yaml is checked again (the configs must
        still exist)."""
        f = Path(out) / SWEEP_FILE
        if not f.is_file():
            raise SgrError(f"{out} is not a sweep directory (no {SWEEP_FILE})")
        sweep = cls(out, check_sweep(read_yaml(f), str(f), named_in=f), named_in=f)
        old = [r.name for r in sweep.runs if sweep.run_dir(r).pickled_checkpoints()
               and not sweep.run_dir(r).checkpoints()]
        if old:  # refused before any run starts (each would fail, and be retried, alone)
            names = ", ".join(old[:3]) + (", ..." if len(old) > 3 else "")
            raise SgrError(f"{len(old)} run(s) of {out} ({names}) "
                           "hold only pickled checkpoints of an older sgr; sgr does not load pickles, "
                           "which can run any code; if you trust this folder, convert them with: "
                           f"sgr migrate {out} --trust-pickle")
        return sweep

    def run_dir(self, run: SweepRun) -> RunDir:
        """The RunDir of `run` (runs/<name>), whether or not it exists yet."""
        return RunDir(self.path / "runs" / run.name)

    def status(self, run: SweepRun) -> tuple[int, int]:
        """(generations done, generations wanted) from the run's files; (0, 0) before it exists."""
        rd = self.run_dir(run)
        if not (rd.path / "config.yaml").is_file():
            return 0, 0
        return len(rd.rows()), int(rd.config()["generations"])

    def prepare(self, run: SweepRun) -> None:
        """Create the run directory (config, generation-0 checkpoint) unless it holds a resumable run;
        a directory left without any checkpoint (killed while being created) is made anew."""
        from evolve.runs.experiment import Experiment

        rd = self.run_dir(run)
        if (rd.path / "config.yaml").is_file() and rd.has_checkpoint():
            return
        if rd.path.exists():
            shutil.rmtree(rd.path)
        path, overrides = run_config(self.sweep, run, named_in=self.named_in)
        Experiment.create(str(path), str(rd.path), overrides, quiet=True, named_in=self.named_in).close()

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


def trust_flag() -> list[str]:
    """`--trust-imports` for a run's process when this sweep was trusted with its imports."""
    from tasks.registry import imports_trusted

    return ["--trust-imports"] if imports_trusted() else []


def die_with_parent() -> None:
    """In a run's process: SIGKILL when the sweep process dies, so a killed sweep leaves no run
    going on alone (Linux; elsewhere the run's lock still keeps a resumed sweep from doubling it)."""
    try:
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


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
        log = open(sweep.run_dir(run).path / "log.txt", "ab")  # noqa: SIM115 (closed by the process)
        self.procs[run] = subprocess.Popen(
            python_command("evolve.cli", "evolve", "--resume", str(sweep.run_dir(run).path),
                           "--workers", str(workers), "--quiet", *trust_flag()),
            stdout=log, stderr=subprocess.STDOUT, env=child_env(), preexec_fn=die_with_parent)
        log.close()

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

    with sigterm_interrupts():  # and a second SIGTERM, while the runs stop, as a second Ctrl-C
        return _run_sweep(sweep, backend, quiet, every)


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

