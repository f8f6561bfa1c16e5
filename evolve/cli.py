"""`sgr` command line: evolve, render, plot, demo, validate, bench."""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np


def _demo(args: argparse.Namespace) -> int:
    """Short main job: a batch of random robots with open-loop gaits; writes results.json."""
    from tasks.bench import sinusoid
    from tasks.env import BatchEnv
    from tsim.sampling import sample_robot

    rng = np.random.default_rng(args.seed)
    bodies = [sample_robot((5, 5), rng) for _ in range(args.robots)]
    env = BatchEnv(args.task, bodies, episode_steps=args.steps)
    t0 = time.perf_counter()
    total = np.zeros(env.n_worlds)
    A = env.sim.max_actuators
    for t in range(args.steps):
        _, r, term, trunc, _ = env.step(sinusoid(t, A)[None, :].repeat(env.n_worlds, 0))
        total += r
    wall = time.perf_counter() - t0
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    best = int(np.argmax(total))
    result = {"task": args.task, "robots": args.robots, "steps": args.steps, "seed": args.seed,
              "returns": total.tolist(), "best_return": float(total[best]),
              "best_body": bodies[best].tolist(), "unstable": int(env.sim.unstable.sum()),
              "wall_s": wall, "robot_steps_per_s": args.robots * args.steps / wall}
    (out / "results.json").write_text(json.dumps(result, indent=1))
    print(f"{args.task}: {args.robots} robots x {args.steps} steps in {wall:.1f} s "
          f"({result['robot_steps_per_s']:.0f} robot-steps/s); best return "
          f"{result['best_return']:.3f}; wrote {out / 'results.json'}")
    return 0


def _validate(args: argparse.Namespace) -> int:
    from tasks.validate import validate

    report = validate(args.dir)
    if args.json:
        print(json.dumps(report))
        return 0
    for c in report["cases"]:
        print(f"{c['file']:<48} {c['task']:<22} com_err_final {c['com_err_final']:.2e} "
              f"com_err_max50 {c['com_err_max50']:.2e} obs_err_step0 {c['obs_err_step0']:.1e} "
              f"return_err {c['return_err']:.2e}")
    for task, t in report["tasks"].items():
        print(task, " ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}"
                             for k, v in t.items()))
    return 0


REPO_CONFIGS = Path(__file__).resolve().parents[1] / "configs"
DEFAULT_CONFIG = REPO_CONFIGS / "sgr" / "quick.yaml"


def workers_arg(text: str) -> int | str:
    """argparse type of --workers: a positive int or 'auto'."""
    if text == "auto":
        return text
    try:
        n = int(text)
    except ValueError:
        n = 0
    if n < 1:
        raise argparse.ArgumentTypeError(f"must be a positive int or 'auto', got {text!r}")
    return n


def _evolve(args: argparse.Namespace) -> int:
    from evolve.experiment import Experiment

    if args.resume:
        if args.config or args.pop or args.seed is not None or args.out:
            raise ValueError("--resume continues a run with its own config; only --generations "
                             "(to extend it), --workers and --quiet go with it")
        exp = Experiment.resume(args.resume, quiet=args.quiet, workers=args.workers,
                                generations=args.generations)
        print(f"resuming {args.resume} at generation {exp.search.generation}")
    else:
        config = args.config or str(DEFAULT_CONFIG)
        stamp = time.strftime("%Y%m%d-%H%M%S")
        out = args.out or str(Path("runs") / f"{Path(config).stem}-seed{args.seed or 0}-{stamp}")
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
    except OSError as exc:  # e.g. a full disk: every file is still whole (a cut CSV row is dropped)
        print(f"sgr: error: cannot write {exc.filename}: {exc.strerror}; the run stopped at generation "
              f"{exp.search.generation} and keeps its last checkpoint: make room, then "
              f"sgr evolve --resume {exp.run.path}", file=sys.stderr)
        return 1
    finally:
        exp.close()
    return 0


def parse_body(text: str) -> np.ndarray:
    """BODY argument: rows separated by commas, one digit per voxel ("33333,33033,...") or a
    .json / .npy file holding the matrix."""
    path = Path(text)
    if path.suffix in (".json", ".npy"):
        if not path.is_file():
            raise ValueError(f"bad body matrix: file not found: {path}")
        data = np.load(path) if path.suffix == ".npy" else json.loads(path.read_text())
        if isinstance(data, dict):
            data = data.get("body", data.get("matrix"))
        return np.asarray(data)
    rows = text.split(",")
    if not all(r and r.isdigit() for r in rows) or len({len(r) for r in rows}) != 1:
        raise ValueError(f"bad body matrix: {text!r} is not equal-length rows of digits separated "
                         "by commas (e.g. 33333,33333,33033,33033,33033)")
    return np.array([[int(ch) for ch in r] for r in rows])


