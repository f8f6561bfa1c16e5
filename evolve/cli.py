"""`sgr` command line. The dispatcher lives here (evolve is the only layer that may import all
three); evolve's own commands are evolve, sweep, report, select-champion, render and plot, and the task and
simulator commands (demo, validate, bench) come from tasks/cli.py."""

from __future__ import annotations

import argparse
import io
import os
import sys
import time
from pathlib import Path

import numpy as np

from tasks.cli import PRECISIONS, nonnegative, output_path, parse_body, positive, register_task_commands


def workers_arg(text: str) -> int | str:
    """argparse type of --workers: a positive int, 'auto' or 'ray'."""
    if text in ("auto", "ray"):
        return text
    try:
        n = int(text)
    except ValueError:
        n = 0
    if n < 1:
        raise argparse.ArgumentTypeError(f"must be a positive int, 'auto' or 'ray', got {text!r}")
    return n


class _ClosedStdoutTolerant:
    """sys.stdout for a run: once the reader of stdout is gone (`sgr evolve ... | head -2`), the
    rest is dropped and the run goes on; that is no disk error. One line on stderr says so."""

    def __init__(self, stream):
        self.stream, self.closed_pipe = stream, False

    def _gone(self) -> None:
        if not self.closed_pipe:
            self.closed_pipe = True
            try:  # what is still buffered would fail again at exit: send fd 1 to /dev/null
                os.dup2(os.open(os.devnull, os.O_WRONLY), self.stream.fileno())
            except (OSError, ValueError, io.UnsupportedOperation):
                pass
            print("sgr: stdout was closed; the run goes on without progress lines", file=sys.stderr)

    def write(self, text: str) -> int:
        """Write through until the reader is gone, then drop."""
        if not self.closed_pipe:
            try:
                return self.stream.write(text)
            except BrokenPipeError:
                self._gone()
        return len(text)

    def flush(self) -> None:
        """Flush through until the reader is gone."""
        if not self.closed_pipe:
            try:
                self.stream.flush()
            except BrokenPipeError:
                self._gone()

    def __getattr__(self, name):
        return getattr(self.stream, name)


def _resume_dir(path: str) -> str:
    """The run directory to resume, or a ValueError a person can act on."""
    p = Path(path)
    if not p.exists():
        raise ValueError(f"{path} does not exist")
    if (p / "sweep.yaml").is_file():
        raise ValueError(f"{path} is a sweep directory, not a run: continue the sweep with "
                         f"sgr sweep --resume {path}, or one of its runs with sgr evolve --resume "
                         f"{p / 'runs' / '<run>'}")
    return path


def _evolve_config(args: argparse.Namespace) -> Path:
    """The config a new run starts from: --config (a file, or a packaged config's name), the
    packaged config of --method on --task, or the default quick run."""
    from evolve.methods import METHODS
    from evolve.runs.config import configs_dir, find_config
    from tasks.specs import TASKS, unknown_name, unknown_task

    if args.config and (args.task or args.method):
        raise ValueError("give --config, or --task (with --method), not both")
    if args.config:
        return find_config(args.config)
    if args.method and not args.task:
        raise ValueError("--method goes with --task (e.g. sgr evolve --task Climber-v2 --method direct)")
    if not args.task:
        return configs_dir() / "sgr" / "quick.yaml"
    method = args.method or "sgr"
    if method not in METHODS:
        raise ValueError(unknown_name("method", method, METHODS))
    path = configs_dir() / method / f"{args.task}.yaml"
    if path.is_file():
        return path
    if args.task not in TASKS:
        raise ValueError(f"{unknown_task(args.task)} (a task of your own: --config FILE with "
                         "task: and imports:, docs/TASKS.md)")
    shipped = sorted(f.stem for f in (configs_dir() / method).glob("*.yaml"))
    raise ValueError(f"no packaged config for {method} on {args.task} (there are: {', '.join(shipped)}); "
                     "write one and give --config FILE")


