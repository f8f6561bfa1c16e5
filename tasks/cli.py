"""The `sgr` commands that need only tasks and the simulator (demo, bench), and the
argument helpers every command shares; `register_task_commands` adds them to the dispatcher in
evolve/cli/ (the sgr dispatcher)."""

from __future__ import annotations

import argparse
import json
import os
import shlex
import time
from pathlib import Path

import numpy as np

from tasks.specs import MAX_STEPS
from tsim import backend
from tsim.errors import SgrError
from tsim.files import atomic_write

# the precisions' names (tsim/backend/__init__.py imports no Taichi, so a parser need not wait for it)
PRECISIONS = tuple(backend.PRECISIONS)
PRECISION_HELP = "the simulator's real type: f64 (evogym's bits) or f32; default $SGR_PRECISION, else f64"


# the most a command line may ask for: more is a typo, and would run for days or fill memory
MAX_ROBOTS = 1_000_000  # robots in one batch
MAX_PIXELS = 4096  # a frame's width or height


def positive(cast, most: float | None = None):
    """argparse type: a positive number of type `cast` (int or float), at most `most` if given."""
    def parse(text: str):
        try:
            value = cast(text)
        except ValueError:
            value = 0
        if not value > 0:
            raise argparse.ArgumentTypeError(f"must be a positive {cast.__name__}, got {text!r}")
        if most is not None and not value <= most:
            raise argparse.ArgumentTypeError(f"must be at most {most:,}, got {text!r}")
        return value
    return parse


def nonnegative(cast, most: float | None = None):
    """argparse type: a finite number >= 0 of type `cast` (int or float), at most `most` if given."""
    def parse(text: str):
        try:
            value = cast(text)
        except ValueError:
            value = -1
        if not 0 <= value < float("inf"):
            raise argparse.ArgumentTypeError(f"must be {'an' if cast is int else 'a'} {cast.__name__} >= 0, "
                                             f"got {text!r}")
        if most is not None and not value <= most:
            raise argparse.ArgumentTypeError(f"must be at most {most:,}, got {text!r}")
        return value
    return parse


def output_path(path: str | Path, flag: str = "--out", *, folder: bool = False) -> Path:
    """`path` as what a command will write (a folder, or a file); ValueError naming the flag when it
    cannot be one (it, or a folder above it, is a file; a file output is a folder), before any
    work is done."""
    path = Path(path)
    if path.exists() and path.is_dir() != folder:
        raise SgrError(f"{flag} {path}: is a {'file' if folder else 'folder'}")
    for above in path.parents:
        if above.exists():
            if not above.is_dir():
                raise SgrError(f"{flag} {path}: {above} is a file, not a folder")
            break
    return path


def parse_body(text: str) -> np.ndarray:
    """BODY argument: rows separated by commas, one digit per voxel ("33333,33033,...") or a
    .json / .npy file holding the matrix."""
    path = Path(text)
    if path.suffix in (".json", ".npy"):
        if not path.is_file():
            raise SgrError(f"bad body matrix: file not found: {path}")
        if path.suffix == ".npy":
            with path.open("rb") as f:
                if f.read(6) != b"\x93NUMPY":
                    raise SgrError(f"bad body matrix: {path}: not a .npy file")
            try:
                return np.load(path, allow_pickle=False)
            except (ValueError, EOFError, OSError) as exc:  # e.g. truncated
                raise SgrError(f"bad body matrix: {path}: unreadable .npy file ({exc})") from None
        try:
            data = json.loads(path.read_text())
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise SgrError(f"bad body matrix: {path}: not valid JSON ({exc})") from None
        if isinstance(data, dict):
            if "body" not in data and "matrix" not in data:
                raise SgrError(f"bad body matrix: {path}: a JSON object needs a 'body' or 'matrix' key")
            data = data.get("body", data.get("matrix"))
        if not (isinstance(data, list) and data and all(isinstance(r, list) for r in data)
                and len({len(r) for r in data}) == 1):
            raise SgrError(f"bad body matrix: {path}: not a list of equal-length rows")
        return np.asarray(data)
    rows = text.split(",")
    if not all(r and r.isdigit() for r in rows) or len({len(r) for r in rows}) != 1:
        raise SgrError(f"bad body matrix: {text!r} is not equal-length rows of digits separated "
                       "by commas (e.g. 33333,33333,33033,33033,33033)")
    return np.array([[int(ch) for ch in r] for r in rows])