def _render(args: argparse.Namespace) -> int:
    from evolve.champion import champion_gif
    from tasks.bench import sinusoid
    from tasks.render_episode import render_episode
    from tsim.body import check_robot
    from tsim.render import write_gif

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
    from evolve.plots import plot_run, plot_runs

    if len(args.run_dirs) == 1 and not args.compare:
        out = plot_run(args.run_dirs[0], args.out or Path(args.run_dirs[0]) / "fitness.png")
    else:
        out = plot_runs(args.run_dirs, args.out or "fitness.png")
    print(f"wrote {out}")
    return 0


def _bench(args: argparse.Namespace) -> int:
    from tasks.bench import bench

    r = bench(args.task, args.robots, args.steps)
    if args.json:
        print(json.dumps(r))
    else:
        print(f"{r['task']}: {r['robots']} robots x {r['steps']} steps: "
              f"{r['robot_steps_per_s']:.0f} robot-steps/s (env), "
              f"{r['physics_robot_steps_per_s']:.0f} (physics only); compile {r['compile_s']:.1f} s; "
              f"threads {r['threads']}")
    return 0


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="sgr", description="Batched evogym-faithful soft-robot toolkit")
    sub = p.add_subparsers(dest="cmd", required=True)
    e = sub.add_parser("evolve", help="run an evolution experiment (default: a short SGR Walker-v0 run)")
    e.add_argument("--config", help="YAML experiment config (default configs/sgr/quick.yaml)")
    e.add_argument("--generations", type=int)
    e.add_argument("--pop", type=int)
    e.add_argument("--seed", type=int)
    e.add_argument("--out", help="run directory (default runs/<config>-seed<S>-<time>)")
    e.add_argument("--workers", type=workers_arg,
                   help="rollout processes: a number or 'auto' (default: the config's, auto = all CPUs)")
    e.add_argument("--resume", metavar="DIR",
                   help="continue a run from its last checkpoint (with --generations N: extend it to N)")
    e.add_argument("--quiet", action="store_true")
    e.set_defaults(fn=_evolve)
    r = sub.add_parser("render", help="GIF of a run's champion, or of any body with an open-loop gait")
    r.add_argument("run_dir", nargs="?", metavar="RUN_DIR")
    r.add_argument("--task")
    r.add_argument("--body", help="rows of digits separated by commas, or a .json/.npy matrix file")
    r.add_argument("--steps", type=int, help="episode length (default: the task's paper length)")
    r.add_argument("--out", help="GIF path (default RUN_DIR/champion.gif or robot.gif)")
    r.add_argument("--width", type=int, default=640)
    r.add_argument("--height", type=int, default=320)
    r.add_argument("--fps", type=float, default=30.0)
    r.set_defaults(fn=_render)
    pl = sub.add_parser("plot", help="best fitness per generation; runs of one method/task averaged")
    pl.add_argument("run_dirs", nargs="+", metavar="RUN_DIR")
    pl.add_argument("--out", help="PNG path (default RUN_DIR/fitness.png for one run, else fitness.png)")
    pl.add_argument("--compare", action="store_true", help="group style even for a single run")
    pl.set_defaults(fn=_plot)
    d = sub.add_parser("demo", help="simulate random robots with open-loop gaits (short main job)")
    d.add_argument("--task", default="Walker-v0")
    d.add_argument("--robots", type=int, default=32)
    d.add_argument("--steps", type=int, default=300)
    d.add_argument("--seed", type=int, default=0)
    d.add_argument("--out", default="runs/demo")
    d.set_defaults(fn=_demo)
    v = sub.add_parser("validate", help="compare with evogym reference traces or returns")
    v.add_argument("dir")
    v.add_argument("--json", action="store_true")
    v.set_defaults(fn=_validate)
    b = sub.add_parser("bench", help="robot-steps per second on random bodies")
    b.add_argument("--task", default="Walker-v0")
    b.add_argument("--robots", type=int, default=128)
    b.add_argument("--steps", type=int, default=100)
    b.add_argument("--json", action="store_true")
    b.set_defaults(fn=_bench)
    args = p.parse_args(argv)
    try:
        return args.fn(args)
    except ValueError as exc:
        print(f"sgr: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