def _evolve(args: argparse.Namespace) -> int:
    from evolve.runs.config import load_config
    from evolve.runs.experiment import Experiment
    from tsim import runtime

    runtime.requested_arch()  # a misspelt SGR_ARCH fails before a run directory exists
    runtime.requested_precision()  # and so does a misspelt SGR_PRECISION
    if args.resume:
        if (args.config or args.pop or args.seed is not None or args.out or args.task or args.method
                or args.precision):
            raise ValueError("--resume continues a run with its own config; only --generations "
                             "(to extend it), --workers, --trust-imports and --quiet go with it")
        exp = Experiment.resume(_resume_dir(args.resume), quiet=args.quiet, workers=args.workers,
                                generations=args.generations)
        print(f"resuming {args.resume} after generation {exp.search.generation}")
    else:
        config = _evolve_config(args)
        flags = {"generations": args.generations, "pop_size": args.pop, "seed": args.seed,
                 "workers": args.workers, "precision": args.precision}
        overrides = {k: v for k, v in flags.items() if v is not None}  # the flags given
        cfg = load_config(config, overrides)
        stamp = time.strftime("%Y%m%d-%H%M%S")
        name = f"{cfg['method']}-{config.stem}" if config.stem != cfg["method"] else config.stem
        out = args.out or str(Path("runs") / f"{name}-seed{cfg['seed']}-{stamp}")
        output_path(out, folder=True)
        exp = Experiment.create(config, out, overrides, quiet=args.quiet)
        print(f"run directory: {out}")
    return _run(exp)


def _last_checkpoint(run_path: Path) -> int | None:
    """Generations done at the newest checkpoint file (checkpoints/gen-NNNNN.*), None without one."""
    gens = [int(f.name[4:9]) for f in (run_path / "checkpoints").glob("gen-*") if f.name[4:9].isdigit()]
    return max(gens) if gens else None


def _run(exp) -> int:
    from evolve.rollout.pool import WorkerDied

    try:
        exp.run_all()
        exp.finish()
    except KeyboardInterrupt:
        done, want = exp.search.generation, exp.cfg["generations"]
        ckpt = _last_checkpoint(exp.run.path)
        where = (f"stopped after generation {done} of {want}, with a checkpoint" if ckpt == done else
                 f"stopped during generation {done + 1} of {want}; its last checkpoint is after "
                 f"generation {ckpt}")
        print(f"\nsgr: {where}; continue with: sgr evolve --resume {exp.run.path}", file=sys.stderr)
        return 130
    except WorkerDied as exc:
        print(f"sgr: error: {exc}; the run stopped during generation {exp.search.generation + 1} and "
              f"keeps its last checkpoint: sgr evolve --resume {exp.run.path}", file=sys.stderr)
        return 1
    except OSError as exc:  # e.g. a full disk: every file is still whole (a cut CSV row is dropped)
        print(f"sgr: error: {exp.write_failed(exc)}", file=sys.stderr)
        return 1
    finally:
        exp.close()
    return 0


def _sweep(args: argparse.Namespace) -> int:
    from evolve.runs.sweep import LocalBackend, Sweep, run_sweep

    if args.backend == "ray":
        from evolve.rollout.ray_cluster import require_ray
        require_ray("--backend ray")  # before the sweep directory exists
    elif args.address:
        raise ValueError("--address goes with --backend ray")
    if args.resume:
        if args.config or args.out:
            raise ValueError("--resume continues a sweep with its own sweep file; drop --config and --out")
        if not Path(args.resume).exists():
            raise ValueError(f"{args.resume} does not exist")
        sweep = Sweep.open(args.resume)
    else:
        if not args.config:
            raise ValueError("sgr sweep needs --config SWEEP.yaml (or --resume DIR)")
        from evolve.runs.config import find_config

        config = find_config(args.config, "sweep file")  # a path, or a packaged sweep's name (paper)
        stamp = time.strftime("%Y%m%d-%H%M%S")
        out = args.out or str(Path("runs") / f"sweep-{config.stem}-{stamp}")
        from tasks.registry import trust_imports

        trust_imports()  # the user names this sweep file: its imports go to the run processes trusted
        sweep = Sweep.create(config, out)
        print(f"sweep directory: {out}")
    if args.backend == "ray":
        from evolve.runs.ray_sweep import RayBackend
        backend = RayBackend(args.parallel, address=args.address)
    else:
        backend = LocalBackend(args.parallel)
    try:
        failed = run_sweep(sweep, backend, quiet=args.quiet)
    except KeyboardInterrupt:
        return 130
    return 1 if failed else 0