def _demo(args: argparse.Namespace) -> int:
    """Short main job: a batch of random robots with open-loop gaits; writes results.json."""
    from tasks.bench import sinusoid
    from tasks.env import BatchEnv
    from tsim.sampling import sample_robots

    out = output_path(args.out, folder=True)
    rng = np.random.default_rng(args.seed)
    bodies = sample_robots(args.robots, (5, 5), rng)
    env = BatchEnv(args.task, bodies, episode_steps=args.steps)
    t0 = time.perf_counter()
    total = np.zeros(env.n_worlds)
    A = env.sim.max_actuators
    for t in range(args.steps):
        _, r, term, trunc, _ = env.step(sinusoid(t, A)[None, :].repeat(env.n_worlds, 0))
        total += r
    wall = time.perf_counter() - t0
    out.mkdir(parents=True, exist_ok=True)
    best = int(np.argmax(total))
    result = {"task": args.task, "robots": args.robots, "steps": args.steps, "seed": args.seed,
              "returns": total.tolist(), "best_return": float(total[best]),
              "best_body": bodies[best].tolist(), "unstable": int(env.sim.unstable.sum()),
              "wall_s": wall, "robot_steps_per_s": args.robots * args.steps / wall}
    atomic_write(out / "results.json", json.dumps(result, indent=1).encode())
    print(f"{args.task}: {args.robots} robots x {args.steps} steps in {wall:.1f} s "
          f"({result['robot_steps_per_s']:.0f} robot-steps/s); best return "
          f"{result['best_return']:.3f}; wrote {out / 'results.json'}")
    return 0


def _bench(args: argparse.Namespace) -> int:
    from tasks.bench import bench
    from tsim import backend
    from tsim.backend import runtime

    runtime.use_precision(args.precision)
    here = backend.get()  # one that cannot start fails here, in one line
    if not args.json:
        print(here.line(), flush=True)
    r = bench(args.task, args.robots, args.steps)
    if args.record:
        from tasks.records import figure, write_record

        write_record(args.record, None, {
            "env": figure(round(r["robot_steps_per_s"]), "robot-steps/s"),
            "physics": figure(round(r["physics_robot_steps_per_s"]), "robot-steps/s")},
            task=r["task"], robots=r["robots"], steps=r["steps"], threads=r["threads"],
            precision=r["precision"], backend=here.record(),
            command=shlex.join([*(f"{k}={v}" for k, v in sorted(os.environ.items()) if k.startswith("SGR_")),
                                "sgr", "bench", "--task", r["task"], "--robots", str(r["robots"]), "--steps",
                                str(r["steps"]), *(["--precision", args.precision] * bool(args.precision))]))
    if args.json:
        print(json.dumps({**r, "backend": here.record()}))
    else:
        print(f"{r['task']}: {r['robots']} robots x {r['steps']} steps: "
              f"{r['robot_steps_per_s']:.0f} robot-steps/s (env), "
              f"{r['physics_robot_steps_per_s']:.0f} (physics only); compile {r['compile_s']:.1f} s; "
              f"threads {r['threads']}" + (" (pinned)" if r["pinned"] else "") + f"; {r['precision']}")
    return 0


def register_task_commands(sub) -> None:
    """Add demo and bench to an argparse subparsers object."""
    d = sub.add_parser("demo", help="simulate random robots with open-loop gaits (short main job)")
    d.add_argument("--task", default="Walker-v0",
                   help="the task (default Walker-v0; sgr's 32: docs/TASKS.md)")
    d.add_argument("--robots", type=positive(int, MAX_ROBOTS), default=32,
                   help="random bodies simulated together in one batch (default 32)")
    d.add_argument("--steps", type=positive(int, MAX_STEPS), default=300,
                   help="steps simulated (default 300)")
    d.add_argument("--seed", type=nonnegative(int), default=0,
                   help="the seed of the bodies and their gaits (default 0)")
    d.add_argument("--out", default="runs/demo", help="folder for the demo's GIF and results.json "
                                                       "(default runs/demo)")
    d.set_defaults(fn=_demo)
    b = sub.add_parser("bench", help="robot-steps per second on random bodies")
    b.add_argument("--task", default="Walker-v0", help="the task (default Walker-v0)")
    b.add_argument("--robots", type=positive(int, MAX_ROBOTS), default=128,
                   help="random bodies simulated together in one batch (default 128)")
    b.add_argument("--steps", type=positive(int, MAX_STEPS), default=100,
                   help="steps timed after the compile (default 100)")
    b.add_argument("--json", action="store_true", help="print the figures as JSON")
    b.add_argument("--record", metavar="PATH", help="also write the figures as a record (JSON with the "
                   "machine, commit, date and command; docs/records/ holds those the docs quote)")
    b.add_argument("--precision", choices=PRECISIONS, help=PRECISION_HELP)
    b.set_defaults(fn=_bench)
