"""`sgr` command line. The dispatcher lives here (evolve is the only layer that may import all
three); evolve's own commands are evolve, sweep, report, render and plot, and the task and
simulator commands (demo, validate, bench) come from tasks/cli.py."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from tasks.cli import output_path, parse_body, positive, register_task_commands


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


def _evolve(args: argparse.Namespace) -> int:
    from evolve.rollout.pool import WorkerDied
    from evolve.runs.experiment import Experiment
    from tsim import runtime

    runtime.requested_arch()  # a misspelt SGR_ARCH fails before a run directory exists
    if args.resume:
        if args.config or args.pop or args.seed is not None or args.out:
            raise ValueError("--resume continues a run with its own config; only --generations "
                             "(to extend it), --workers and --quiet go with it")
        exp = Experiment.resume(args.resume, quiet=args.quiet, workers=args.workers,
                                generations=args.generations)
        print(f"resuming {args.resume} at generation {exp.search.generation}")
    else:
        from evolve.runs.config import configs_dir

        config = args.config or str(configs_dir() / "sgr" / "quick.yaml")
        stamp = time.strftime("%Y%m%d-%H%M%S")
        out = args.out or str(Path("runs") / f"{Path(config).stem}-seed{args.seed or 0}-{stamp}")
        output_path(out, folder=True)
        exp = Experiment.create(config, out, {"generations": args.generations, "pop_size": args.pop,
                                              "seed": args.seed, "workers": args.workers},
                                quiet=args.quiet)
        print(f"run directory: {out}")
    try:
        exp.run_all()
        exp.finish()
    except KeyboardInterrupt:
        print(f"\ninterrupted at generation {exp.search.generation}; continue with: "
              f"sgr evolve --resume {exp.run.path}", file=sys.stderr)
        return 130
    except WorkerDied as exc:
        print(f"sgr: error: {exc}; the run stopped at generation {exp.search.generation} and keeps its "
              f"last checkpoint: sgr evolve --resume {exp.run.path}", file=sys.stderr)
        return 1
    except OSError as exc:  # e.g. a full disk: every file is still whole (a cut CSV row is dropped)
        print(f"sgr: error: cannot write {exc.filename}: {exc.strerror}; the run stopped at generation "
              f"{exp.search.generation} and keeps its last checkpoint: make room, then "
              f"sgr evolve --resume {exp.run.path}", file=sys.stderr)
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
        sweep = Sweep.open(args.resume)
    else:
        if not args.config:
            raise ValueError("sgr sweep needs --config SWEEP.yaml (or --resume DIR)")
        stamp = time.strftime("%Y%m%d-%H%M%S")
        out = args.out or str(Path("runs") / f"sweep-{Path(args.config).stem}-{stamp}")
        sweep = Sweep.create(args.config, out)
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

    out = write_report(args.dir, args.out, robustness=not args.no_robustness)
    print(f"wrote {out}, {out.parent / 'summary.csv'} and {out.parent / 'curves.png'}")
    return 0


def _render(args: argparse.Namespace) -> int:
    from evolve.runs.champion import champion_gif
    from tasks.bench import sinusoid
    from tasks.render_episode import render_episode
    from tsim.body import check_robot
    from tsim.render import write_gif

    if args.out:
        output_path(args.out)
    if args.run_dir:
        if args.task or args.body:
            raise ValueError("give either RUN_DIR or --task with --body, not both")
        out = champion_gif(args.run_dir, args.out, width=args.width, height=args.height, fps=args.fps)
    else:
        if not (args.task and args.body):
            raise ValueError("sgr render needs RUN_DIR, or --task and --body")
        body = check_robot(parse_body(args.body))
        n_act = int(np.count_nonzero((body == 3) | (body == 4)))
        frames = render_episode(args.task, body, lambda t, obs: sinusoid(t, n_act), args.steps,
                                args.width, args.height, indexed=True)
        out = write_gif(frames, args.out or "robot.gif", fps=args.fps)
    print(f"wrote {out}")
    return 0


def _plot(args: argparse.Namespace) -> int:
    from evolve.runs.plots import plot_run, plot_runs

    if args.out:
        output_path(args.out)
    if len(args.run_dirs) == 1 and not args.compare:
        out = plot_run(args.run_dirs[0], args.out or Path(args.run_dirs[0]) / "fitness.png")
    else:
        out = plot_runs(args.run_dirs, args.out or "fitness.png")
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
    e.add_argument("--config", help="YAML experiment config (default configs/sgr/quick.yaml)")
    e.add_argument("--generations", type=positive(int))
    e.add_argument("--pop", type=positive(int))
    e.add_argument("--seed", type=int)
    e.add_argument("--out", help="run directory (default runs/<config>-seed<S>-<time>)")
    e.add_argument("--workers", type=workers_arg,
                   help="rollout processes: a number, 'auto' (all CPUs) or 'ray' (the actors of a Ray "
                        "cluster); default: the config's")
    e.add_argument("--resume", metavar="DIR",
                   help="continue a run from its last checkpoint (with --generations N: extend it to N)")
    e.add_argument("--quiet", action="store_true")
    e.set_defaults(fn=_evolve)
    sw = sub.add_parser("sweep", help="every method x task x seed of a sweep file, resumable")
    sw.add_argument("--config", metavar="SWEEP.yaml", help="methods, tasks, seeds, [configs], [overrides]")
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
    rp = sub.add_parser("report", help="a sweep's table (with the authors' figures), summary CSV and curves")
    rp.add_argument("dir", metavar="DIR", help="a sweep directory, or a folder of run directories")
    rp.add_argument("--out", help="report path (default DIR/report.md); summary.csv, curves.png beside it")
    rp.add_argument("--no-robustness", action="store_true",
                    help="skip replaying each champion under 1e-9 action perturbations")
    rp.set_defaults(fn=_report)
    r = sub.add_parser("render", help="GIF of a run's champion, or of any body with an open-loop gait")
    r.add_argument("run_dir", nargs="?", metavar="RUN_DIR")
    r.add_argument("--task")
    r.add_argument("--body", help="rows of digits separated by commas, or a .json/.npy matrix file")
    r.add_argument("--steps", type=positive(int), help="episode length (default: the task's paper length)")
    r.add_argument("--out", help="GIF path (default RUN_DIR/champion.gif or robot.gif)")
    r.add_argument("--width", type=positive(int), default=640)
    r.add_argument("--height", type=positive(int), default=320)
    r.add_argument("--fps", type=positive(float), default=30.0)
    r.set_defaults(fn=_render)
    pl = sub.add_parser("plot", help="best fitness per generation; runs of one method/task averaged")
    pl.add_argument("run_dirs", nargs="+", metavar="RUN_DIR")
    pl.add_argument("--out", help="PNG path (default RUN_DIR/fitness.png for one run, else fitness.png)")
    pl.add_argument("--compare", action="store_true", help="group style even for a single run")
    pl.set_defaults(fn=_plot)
    cc = sub.add_parser("convert-checkpoints",
                        help="turn an older sgr's pickled checkpoints (gen-*.pkl) into JSON checkpoints")
    cc.add_argument("dir", metavar="DIR", help="a run directory or a sweep directory")
    cc.add_argument("--trust-pickle", action="store_true",
                    help="required: loading a pickle runs any code in it; say you trust the folder")
    cc.set_defaults(fn=_convert_checkpoints)
    register_task_commands(sub)
    args = p.parse_args(argv)
    try:
        return args.fn(args)
    except ValueError as exc:
        print(f"sgr: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