def _report(args: argparse.Namespace) -> int:
    from evolve.runs.report import write_report

    out = write_report(args.dir, args.out, robustness=not args.no_robustness, levels=args.noise,
                       replays=args.replays, gallery=not args.no_gallery)
    print(f"wrote {out}, {out.parent / 'report.html'}, {out.parent / 'summary.csv'} and "
          f"{out.parent / 'curves.png'}" + ("" if args.no_gallery else f" and {out.parent / 'gallery'}/"))
    return 0


def _select_champion(args: argparse.Namespace) -> int:
    from evolve.runs.experiment import select_finished_run
    from evolve.runs.final_selection import describe

    given = {k: v for k, v in (("candidates", args.candidates), ("episodes", args.episodes),
                               ("statistic", args.statistic), ("tolerance", args.tolerance),
                               ("rank", args.rank)) if v is not None}
    champ = select_finished_run(_resume_dir(args.run_dir), given, args.workers)
    print(f"{args.run_dir}: {describe(champ)}")
    return 0


def _render(args: argparse.Namespace) -> int:
    from evolve.runs.champion import champion_gif, replay_line
    from tasks.bench import sinusoid
    from tasks.render_episode import render_episode
    from tsim.body import check_robot
    from tsim.render import write_gif

    if args.out:
        output_path(args.out)
    if args.run_dir:
        if args.task or args.body:
            raise ValueError("give either RUN_DIR or --task with --body, not both")
        out = champion_gif(args.run_dir, args.out, width=args.width, height=args.height, fps=args.fps,
                           replay=args.replay, eps=args.noise, kind=args.noise_kind, offset=args.offset)
        line = replay_line(args.run_dir, args.replay, args.noise, args.noise_kind, args.offset)
        print(f"wrote {out}: {line}")
        return 0
    else:
        if not (args.task and args.body):
            raise ValueError("sgr render needs RUN_DIR, or --task and --body")
        if args.replay:
            raise ValueError("--replay renders a perturbed episode of a run's champion: give RUN_DIR")
        body = check_robot(parse_body(args.body))
        n_act = int(np.count_nonzero((body == 3) | (body == 4)))
        frames = render_episode(args.task, body, lambda t, obs: sinusoid(t, n_act), args.steps,
                                args.width, args.height, indexed=True)
        out = write_gif(frames, args.out or "robot.gif", fps=args.fps)
    print(f"wrote {out}")
    return 0


def _plot(args: argparse.Namespace) -> int:
    from evolve.runs.plots import plot_run, plot_runs, runs_plot_path

    if args.out:
        output_path(args.out)
    if len(args.run_dirs) == 1 and not (args.compare or args.per_run):
        out = plot_run(args.run_dirs[0], args.out or Path(args.run_dirs[0]) / "fitness.png")
    else:
        out = plot_runs(args.run_dirs, args.out or runs_plot_path(args.run_dirs), per_run=args.per_run)
    print(f"wrote {out}")
    return 0


def _convert_checkpoints(args: argparse.Namespace) -> int:
    from evolve.runs.legacy import convert_run, run_dirs

    if not args.trust_pickle:
        raise ValueError("an older sgr's checkpoints are pickles, and loading a pickle runs any code "
                         "its author put in it: add --trust-pickle only if you trust everyone who "
                         f"could write {args.dir}")
    for run in run_dirs(args.dir):
        written = convert_run(run)
        if written:
            print(f"{run.path}: {', '.join(written)}")
    return 0


def main(argv: list[str] | None = None) -> int:
    """The `sgr` command; returns the exit code. A ValueError from a command is printed as one
    line, sgr: error: ..., on stderr with exit code 2 (argparse's own errors exit 2 as well)."""
    p = argparse.ArgumentParser(prog="sgr", description="Batched evogym-faithful soft-robot toolkit")
    sub = p.add_subparsers(dest="cmd", required=True)
    e = sub.add_parser("evolve", help="run an evolution experiment (default: a short SGR Walker-v0 run)")
    e.add_argument("--config", help="YAML experiment config: a file, or a packaged config's name such as "
                                    "sgr/Climber-v2 or direct/Walker-v0 (default: quick, a short SGR "
                                    "Walker-v0 run)")
    e.add_argument("--task", help="the packaged config of this task (with --method; default method sgr)")
    e.add_argument("--method", help="with --task: sgr, direct or nested")
    e.add_argument("--generations", type=positive(int))
    e.add_argument("--pop", type=positive(int))
    e.add_argument("--seed", type=int)
    e.add_argument("--out", help="run directory (default runs/<method>-<config>-seed<S>-<time>)")
    e.add_argument("--workers", type=workers_arg,
                   help="rollout processes: a number, 'auto' (all CPUs) or 'ray' (the actors of a Ray "
                        "cluster); default: the config's")
    e.add_argument("--resume", metavar="DIR",
                   help="continue a run from its last checkpoint (with --generations N: extend it to N)")
    e.add_argument("--precision", choices=PRECISIONS,
                   help="the simulator's real type: f64 (evogym's bits) or f32; default: the config's, "
                        "else $SGR_PRECISION, else f64")
    e.add_argument("--quiet", action="store_true")
    e.set_defaults(fn=_evolve)
    sw = sub.add_parser("sweep", help="every method x task x seed of a sweep file, resumable")
    sw.add_argument("--config", metavar="SWEEP.yaml",
                    help="methods, tasks, seeds, [configs], [overrides], [imports]: a file, or a packaged "
                         "sweep's name (paper, tiny)")
    sw.add_argument("--out", help="sweep directory (default runs/sweep-<name>-<time>)")
    sw.add_argument("--resume", metavar="DIR",
                    help="continue a sweep: finished runs are kept, the others resumed")
    sw.add_argument("--backend", choices=("local", "ray"), default="local",
                    help="local: runs on this machine; ray: runs as tasks on a Ray cluster (default local)")
    sw.add_argument("--address", metavar="ADDR",
                    help="ray backend: join this running cluster ('auto': the one on this machine); "
                         "default: start a local Ray instance")
    sw.add_argument("--parallel", type=positive(int), default=1, metavar="K",
                    help="runs at once (on each machine with --backend ray), each with CPUs / K rollout "
                         "workers (default 1)")
    sw.add_argument("--quiet", action="store_true", help="only run starts and ends, no progress lines")
    sw.set_defaults(fn=_sweep)
    rp = sub.add_parser("report", help="a run's or a sweep's table (with the authors' figures), summary CSV "
                                       "and curves")
    rp.add_argument("dir", metavar="DIR", nargs="+",
                    help="a run directory, a sweep directory or a folder of run directories (several: one "
                         "report)")
    rp.add_argument("--out", help="report path (default DIR/report.md); summary.csv, curves.png beside it")
    rp.add_argument("--no-robustness", action="store_true",
                    help="skip replaying each champion under action noise")
    rp.add_argument("--noise", type=positive(float), nargs="+", default=[1e-9, 1e-3], metavar="EPS",
                    help="noise levels: each champion replayed with uniform(+-EPS) added to every "
                         "action (default 1e-9 1e-3)")
    rp.add_argument("--replays", type=positive(int), default=10, metavar="N",
                    help="replays per champion and noise level (default 10)")
    rp.add_argument("--no-gallery", action="store_true",
                    help="no champion GIFs (gallery/) in report.html")
    rp.set_defaults(fn=_report)
    sc = sub.add_parser("select-champion",
                        help="choose a finished run's champion afresh among its final elites by many "
                             "perturbed episodes (the final_selection config key, after the fact)")
    sc.add_argument("run_dir", metavar="RUN_DIR")
    sc.add_argument("--candidates", type=positive(int), help="top final elites scored, besides the "
                                                                "best-ever genome (default 16)")
    sc.add_argument("--episodes", type=positive(int), help="perturbed episodes per candidate (default 32)")
    sc.add_argument("--statistic", help="mean, min, median or qNN (default mean)")
    sc.add_argument("--tolerance", type=float, help="a candidate holds if its score is at least its "
                                                    "nominal return less TOLERANCE x it (default 0.05)")
    sc.add_argument("--rank", choices=("min", "score"),
                    help="among candidates that hold: the best min(score, nominal return), or the best "
                         "score (default min)")
    sc.add_argument("--workers", type=workers_arg, default=1, help="rollout processes (default 1)")
    sc.set_defaults(fn=_select_champion)
    r = sub.add_parser("render", help="GIF of a run's champion, or of any body with an open-loop gait")
    r.add_argument("run_dir", nargs="?", metavar="RUN_DIR")
    r.add_argument("--task")
    r.add_argument("--body", help="rows of digits separated by commas, or a .json/.npy matrix file")
    r.add_argument("--steps", type=positive(int), help="episode length (default: the task's paper length)")
    r.add_argument("--out", help="GIF path (default RUN_DIR/champion.gif, with --replay I "
                                 "RUN_DIR/champion-replayI.gif; with --body robot.gif)")
    r.add_argument("--width", type=positive(int), default=640)
    r.add_argument("--height", type=positive(int), default=320)
    r.add_argument("--fps", type=positive(float), default=30.0)
    r.add_argument("--replay", type=nonnegative(int), default=0, metavar="I",
                   help="the champion's perturbed replay I (as sgr report replays it; default 0: the "
                        "exact episode)")
    r.add_argument("--noise", type=nonnegative(float), default=1e-3, metavar="EPS",
                   help="with --replay: action noise scale (default 1e-3)")
    r.add_argument("--noise-kind", choices=("uniform", "gaussian"), default="uniform",
                   help="with --replay: uniform(+-EPS) or gaussian(0, EPS) (default uniform)")
    r.add_argument("--offset", type=nonnegative(float), default=0.0,
                   help="with --replay: start shifted by uniform(+-OFFSET) (evogym units, voxel 0.1)")
    r.set_defaults(fn=_render)
    pl = sub.add_parser("plot", help="best fitness per generation; runs of one method/task averaged, or "
                                     "one line per run with --per-run")
    pl.add_argument("run_dirs", nargs="+", metavar="RUN_DIR")
    pl.add_argument("--out", help="PNG path (default: RUN_DIR/fitness.png for one run, else fitness.png in "
                                  "the folder that holds the runs, e.g. runs/fitness.png for runs/*)")
    pl.add_argument("--compare", action="store_true", help="group style even for a single run")
    pl.add_argument("--per-run", action="store_true",
                    help="one line per run (coloured by method and task) instead of a mean with a band")
    pl.set_defaults(fn=_plot)
    cc = sub.add_parser("convert-checkpoints",
                        help="turn an older sgr's pickled checkpoints (gen-*.pkl) into JSON checkpoints")
    cc.add_argument("dir", metavar="DIR", help="a run directory or a sweep directory")
    cc.add_argument("--trust-pickle", action="store_true",
                    help="required: loading a pickle runs any code in it; say you trust the folder")
    cc.set_defaults(fn=_convert_checkpoints)
    trust_help = ("import the code (imports:) that a run or sweep folder names even where someone else "
                  "could have written it; say you trust the folder")
    for parser in (e, sw, rp, r, sc):
        parser.add_argument("--trust-imports", action="store_true", help=trust_help)
    register_task_commands(sub)
    args = p.parse_args(argv)
    if getattr(args, "trust_imports", False):
        from tasks.registry import trust_imports

        trust_imports()
    stdout, sys.stdout = sys.stdout, _ClosedStdoutTolerant(sys.stdout)  # `sgr ... | head` is no error
    try:
        return args.fn(args)
    except ValueError as exc:
        print(f"sgr: error: {exc}", file=sys.stderr)
        return 2
    finally:
        sys.stdout = stdout


if __name__ == "__main__":
    sys.exit(main())
